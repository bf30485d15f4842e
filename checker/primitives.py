"""Signed distances of points to the primitive shapes, for whole batches.

Box, sphere, cylinder, capsule and plane are closed-form; the ellipsoid
solves its one-dimensional Lagrange equation by safeguarded Newton
iteration to about 1e-12 of its largest radius. Sizes follow MuJoCo's
convention (box half-extents, sphere radius, cylinder and capsule
``(radius, half_length)`` along local z, ellipsoid radii, a plane as the
solid half-space ``z < 0``), one row of ``size`` per point, so every part of
one type is answered in one call. Points are in each shape's own frame.

Not here: meshes (:mod:`checker.meshdata`), segments
(:mod:`checker.segments`), poses and the :class:`~checker.shapes.Shape`
object (:mod:`checker.shapes`).
"""

from __future__ import annotations

from enum import Enum

import numpy as np

from checker.closest import row_norm


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


def _sd_box_value(h: np.ndarray, p: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Signed distance to boxes without the closest point: (d, q, inside)."""
    q = np.abs(p) - h
    outside = row_norm(np.maximum(q, 0.0))
    inside = np.max(q, axis=1)
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
    inside = np.max(q, axis=1)
    return np.where(inside > 0.0, np.min(np.abs(q), axis=1), inside)


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


def sd_ellipsoid(e: np.ndarray, p: np.ndarray, t0: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Signed distance to ellipsoids with radii ``e`` (m, 3).

    The closest point is ``x_i = e_i^2 y_i / (t + e_i^2)`` where ``t`` is the
    root of ``F(t) = sum (e_i y_i / (t + e_i^2))^2 - 1`` above ``-min e_i^2``
    (Eberly, "Distance from a point to an ellipse, an ellipsoid, or a
    hyperellipsoid"), solved in the first octant by Newton steps kept inside a
    shrinking bracket (bisection when a step leaves it) until the step is below
    1e-14 of the problem's squared scale. ``F`` is convex and decreasing, so
    from the bracket's lower end Newton converges monotonically; ``t0`` (a
    previous root for a nearby point) warm-starts it. The component along the
    smallest radius is taken from the surface equation near the pole (points
    inside, near the plane of the two larger radii: the degenerate case).

    Returns (d (m,), closest (m, 3), t (m,)).
    """
    sgn = np.where(p >= 0.0, 1.0, -1.0)
    y = np.abs(p)
    order = np.argsort(-e, axis=1)
    es = np.take_along_axis(e, order, axis=1)
    ys = np.take_along_axis(y, order, axis=1)
    e2 = es * es
    emin2 = e2[:, 2]
    ey = es * ys
    lo = np.maximum(np.max(ey - e2, axis=1), -emin2)
    hi = np.maximum(-emin2 + row_norm(ey), lo)
    tol = 1e-14 * np.maximum(e2[:, 0], np.max(ey, axis=1))
    t = lo.copy() if t0 is None else np.clip(t0, lo, hi)
    act = np.nonzero(hi - lo > tol)[0]
    # the unconverged points' state, compacted: written back as they converge
    ta, la, ha, e2a, eya, tola = t[act], lo[act], hi[act], e2[act], ey[act], tol[act]
    for _ in range(200):
        if len(act) == 0:
            break
        den = ta[:, None] + e2a
        ok = den > 0
        regular = ok.all()                                   # no point at a pole: fewer operations, same values
        safe = den if regular else np.where(ok, den, 1.0)
        r = (eya if regular else np.where(ok, eya, 0.0)) / safe
        r2 = r * r
        f = ((r2[:, 0] + r2[:, 1]) + r2[:, 2]) - 1.0        # np.sum's order, written out
        q = r2 / safe
        df = -2.0 * ((q[:, 0] + q[:, 1]) + q[:, 2])
        if regular:
            lo_a = np.where(f > 0, ta, la)
            hi_a = np.where(f <= 0, ta, ha)
            step_ok = df < 0
        else:
            # At the pole with y_min > 0, F is +inf.
            at_pole = ~ok & (eya > 0)
            pole = at_pole[:, 0] | at_pole[:, 1] | at_pole[:, 2]
            lo_a = np.where((f > 0) | pole, ta, la)
            hi_a = np.where((f <= 0) & ~pole, ta, ha)
            step_ok = ~pole & (df < 0)
        tn = ta - (f / df if step_ok.all() else np.where(step_ok, f, 0.0) / np.where(step_ok, df, -1.0))
        mid = 0.5 * (lo_a + hi_a)
        # a tiny Newton step far from the root (F steep near the pole: a point
        # on a principal plane by rounding) is no convergence: bisect instead
        small = np.abs(tn - ta) <= tola
        stalled = small & (np.abs(f) > 1e-10)
        tn = np.where(~step_ok | (tn < lo_a) | (tn > hi_a) | stalled, mid, tn)
        conv = ((np.abs(tn - ta) <= tola) & ~stalled) | (hi_a - lo_a <= tola)
        if conv.any():
            done = act[conv]
            t[done], lo[done], hi[done] = tn[conv], lo_a[conv], hi_a[conv]
            go = ~conv
            act = act[go]
            ta, la, ha, e2a, eya, tola = tn[go], lo_a[go], hi_a[go], e2a[go], eya[go], tola[go]
        else:
            ta, la, ha = tn, lo_a, hi_a
    t[act], lo[act], hi[act] = ta, la, ha
    den = t[:, None] + e2
    ok = den > 0.0
    x = np.where(ok, e2 * ys, 0.0) / np.where(ok, den, 1.0)
    # The smallest axis at or near the pole (points inside, near the plane of
    # the larger radii) is better taken from the surface equation.
    rest = 1.0 - (x[:, 0] / es[:, 0]) ** 2 - (x[:, 1] / es[:, 1]) ** 2
    use_eq = (rest >= 0.25) | (den[:, 2] <= 1e-6 * e2[:, 2])
    x[:, 2] = np.where(use_eq, es[:, 2] * np.sqrt(np.maximum(rest, 0.0)), x[:, 2])
    inv = np.argsort(order, axis=1)
    cl = np.take_along_axis(x, inv, axis=1) * sgn
    d = row_norm(p - cl)
    inside = np.sum((p / e) ** 2, axis=1) < 1.0
    return np.where(inside, -d, d), cl, t


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
