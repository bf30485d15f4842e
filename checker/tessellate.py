"""Triangle surfaces of parts, for the rigid-part checks (sweep, part-part).

:func:`part_surface` turns a :class:`~checker.shapes.Shape` into a closed,
outward-wound triangle surface in the part frame, and says how far that surface
may lie from the true one:

- box: its 12 triangles, exact (error 0);
- mesh: its own triangles, exact; ``closed`` says whether inside and outside
  are defined (trimesh's watertight and winding-consistent test);
- sphere, ellipsoid, cylinder, capsule: tessellated with every vertex on the
  true surface (the polyhedron is inscribed), fine enough that no point of the
  true surface is farther than ``tolerance`` from the polyhedron. The bound
  used: a triangle whose corners lie within a spherical cap of angular radius
  ``a`` stays within ``r (1 - cos a)`` of a sphere of radius ``r``; for the
  ellipsoid ``r`` is its largest radius. The count of segments is capped at
  ``MAX_SEGMENTS``; the achieved bound is returned as ``error``;
- plane: no triangles (an infinite half-space is handled analytically by the
  callers), ``error`` 0.

Not here: poses, bounding volumes, contact tests.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import trimesh

from checker.shapes import Shape, ShapeType

MAX_SEGMENTS = 256
"""Most segments around a curved primitive (caps the triangle count near 130k)."""

MIN_SEGMENTS = 12
"""Fewest segments around a curved primitive."""


@dataclass(frozen=True, eq=False)
class Surface:
    """A part's triangle surface in its own frame.

    Attributes:
        vertices: (V, 3) float.
        faces: (F, 3) int, wound outward when ``closed``.
        closed: inside and outside are defined.
        error: largest distance from the true surface to this one (0: exact).
        plane: the part is the half-space z < 0 (no triangles).
    """

    vertices: np.ndarray
    faces: np.ndarray
    closed: bool
    error: float
    plane: bool = False


def _segments_for(radius: float, tolerance: float, angle_factor: float) -> tuple[int, float]:
    """Segments around a circle so that r (1 - cos(angle_factor * pi / n)) <= tolerance."""
    if tolerance >= radius:
        n = MIN_SEGMENTS
    else:
        half = np.arccos(1.0 - tolerance / radius)
        n = int(np.ceil(angle_factor * np.pi / half))
    n = int(min(max(n, MIN_SEGMENTS), MAX_SEGMENTS))
    n += n % 2
    return n, float(radius * (1.0 - np.cos(angle_factor * np.pi / n)))


def _sphere_grid(n: int) -> trimesh.Trimesh:
    """Unit UV sphere with n segments around and n / 2 rings."""
    return trimesh.creation.uv_sphere(radius=1.0, count=[n // 2 + 1, n])


def part_surface(shape: Shape, tolerance: float) -> Surface:
    """The triangle surface of ``shape`` (see the module docstring for the error bound).

    Args:
        shape: the part's shape in its own frame.
        tolerance: wanted largest distance between a curved primitive's true
            surface and its tessellation (same units as the shape), > 0.
    """
    if not tolerance > 0:
        raise ValueError(f"tolerance must be positive, got {tolerance}")
    s = shape.size
    st = shape.type
    if st is ShapeType.PLANE:
        return Surface(np.zeros((0, 3)), np.zeros((0, 3), np.int64), True, 0.0, plane=True)
    if st is ShapeType.MESH:
        return Surface(shape.mesh.vertices, shape.mesh.faces, shape.mesh.closed, 0.0)
    if st is ShapeType.BOX:
        tm = trimesh.creation.box(extents=2.0 * s[:3])
        return Surface(np.asarray(tm.vertices, float), np.asarray(tm.faces, np.int64), True, 0.0)
    # Quads of the UV grid span 2 pi / n around and pi / (n / 2) along a
    # meridian: their corners lie in a cap of angular radius (pi / n) sqrt(2)
    # (half the diagonal), hence the factor sqrt(2) for spheres.
    if st in (ShapeType.SPHERE, ShapeType.ELLIPSOID):
        radii = np.repeat(s[0], 3) if st is ShapeType.SPHERE else s[:3]
        n, err = _segments_for(float(radii.max()), tolerance, np.sqrt(2.0))
        tm = _sphere_grid(n)
        v = np.asarray(tm.vertices) * radii
    elif st is ShapeType.CYLINDER:
        n, err = _segments_for(float(s[0]), tolerance, 1.0)
        tm = trimesh.creation.cylinder(radius=s[0], height=2.0 * s[1], sections=n)
        v = np.asarray(tm.vertices)
    else:  # capsule: trimesh's, a UV sphere split at its equator (height = 2 half_length)
        n, err = _segments_for(float(s[0]), tolerance, np.sqrt(2.0))
        tm = trimesh.creation.capsule(height=2.0 * s[1], radius=s[0], count=[n, n])
        v = np.asarray(tm.vertices)
    tm = trimesh.Trimesh(vertices=v, faces=np.asarray(tm.faces), process=True)
    tm.update_faces(tm.nondegenerate_faces())
    tm.remove_unreferenced_vertices()
    if tm.volume < 0:
        tm.invert()
    return Surface(np.asarray(tm.vertices, float), np.asarray(tm.faces, np.int64),
                   bool(tm.is_watertight), err)
