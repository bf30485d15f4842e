"""cablecheck's geometry: shapes, cable discretisation and interference checks.

Pure numpy/scipy/trimesh, importable without MuJoCo. Inputs are arrays and
plain records (:mod:`cablecheck.checker.scene_state`); outputs are
:class:`~cablecheck.checker.records.Interference` records. This package does not step
physics, read scene files or write reports.
"""

if __name__ != "cablecheck.checker":   # one name for one module: a second import as `checker` would duplicate every class
    raise ImportError(f"the folder checker/ is the package `cablecheck.checker` (pip install -e .): "
                      f"import cablecheck.checker, not {__name__}")

from cablecheck.checker.cable import arc_length, bend_radius, densify, resample, self_pair_excluded
from cablecheck.checker.interference import Checker, check_state
from cablecheck.checker.records import Interference, PairType, Severity, severity_of
from cablecheck.checker.scene_state import CableState, CheckConfig, Exclusion, PartState
from cablecheck.checker.shapes import (
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
