"""Signed distances of points to the primitive shapes, for whole batches.

Box, sphere, cylinder, capsule and plane are closed-form; the ellipsoid
solves its one-dimensional Lagrange equation by safeguarded Newton
iteration, in a variable that keeps its digits next to the centre, to a
few units in the last place of the distance. Sizes follow MuJoCo's
convention (box half-extents, sphere radius, cylinder and capsule
``(radius, half_length)`` along local z, ellipsoid radii, a plane as the
solid half-space ``z < 0``), one row of ``size`` per point, so every part of
one type is answered in one call. Points are in each shape's own frame.

Not here: meshes (:mod:`cablecheck.checker.meshdata`), segments
(:mod:`cablecheck.checker.segments`), poses and the :class:`~cablecheck.checker.shapes.Shape`
object (:mod:`cablecheck.checker.shapes`).
"""

from __future__ import annotations

from enum import Enum

import numpy as np

from cablecheck.checker.arrays import max_columns, min_columns
from cablecheck.checker.closest import row_norm


class ShapeType(str, Enum):
    """Primitive or mesh; the values are MuJoCo's geom type names."""

    BOX = "box"
    SPHERE = "sphere"
    CYLINDER = "cylinder"
    CAPSULE = "capsule"
    ELLIPSOID = "ellipsoid"
    PLANE = "plane"
    MESH = "mesh"


def _unit_or(v: np.ndarray, fallback: np.ndarray) -> np.ndarray:
    """Rows of v normalised; rows of zero length take ``fallback`` (3,)."""
    n = row_norm(v)
    ok = n > 0
    return np.where(ok[:, None], v / np.where(ok, n, 1.0)[:, None], fallback)


_EX = np.array([1.0, 0.0, 0.0])
_EZ = np.array([0.0, 0.0, 1.0])
# the ellipsoid root's relative tolerance (a few units in the last place)
_ELL_TOL = 1e-15


def _sd_box_value(h: np.ndarray, p: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Signed distance to boxes without the closest point: (d, q, inside)."""
    q = np.abs(p) - h
    outside = row_norm(np.maximum(q, 0.0))
    inside = max_columns(q)
    return np.where(inside > 0.0, outside, inside), q, inside


def _sd_box(h: np.ndarray, p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    d, q, inside = _sd_box_value(h, p)
    # Closest point: clamp outside; inside, move to the nearest face.
    cl = np.clip(p, -h, h)
    k = np.argmax(q, axis=1)
    rows = np.arange(len(p))
    face = cl.copy()
    face[rows, k] = np.where(p[rows, k] >= 0.0, h[rows, k], -h[rows, k])
    cl = np.where((inside <= 0.0)[:, None], face, cl)
    return d, cl


def _sd_box_face_plane(h: np.ndarray, p: np.ndarray) -> np.ndarray:
    """The paper's face-plane distance: least |BP . N| over the six face planes.

    Inside points keep the true (negative) distance; outside, the distance to
    the nearest face *plane*, which underestimates near edges and corners.
    """
    q = np.abs(p) - h
    inside = max_columns(q)
    return np.where(inside > 0.0, min_columns(np.abs(q)), inside)


def _sd_sphere(rad: np.ndarray, p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    n = row_norm(p)
    return n - rad, rad[:, None] * _unit_or(p, _EX)


def _sd_capsule(rad: np.ndarray, half: np.ndarray, p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    z = np.clip(p[:, 2], -half, half)
    axis = np.zeros_like(p)
    axis[:, 2] = z
    off = p - axis
    n = row_norm(off)
    return n - rad, axis + rad[:, None] * _unit_or(off, _EX)


def _sd_cylinder_value(rad: np.ndarray, half: np.ndarray, p: np.ndarray) -> tuple:
    """Signed distance to cylinders without the closest point: (d, rho, dr, dz, inside)."""
    rho = np.hypot(p[:, 0], p[:, 1])
    dr = rho - rad
    dz = np.abs(p[:, 2]) - half
    inside = np.maximum(dr, dz)
    outside = np.hypot(np.maximum(dr, 0.0), np.maximum(dz, 0.0))
    return np.where(inside > 0.0, outside, inside), rho, dr, dz, inside


def _sd_cylinder(rad: np.ndarray, half: np.ndarray, p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    d, rho, dr, dz, inside = _sd_cylinder_value(rad, half, p)
    ok = rho > 0
    ux = np.where(ok, p[:, 0], 1.0) / np.where(ok, rho, 1.0)
    uy = np.where(ok, p[:, 1], 0.0) / np.where(ok, rho, 1.0)
    zs = np.where(p[:, 2] >= 0.0, half, -half)
    r_out = np.minimum(rho, rad)
    z_out = np.clip(p[:, 2], -half, half)
    side = dr >= dz  # inside: nearer to the side than to a cap
    r_cl = np.where(inside > 0.0, r_out, np.where(side, rad, rho))
    z_cl = np.where(inside > 0.0, z_out, np.where(side, p[:, 2], zs))
    return d, np.stack([r_cl * ux, r_cl * uy, z_cl], axis=1)


def _sd_plane(p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    cl = p.copy()
    cl[:, 2] = 0.0
    return p[:, 2].copy(), cl


def sd_ellipsoid(e: np.ndarray, p: np.ndarray, u0: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Signed distance to ellipsoids with radii ``e`` (m, 3).

    The closest point is ``x_i = e_i^2 y_i / (u + c_i)`` with
    ``c_i = e_i^2 - m^2`` (``m`` the smallest radius, so ``c_i >= 0`` and 0
    exactly on the smallest radii's axes), where ``u`` is the root of
    ``F(u) = sum (e_i y_i / (u + c_i))^2 - 1`` in ``u >= 0`` (Eberly,
    "Distance from a point to an ellipse, an ellipsoid, or a
    hyperellipsoid", his ``t`` shifted by ``m^2``), solved in the first
    octant. Working in ``u`` rather than ``t = u - m^2`` keeps the
    denominators free of cancellation: deep inside, near the centre, ``u`` is
    about ``m |y|`` and would be lost in the rounding of ``t + m^2`` (it
    was: a ball read -1.0000221 at (1e-12, 0, 1e-14) of a unit ball). Newton
    steps kept inside a shrinking bracket (a step below it goes to its lower
    end, one above it bisects) run until the step is below 1e-15 of ``u``:
    ``F`` is convex and decreasing, so from the bracket's lower end Newton
    converges monotonically. The lower end is the largest of ``0`` and
    ``|e y|_S - max_S c`` over the axis sets S = {smallest}, {two smallest},
    {all} (so a ball's root is exact from the start and no denominator of a
    nonzero term is ever zero); ``u0`` (a previous root for a nearby point)
    warm-starts it. Where ``F(0) <= 0`` (a point inside with no component
    along the smallest radii, in their medial region) the root is 0 and the
    closest point's component along the smallest radii comes from the
    surface equation; so does it, along the point's own direction in their
    axes, wherever it is large (at least half the smallest radius), which
    keeps it exact for points on the principal planes.

    Returns (d (m,), closest (m, 3), u (m,)).
    """
    sgn = np.where(p >= 0.0, 1.0, -1.0)
    y = np.abs(p)
    order = np.argsort(-e, axis=1)
    es = np.take_along_axis(e, order, axis=1)
    ys = np.take_along_axis(y, order, axis=1)
    emin = es[:, 2:]
    # Coordinates below 1e-100 of the smallest radius count as 0: the
    # distance moves by no more than they do (far below its rounding), and
    # nothing underflows below.
    ys = np.where(ys < 1e-100 * emin, 0.0, ys)
    c = (es - emin) * (es + emin)            # e_i^2 - m^2 without cancellation; c[:, 2] == 0
    ey = es * ys
    ey2 = ey * ey
    lo = np.maximum(np.maximum(ey[:, 2], np.sqrt(ey2[:, 1] + ey2[:, 2]) - c[:, 1]),
                    np.maximum(row_norm(ey) - c[:, 0], 0.0))
    hi = np.maximum(row_norm(ey), lo)
    u = lo.copy() if u0 is None else np.clip(u0, lo, hi)
    act = np.nonzero(hi - lo > _ELL_TOL * hi)[0]
    # the unconverged points' state, compacted: written back as they converge
    ua, la, ha, ca, eya = u[act], lo[act], hi[act], c[act], ey[act]
    for _ in range(200):
        if len(act) == 0:
            break
        # where ey > 0, u + c > 0 (u is at least the lower end): a zero
        # denominator has a zero term (u = 0 on the smallest radii's axes)
        den = ua[:, None] + ca
        if not (den > 0.0).all():
            den = np.where(den > 0.0, den, 1.0)
        r = eya / den
        r2 = r * r
        f = ((r2[:, 0] + r2[:, 1]) + r2[:, 2]) - 1.0        # np.sum's order, written out
        q = r2 / den
        df = -2.0 * ((q[:, 0] + q[:, 1]) + q[:, 2])
        la = np.where(f > 0.0, ua, la)
        ha = np.where(f <= 0.0, ua, ha)
        step_ok = df < 0.0
        tn = ua - np.where(step_ok, f, 0.0) / np.where(step_ok, df, -1.0)
        # Newton from the right (a warm start) lands left of the root: below
        # the bracket it tries the lower end (the root itself where F <= 0
        # there, a point inside in the medial region: u = 0)
        tn = np.where(~step_ok | (tn > ha), 0.5 * (la + ha), np.maximum(tn, la))
        conv = (np.abs(tn - ua) <= _ELL_TOL * tn) | (ha - la <= _ELL_TOL * ha)
        if conv.any():
            done = act[conv]
            u[done] = tn[conv]
            go = ~conv
            act = act[go]
            ua, la, ha, ca, eya = tn[go], la[go], ha[go], ca[go], eya[go]
        else:
            ua = tn
    u[act] = ua
    den = u[:, None] + c
    x = es * (ey / np.where(den > 0.0, den, 1.0))
    # The smallest radii's components from the surface equation, along the
    # point's direction in their axes (the last axis when it has none there).
    pole = c == 0.0
    rest = 1.0 - np.sum(np.where(pole, 0.0, x / es) ** 2, axis=1)
    use_eq = (u == 0.0) | (rest >= 0.25)
    yp = np.where(pole, ys, 0.0)
    ymax = max_columns(yp)
    dirn = _unit_or(yp / np.where(ymax > 0.0, ymax, 1.0)[:, None], _EZ)
    xeq = (es[:, 2] * np.sqrt(np.maximum(rest, 0.0)))[:, None] * dirn
    x = np.where(use_eq[:, None] & pole, xeq, x)
    inv = np.argsort(order, axis=1)
    cl = np.take_along_axis(x, inv, axis=1) * sgn
    d = row_norm(p - cl)
    inside = np.sum((p / e) ** 2, axis=1) < 1.0
    return np.where(inside, -d, d), cl, u


def signed_distance_batch(stype: ShapeType, size: np.ndarray, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Signed distance of points to primitives of one type with per-point sizes.

    Args:
        stype: any type but MESH.
        size: (n, k) sizes per point (k as in :class:`Shape`; plane ignores it).
        points: (n, 3) points in each shape's frame.

    Returns:
        d: (n,) signed distance, negative inside.
        closest: (n, 3) closest surface point, in the shape frame.
    """
    p = np.asarray(points, dtype=float).reshape(-1, 3)
    s = np.asarray(size, dtype=float).reshape(len(p), -1)
    if stype is ShapeType.BOX:
        return _sd_box(s[:, :3], p)
    if stype is ShapeType.SPHERE:
        return _sd_sphere(s[:, 0], p)
    if stype is ShapeType.CAPSULE:
        return _sd_capsule(s[:, 0], s[:, 1], p)
    if stype is ShapeType.CYLINDER:
        return _sd_cylinder(s[:, 0], s[:, 1], p)
    if stype is ShapeType.ELLIPSOID:
        return sd_ellipsoid(s[:, :3], p)[:2]
    if stype is ShapeType.PLANE:
        return _sd_plane(p)
    raise ValueError(f"signed_distance_batch does not take {stype}")


def signed_distance_value_batch(stype: ShapeType, size: np.ndarray, points: np.ndarray) -> np.ndarray:
    """The distance (n,) of :func:`signed_distance_batch` alone (boxes and
    cylinders skip their closest points; the values are the same)."""
    p = np.asarray(points, dtype=float).reshape(-1, 3)
    s = np.asarray(size, dtype=float).reshape(len(p), -1)
    if stype is ShapeType.BOX:
        return _sd_box_value(s[:, :3], p)[0]
    if stype is ShapeType.CYLINDER:
        return _sd_cylinder_value(s[:, 0], s[:, 1], p)[0]
    return signed_distance_batch(stype, s, p)[0]


def face_plane_distance_batch(stype: ShapeType, size: np.ndarray, points: np.ndarray) -> np.ndarray:
    """:func:`face_plane_distance` for primitives of one type with per-point sizes, (n,)."""
    p = np.asarray(points, dtype=float).reshape(-1, 3)
    if stype is ShapeType.BOX:
        return _sd_box_face_plane(np.asarray(size, dtype=float).reshape(len(p), -1)[:, :3], p)
    return signed_distance_batch(stype, size, p)[0]
