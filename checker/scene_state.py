"""The checker's input: one scene state (cables and posed parts) and settings.

These records are what the simulation side fills every checked step: cable
centrelines as arrays of body centres, parts as shapes with 4x4 poses, the
arc-length windows where touching a part is expected, and the check settings.
Validation of values that would break the geometry (non-finite points, bad
poses, non-positive radii) happens here, at construction, with a message naming
the record.

Deliberately not here: scene files, units, MuJoCo ids; the geometry itself
(:mod:`cablecheck.checker.shapes`, :mod:`cablecheck.checker.interference`).
"""

from __future__ import annotations

import copy
from dataclasses import dataclass

import numpy as np

from cablecheck.checker.shapes import Shape


@dataclass(frozen=True, eq=False)
class PartState:
    """A rigid part at one instant.

    Attributes:
        name: part name ("/" separates assembly levels).
        shape: its geometry in the part frame.
        pose: (4, 4) homogeneous transform part -> world (rotation must be
            orthonormal).
        keepout: a clearance zone: reported as ``keepout``, never as
            ``cable-structure``.
    """

    name: str
    shape: Shape
    pose: np.ndarray
    keepout: bool = False

    def __post_init__(self) -> None:
        pose = np.asarray(self.pose, dtype=float)
        if pose.shape != (4, 4) or not np.all(np.isfinite(pose)):
            raise ValueError(f"part {self.name!r}: pose must be a finite 4x4 matrix")
        rot = pose[:3, :3]
        if not np.allclose(rot.T @ rot, np.eye(3), atol=1e-9):
            raise ValueError(f"part {self.name!r}: pose rotation is not orthonormal")
        object.__setattr__(self, "pose", pose)


@dataclass(frozen=True, eq=False)
class CableState:
    """A cable's centreline at one instant.

    Attributes:
        name: cable name.
        points: (n, 3) body centres from start to end, any spacing, n >= 2.
        radius: cable radius (> 0).
        min_bend_radius: optional bend limit; tighter bends are reported as
            ``bend``.
        rest_length: optional unstretched length; stretching beyond 1 % is
            reported as ``taut``.
        rest_s: optional (n,) strictly increasing material coordinate of
            each point: its arc length along the unstretched cable (element
            index times the rest element length for a uniform cable).
            Exclusion windows are measured in it, so a stretched cable still
            has the same piece of material in its window. None: the current
            arc length.
    """

    name: str
    points: np.ndarray
    radius: float
    min_bend_radius: float | None = None
    rest_length: float | None = None
    rest_s: np.ndarray | None = None

    def __post_init__(self) -> None:
        pts = np.asarray(self.points, dtype=float)
        if pts.ndim != 2 or pts.shape[1] != 3 or len(pts) < 2:
            raise ValueError(f"cable {self.name!r}: points must be (n, 3) with n >= 2, got {pts.shape}")
        self._check_finite(pts)
        if not (np.isfinite(self.radius) and self.radius > 0):
            raise ValueError(f"cable {self.name!r}: radius must be positive, got {self.radius}")
        object.__setattr__(self, "points", pts)
        if self.rest_s is not None:
            rest = np.asarray(self.rest_s, dtype=float)
            if rest.shape != (len(pts),) or not np.all(np.isfinite(rest)) or np.any(np.diff(rest) <= 0):
                raise ValueError(f"cable {self.name!r}: rest_s must be ({len(pts)},) finite and "
                                 "strictly increasing")
            object.__setattr__(self, "rest_s", rest)

    def with_points(self, points: np.ndarray) -> CableState:
        """This cable at other body centres, as many (n, 3) and finite
        (checked); its other fields as they are, checked when it was made.
        What ``dataclasses.replace`` gives, at a fifth of its cost (a
        batch's states make thousands of them)."""
        pts = np.asarray(points, dtype=float)
        if pts.shape != self.points.shape:
            raise ValueError(f"cable {self.name!r}: points must be {self.points.shape}, got {pts.shape}")
        self._check_finite(pts)
        out = copy.copy(self)
        object.__setattr__(out, "points", pts)
        return out

    def _check_finite(self, pts: np.ndarray) -> None:
        if not np.all(np.isfinite(pts)):
            raise ValueError(f"cable {self.name!r}: points contain NaN or infinite values")


@dataclass(frozen=True)
class Exclusion:
    """A window along a cable's material where touching a part is expected.

    The elements (with method exact, centreline pieces) of ``cable`` whose
    middle's material coordinate (:attr:`CableState.rest_s`: arc length
    along the unstretched cable, or the current arc length where the cable
    has none) lies in ``[s_min, s_max]`` are not checked against ``part``:
    the attachment or clip zone; nor are the discrete points on them
    (method points). A point on an end of the window that is also on an
    element outside it is checked, as that element is (MuJoCo's contacts,
    one per element, are filtered the same way): the window's ends are
    open to points, but where the window reaches the cable's own start
    (``s_min`` 0) or its end (``to_end``). Measured along the material, the
    window holds the same piece of cable however far the cable stretches.
    ``window`` names it in reports ("start", "end", "clip N"; may be
    empty).
    """

    cable: str
    part: str
    s_min: float
    s_max: float
    window: str = ""
    to_end: bool = False


@dataclass(frozen=True)
class CheckConfig:
    """Check settings.

    Attributes:
        method: "points" (the paper's discrete points) or "exact" (segment
            distances: capsules against capsules and shapes).
        spacing: largest discrete-point spacing as a multiple of each cable's
            radius (2: the paper's ``2r`` within a cable; between two cables
            the mean spacing is then ``r1 + r2``, the paper's value).
        clearance: soft interference below this surface distance.
        face_plane: measure cable-structure distance to boxes and meshes as
            the paper's ``|BP . N|`` to the nearest face plane (benchmark
            only: it raises false alarms near edges).
    """

    method: str = "points"
    spacing: float = 2.0
    clearance: float = 0.005
    face_plane: bool = False

    def __post_init__(self) -> None:
        if self.method not in ("points", "exact"):
            raise ValueError(f"method must be 'points' or 'exact', got {self.method!r}")
        if not (np.isfinite(self.spacing) and self.spacing > 0):
            raise ValueError(f"spacing must be positive, got {self.spacing}")
        if not (np.isfinite(self.clearance) and self.clearance >= 0):
            raise ValueError(f"clearance must be >= 0, got {self.clearance}")
