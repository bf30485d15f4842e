"""cablecheck's geometry: shapes, cable discretisation and interference checks.

Pure numpy/scipy/trimesh, importable without MuJoCo. Inputs are arrays and
plain records (:mod:`checker.scene_state`); outputs are
:class:`~checker.records.Interference` records. This package does not step
physics, read scene files or write reports.
"""

from checker.cable import arc_length, bend_radius, densify, resample, self_pair_excluded
from checker.interference import Checker, check_state
from checker.records import Interference, PairType, Severity, severity_of
from checker.scene_state import CableState, CheckConfig, Exclusion, PartState
from checker.shapes import (
    Shape,
    ShapeType,
    face_plane_distance,
    mesh_shape,
    segment_signed_distance,
    signed_distance,
)

__all__ = [
    "CableState", "CheckConfig", "Checker", "Exclusion", "Interference", "PairType", "PartState", "Severity",
    "Shape", "ShapeType", "arc_length", "bend_radius", "check_state", "densify", "face_plane_distance",
    "mesh_shape", "resample", "segment_signed_distance", "self_pair_excluded", "severity_of", "signed_distance",
]
