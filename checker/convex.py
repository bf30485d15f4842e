"""Signed distance between pairs of placed convex primitives, for whole arrays of pairs.

Part-part checks of two primitives (box, sphere, capsule, cylinder,
ellipsoid) use the true shapes here instead of their tessellations, so
curved parts overlapping by less than their tessellation error are found and
depths are not under-stated. The signed distance of convex ``A`` and ``B``
is ``-min over unit u of h_D(u)``, ``h_D(u) = h_A(u) + h_B(-u)`` the support
function of the Minkowski difference ``A - B``: positive, it is the distance;
negative, minus the penetration depth (the shortest translation that
separates the two). Every direction ``u`` gives ``-h_D(u) <=`` the signed
distance, i.e. a distance never over-stated and a depth never under-stated.

By pair (``exact`` says which answers are exact to rounding):

- sphere with anything: the signed distance of the centre to the other
  shape minus the radius (closed form; the ellipsoid by safeguarded Newton,
  about 1e-10 of its size): exact, inside and out;
- capsule with capsule: the distance between the axes minus both radii:
  exact;
- capsule with box, cylinder or ellipsoid, apart: the least signed distance
  along the axis (:func:`cablecheck.checker.shapes.segment_signed_distance_batch`)
  minus the radius: exact. Overlapping: with a box, the least of ``h_D`` over
  the face normals of ``A - B`` (box axes and axis x box-axis crosses): exact;
  with the others, the general rule below;
- cylinder or capsule with a cylinder on a parallel axis (a pin in its
  bore, a knuckle on its hinge pin): ``A - B`` is a cylinder (grown by the
  capsule's radius), so the signed distance is a point's to that cylinder
  in closed form: exact, inside and out, and the same number however the
  parts turn about the axis (:func:`_parallel_cylinders`);
- box with box overlapping: the least of ``h_D`` over the 15 separating
  axes (they are all the face normals of ``A - B``): exact. Apart, the
  distance is the callers' (exact triangles; see :mod:`cablecheck.checker.parts`);
- any other pair (a cylinder or an ellipsoid with a box, a capsule, a
  cylinder off parallel or an ellipsoid): the least of ``h_D`` over the 15 axes of the two
  frames, their centres' offset and both signs, then refined by Gilbert's
  algorithm, alternating projections between the solids and projected
  gradient descent on the sphere of directions (the gradient of ``h_D`` is
  the difference of the support points; backtracking accepts only
  decreases); an overlapping pair also descends from the best few of those
  axes and of 96 evenly spread directions. The answer is always a lower
  bound of the signed distance. Apart it is exact at convergence (the
  sub-level sets of ``h_D`` below zero are geodesically convex, so a local
  minimum is the global one; on random pairs of sizes 0.2 to 1 it is within
  6e-4 of coal's GJK, never above it); overlapping, it is an upper bound on
  the depth (within 2 % of a dense search of directions). Pairs whose starts
  already prove them farther apart than ``beyond`` (the clearance) are not
  refined.

Why by hand: coal (hpp-fcl's successor) answers a pair as accurately when
apart, but from one Python call per pair, with EPA depths
that can be off either way (a sphere in a cylinder 4 % too deep), and with
about 330 MB of native dependencies (boost, assimp, octomap, qhull,
eigenpy); python-fcl's distances run a little high on curved shapes. The
closed forms above are vectorised and exact, and only pairs within the
clearance of each other reach the refinement.

``where`` is the midpoint of the two support points along the best direction
(the closest points when apart). Not here: meshes and planes, pair
selection, records (:mod:`cablecheck.checker.parts`).
"""

from __future__ import annotations

import numpy as np

from cablecheck.checker.closest import segment_segment
from cablecheck.checker.shapes import ShapeType, segment_signed_distance_batch, signed_distance_batch

CONVEX = (ShapeType.BOX, ShapeType.SPHERE, ShapeType.CAPSULE, ShapeType.CYLINDER, ShapeType.ELLIPSOID)
"""Primitive types handled here."""

DESCENT_ITERS = 60
"""Projected-gradient steps of the general rule."""

GILBERT_ITERS = 100
"""Steps of Gilbert's algorithm of the general rule."""

MULTI_STARTS = 6
"""Descents from the best starts of an overlapping pair of the general rule."""


def _norm(x: np.ndarray, axis: int = 1, keepdims: bool = False) -> np.ndarray:
    """``np.linalg.norm(x, axis=axis, keepdims=keepdims)`` for real arrays:
    its formula and bits, without its Python-level dispatch (a few
    microseconds a call, in loops of a few pairs)."""
    return np.sqrt(np.add.reduce(x * x, axis=axis, keepdims=keepdims))


def _fibonacci(n: int) -> np.ndarray:
    """n directions spread evenly over the sphere (a Fibonacci lattice)."""
    k = np.arange(n) + 0.5
    z = 1.0 - 2.0 * k / n
    phi = np.pi * (1.0 + 5 ** 0.5) * k
    r = np.sqrt(1.0 - z * z)
    return np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=1)


_SPREAD = _fibonacci(96)

PROJECTION_ITERS = 30
"""Alternating projections of the general rule."""


def _support_box(size: np.ndarray, u: np.ndarray) -> np.ndarray:
    return np.sign(u) * size


def _support_sphere(size: np.ndarray, u: np.ndarray) -> np.ndarray:
    nu = _norm(u, axis=1)
    return size[:, :1] * u / np.where(nu > 0, nu, 1.0)[:, None]


def _support_capsule(size: np.ndarray, u: np.ndarray) -> np.ndarray:
    s = _support_sphere(size, u)
    s[:, 2] += np.sign(u[:, 2]) * size[:, 1]
    return s


def _support_cylinder(size: np.ndarray, u: np.ndarray) -> np.ndarray:
    s = np.empty_like(u)
    rad = _norm(u[:, :2], axis=1)
    s[:, :2] = size[:, :1] * u[:, :2] / np.where(rad > 0, rad, 1.0)[:, None]
    s[:, 2] = np.sign(u[:, 2]) * size[:, 1]
    return s


def _support_ellipsoid(size: np.ndarray, u: np.ndarray) -> np.ndarray:
    e2u = size ** 2 * u
    den = np.sqrt(np.einsum("ij,ij->i", e2u, u))
    return e2u / np.where(den > 0, den, 1.0)[:, None]


_SUPPORT = (_support_box, _support_sphere, _support_capsule, _support_cylinder, _support_ellipsoid)
"""Support points per kind of :data:`CONVEX`, for rows of one kind."""


def support(kind: np.ndarray, size: np.ndarray, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Support function and a support point of primitives in their own frames.

    Args:
        kind: (n,) index into :data:`CONVEX`.
        size: (n, 3) sizes (zero-padded).
        u: (n, 3) directions (any length > 0).

    Returns:
        h: (n,) ``max over x in the shape of x . u``.
        s: (n, 3) a point of the shape reaching it.
    """
    # one call per kind present (rows of one kind without any selection: an
    # iteration of a few pairs costs its calls, not its rows); the same
    # arithmetic row by row either way
    count = np.bincount(kind, minlength=len(CONVEX))
    present = np.flatnonzero(count)
    if len(present) == 1:
        s = _SUPPORT[present[0]](size, u)
    else:
        s = np.zeros_like(u)
        for k in present:
            rows = kind == k
            s[rows] = _SUPPORT[k](size[rows], u[rows])
    return np.einsum("ij,ij->i", s, u), s


def _h_d(ka, sa, ra, pa, kb, sb, rb, pb, u):
    """h_D(u) (n,) and the support points of A along u and of B along -u (world)."""
    ha, xa = support(ka, sa, np.einsum("nji,nj->ni", ra, u))
    hb, xb = support(kb, sb, np.einsum("nji,nj->ni", rb, -u))
    wa = np.einsum("nij,nj->ni", ra, xa) + pa
    wb = np.einsum("nij,nj->ni", rb, xb) + pb
    return ha + np.einsum("ij,ij->i", pa, u) + hb - np.einsum("ij,ij->i", pb, u), wa, wb


def _axes(ra: np.ndarray, rb: np.ndarray, offset: np.ndarray) -> np.ndarray:
    """(n, 32, 3) start directions: 3 + 3 frame axes, 9 crosses, the centres' offset; both signs.
    Degenerate crosses (parallel axes) are replaced by the offset."""
    a = np.swapaxes(ra, 1, 2)                                   # rows: A's axes
    b = np.swapaxes(rb, 1, 2)
    cr = np.cross(a[:, :, None, :], b[:, None, :, :]).reshape(len(ra), 9, 3)
    off = offset / np.maximum(_norm(offset, axis=1), 1e-300)[:, None]
    off = np.where(_norm(off, axis=1, keepdims=True) > 0, off, a[:, 2])
    ln = _norm(cr, axis=2, keepdims=True)
    cr = np.where(ln > 1e-9, cr / np.maximum(ln, 1e-300), off[:, None, :])
    u = np.concatenate([a, b, cr, off[:, None, :]], axis=1)
    return np.concatenate([u, -u], axis=1)


def _least_over(dirs: np.ndarray, args) -> tuple[np.ndarray, np.ndarray]:
    """Least h_D over the directions (n, k, 3): (value (n,), direction (n, 3))."""
    n, k, _ = dirs.shape
    rep = [np.repeat(x, k, axis=0) for x in args]
    h, _, _ = _h_d(*rep, dirs.reshape(-1, 3))
    h = h.reshape(n, k)
    best = np.argmin(h, axis=1)
    return h[np.arange(n), best], dirs[np.arange(n), best]


def _gilbert(u: np.ndarray, f: np.ndarray, args, scale: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Gilbert's distance algorithm (1966) on ``D = A - B`` from direction u (n, 3).

    Keeps a point ``x`` of D and moves it to the point nearest the origin on
    the segment to the support point of D along ``-x``; every direction
    visited gives ``h_D``, whose least value (with ``f``) is returned with
    its direction: apart, ``-h_D`` rises to the distance and ``|x|`` falls
    to it. Overlapping, ``x`` tends to the origin and ``f`` only keeps the
    starts' least value. A pair stops once its ``x`` moves less than
    ``CONVERGED`` of its size (:func:`_rows`)."""
    f, best_u = f.copy(), u.copy()
    _, wa, wb = _h_d(*args, u)
    x = wa - wb
    for act, sub in _rows(len(u), args, GILBERT_ITERS):
        xa = x[act]
        ln = _norm(xa, axis=1)
        live = ln > 0
        d = -xa / np.where(live, ln, 1.0)[:, None]
        d = np.where(live[:, None], d, best_u[act])
        h, wa, wb = _h_d(*sub, d)
        better = h < f[act]
        f[act] = np.where(better, h, f[act])
        best_u[act] = np.where(better[:, None], d, best_u[act])
        e = (wa - wb) - xa
        ee = np.einsum("ij,ij->i", e, e)
        t = np.clip(-np.einsum("ij,ij->i", xa, e) / np.where(ee > 0, ee, 1.0), 0.0, 1.0)
        x[act] = xa + t[:, None] * e
        act.moved = t * np.sqrt(ee) > CONVERGED * scale[act]
    return f, best_u


CONVERGED = 1e-9
"""Gilbert's and the projections' iterations of a pair stop once its points
move less than this fraction of its size (the two parts' largest sizes
summed): far below any clearance, and decided by the pair alone, so a pair's
answer does not depend on the others checked with it. Stopping early only
keeps fewer directions: the answer stays a lower bound of the signed
distance."""

CONVERGED_ANGLE = 1e-7
"""The descent of a pair stops once a trial fails with a turn of the
direction below this (radians): near the minimum h_D differs from its least
value by the square of that times its curvature."""


class _Active(np.ndarray):
    """Row indices still iterating, with a `moved` mask set by each iteration."""

    moved: np.ndarray


def _rows(n: int, args, iters: int):
    """Yield (rows still iterating, args of those rows) up to `iters` times;
    after each iteration the rows whose `act.moved` is False stop (their
    values stay as they were: every update is row by row, so the rows left
    give the same bits as iterating them alone)."""
    act = np.arange(n)
    sub = args
    for _ in range(iters):
        if not len(act):
            return
        view = act.view(_Active)
        view.moved = np.ones(len(act), bool)
        yield view, sub
        keep = view.moved
        if not keep.all():
            act = act[keep]
            sub = tuple(x[act] for x in args)


def _project(kind: np.ndarray, size: np.ndarray, rot: np.ndarray, pos: np.ndarray, x: np.ndarray) -> np.ndarray:
    """The point of each solid (world) nearest x (n, 3): x itself inside, else the closest surface point."""
    out = x.copy()
    local = np.einsum("nji,nj->ni", rot, x - pos)
    types = list(CONVEX)
    for k in np.unique(kind):
        rows = np.flatnonzero(kind == k)
        d, q = signed_distance_batch(types[k], size[rows], local[rows])
        outside = d > 0
        r = rows[outside]
        out[r] = np.einsum("nij,nj->ni", rot[r], q[outside]) + pos[r]
    return out


def _alternate(u: np.ndarray, f: np.ndarray, args, scale: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Alternating projections between the solids from their support points along u; every
    pair of points met gives the direction from one to the other, kept when h_D is lower.
    A pair stops once its points move less than ``CONVERGED`` of its size."""
    f, u = f.copy(), u.copy()
    _, p, q = _h_d(*args, u)
    for act, sub in _rows(len(u), args, PROJECTION_ITERS):
        ka, sa, ra, pa, kb, sb, rb, pb = sub
        p_new = _project(ka, sa, ra, pa, q[act])
        q_new = _project(kb, sb, rb, pb, p_new)
        step = _norm(p_new - p[act], axis=1) + _norm(q_new - q[act], axis=1)
        p[act], q[act] = p_new, q_new
        v = q_new - p_new
        ln = _norm(v, axis=1)
        d = np.where(ln[:, None] > 0, v / np.where(ln > 0, ln, 1.0)[:, None], u[act])
        h, _, _ = _h_d(*sub, d)
        better = h < f[act]
        f[act] = np.where(better, h, f[act])
        u[act] = np.where(better[:, None], d, u[act])
        act.moved = step > CONVERGED * scale[act]
    return f, u


def _descend(u: np.ndarray, f: np.ndarray, args, scale: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Projected gradient descent of h_D on the unit sphere from u (n, 3), value f; monotone.
    A pair stops once a trial fails with a turn below ``CONVERGED_ANGLE``."""
    f, u = f.copy(), u.copy()
    step = 0.5 / scale
    for act, sub in _rows(len(u), args, DESCENT_ITERS):
        ua = u[act]
        _, wa, wb = _h_d(*sub, ua)
        g = wa - wb
        g -= np.einsum("ij,ij->i", g, ua)[:, None] * ua
        turn = step[act] * _norm(g, axis=1)
        trial = ua - step[act, None] * g
        trial /= np.maximum(_norm(trial, axis=1), 1e-300)[:, None]
        ft, _, _ = _h_d(*sub, trial)
        better = ft < f[act]
        u[act] = np.where(better[:, None], trial, ua)
        f[act] = np.where(better, ft, f[act])
        step[act] = np.where(better, 1.5 * step[act], 0.5 * step[act])
        act.moved = better | (turn > CONVERGED_ANGLE)
    return f, u


PARALLEL_SIN = 1e-9
"""Axes whose angle's sine is at most this count as parallel for the closed
form of a cylinder (or capsule) with a cylinder: B is widened to the
cylinder along A's axis that holds it (radius ``rb + hb sin``, half length
``hb cos + rb sin``), so the answer stays a lower bound, exact when the axes
are parallel to the bit."""


def _parallel_cylinders(ka, sa, ra, pa, kb, sb, rb, pb):
    """A cylinder or capsule A and a cylinder B on (nearly) parallel axes: (sd, where, exact, ok).

    With parallel axes, ``A - B`` is the cylinder of radius ``ra + rb`` and half
    length ``ha + hb`` about ``pa - pb`` (a capsule: the cylinder of radius
    ``rb``, half length ``ha + hb``, grown by the ball of radius ``ra``), so
    the signed distance is the closed-form signed distance of B's centre, in
    A's frame, to that cylinder (less the capsule's radius: growing a convex
    set by a ball lowers its signed distance by the radius everywhere,
    inside too). Axes within :data:`PARALLEL_SIN` of parallel take B's
    enclosing cylinder along A's axis (a lower bound); ``ok`` is False for the
    others (left to the general rule). ``where`` is the midpoint of the two
    support points along the normal of ``A - B`` nearest the origin."""
    axis_a, axis_b = ra[:, :, 2], rb[:, :, 2]
    cos = np.abs(np.einsum("ni,ni->n", axis_a, axis_b))
    a0, a1, a2 = axis_a[:, 0], axis_a[:, 1], axis_a[:, 2]
    b0, b1, b2 = axis_b[:, 0], axis_b[:, 1], axis_b[:, 2]
    cx, cy, cz = a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0     # a x b
    sin = np.sqrt(cx * cx + cy * cy + cz * cz)
    ok = sin <= PARALLEL_SIN
    cap = ka == 2
    rad_b = sb[:, 0] + sb[:, 1] * sin
    half_b = sb[:, 1] * cos + sb[:, 0] * sin
    rad = np.where(cap, 0.0, sa[:, 0]) + rad_b
    half = sa[:, 1] + half_b
    x = np.einsum("nji,nj->ni", ra, pb - pa)                  # B's centre in A's frame
    rho = np.hypot(x[:, 0], x[:, 1])
    dr, dz = rho - rad, np.abs(x[:, 2]) - half
    inside = np.maximum(dr, dz)                               # > 0: apart
    d = np.where(inside > 0.0, np.hypot(np.maximum(dr, 0.0), np.maximum(dz, 0.0)), inside)
    sd = d - np.where(cap, sa[:, 0], 0.0)
    # the outward normal of A - B nearest the origin (A's frame): the pair's best direction
    radial = np.where(rho[:, None] > 0, np.stack([x[:, 0], x[:, 1], np.zeros(len(x))], axis=1)
                      / np.where(rho > 0, rho, 1.0)[:, None], [1.0, 0.0, 0.0])
    axial = np.zeros_like(x)
    axial[:, 2] = np.where(x[:, 2] >= 0.0, 1.0, -1.0)
    out = np.maximum(dr, 0.0)[:, None] * radial + np.maximum(dz, 0.0)[:, None] * axial
    u = np.where((inside > 0.0)[:, None], out / np.maximum(_norm(out, axis=1), 1e-300)[:, None],
                 np.where((dr >= dz)[:, None], radial, axial))
    _, wa, wb = _h_d(ka, sa, ra, pa, kb, sb, rb, pb, np.einsum("nij,nj->ni", ra, u))
    return sd, 0.5 * (wa + wb), ok & (sin == 0.0), ok


def convex_pairs(kind_a: np.ndarray, size_a: np.ndarray, rot_a: np.ndarray, pos_a: np.ndarray,
                 kind_b: np.ndarray, size_b: np.ndarray, rot_b: np.ndarray, pos_b: np.ndarray,
                 beyond: float = np.inf) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Signed distances of n pairs of placed convex primitives (see the module docstring).

    Args:
        kind_a, kind_b: (n,) indices into :data:`CONVEX`.
        size_a, size_b: (n, 3) sizes, zero-padded.
        rot_a, rot_b: (n, 3, 3) part-to-world rotations; pos_a, pos_b: (n, 3) origins.
        beyond: pairs of the general rule whose starts already prove a
            distance of at least this are not refined (their ``sd``, a lower
            bound, is all a clearance test needs).

    Returns:
        sd: (n,) signed distance (negative: minus the depth); ``np.nan`` for
            two boxes that do not overlap (the callers measure those).
        where: (n, 3) world point.
        exact: (n,) bool, ``sd`` is exact (else a lower bound: the depth an
            upper bound).
        boxes_apart: (n,) bool, two boxes whose distance is left to the caller.
    """
    # order each pair so that a sphere, else a capsule, comes first
    rank = np.array([3, 0, 1, 2, 2])                     # box, sphere, capsule, cylinder, ellipsoid
    swap = rank[kind_b] < rank[kind_a]
    if swap.any():
        ka, kb = np.where(swap, kind_b, kind_a), np.where(swap, kind_a, kind_b)
        sa = np.where(swap[:, None], size_b, size_a)
        sb = np.where(swap[:, None], size_a, size_b)
        ra = np.where(swap[:, None, None], rot_b, rot_a)
        rb = np.where(swap[:, None, None], rot_a, rot_b)
        pa = np.where(swap[:, None], pos_b, pos_a)
        pb = np.where(swap[:, None], pos_a, pos_b)
    else:                                                # (the same arrays, uncopied)
        ka, kb, sa, sb, ra, rb, pa, pb = kind_a, kind_b, size_a, size_b, rot_a, rot_b, pos_a, pos_b
    n = len(ka)
    sd = np.full(n, np.nan)
    where = np.zeros((n, 3))
    exact = np.zeros(n, bool)
    done = np.zeros(n, bool)
    args = (ka, sa, ra, pa, kb, sb, rb, pb)
    types = list(CONVEX)

    # sphere with anything: the centre's signed distance to B, minus the radius
    sph = np.flatnonzero(ka == 1)
    for k in (np.unique(kb[sph]) if len(sph) else ()):
        rows = sph[kb[sph] == k]
        c = np.einsum("nji,nj->ni", rb[rows], pa[rows] - pb[rows])
        d, q = signed_distance_batch(types[k], sb[rows], c)
        qw = np.einsum("nij,nj->ni", rb[rows], q) + pb[rows]
        cw = pa[rows]
        v = qw - cw
        ln = _norm(v, axis=1)
        # the sphere's own point nearest the other surface
        u = np.where(ln[:, None] > 0, v / np.maximum(ln, 1e-300)[:, None], 0.0) * np.sign(d)[:, None]
        sd[rows] = d - sa[rows, 0]
        where[rows] = 0.5 * (qw + cw + sa[rows, :1] * u)
        exact[rows] = done[rows] = True

    # capsule with capsule, and capsule with the others while its axis stays outside
    cap = np.flatnonzero((ka == 2) & ~done)
    if len(cap):
        ends = np.zeros((len(cap), 2, 3))
        ends[:, 0, 2], ends[:, 1, 2] = -sa[cap, 1], sa[cap, 1]
        a0 = np.einsum("nij,nj->ni", ra[cap], ends[:, 0]) + pa[cap]
        a1 = np.einsum("nij,nj->ni", ra[cap], ends[:, 1]) + pa[cap]
        two = kb[cap] == 2
        rows = cap[two]
        if len(rows):
            e = np.zeros((len(rows), 2, 3))
            e[:, 0, 2], e[:, 1, 2] = -sb[rows, 1], sb[rows, 1]
            b0 = np.einsum("nij,nj->ni", rb[rows], e[:, 0]) + pb[rows]
            b1 = np.einsum("nij,nj->ni", rb[rows], e[:, 1]) + pb[rows]
            d, _, _, cp, cq = segment_segment(a0[two], a1[two], b0, b1)
            v = cq - cp
            u = v / np.maximum(_norm(v, axis=1), 1e-300)[:, None]
            sd[rows] = d - sa[rows, 0] - sb[rows, 0]
            where[rows] = 0.5 * ((cp + sa[rows, :1] * u) + (cq - sb[rows, :1] * u))
            exact[rows] = done[rows] = True
        for k in np.unique(kb[cap[~two]]):
            sel = ~two & (kb[cap] == k)
            rows = cap[sel]
            la = np.einsum("nji,nj->ni", rb[rows], a0[sel] - pb[rows])
            lb = np.einsum("nji,nj->ni", rb[rows], a1[sel] - pb[rows])
            m, t = segment_signed_distance_batch(types[k], sb[rows], la, lb)
            out = m >= 0
            r_out = rows[out]
            if not len(r_out):
                continue
            p = la[out] + t[out, None] * (lb[out] - la[out])
            _, q = signed_distance_batch(types[k], sb[r_out], p)
            pw = np.einsum("nij,nj->ni", rb[r_out], p) + pb[r_out]
            qw = np.einsum("nij,nj->ni", rb[r_out], q) + pb[r_out]
            v = qw - pw
            u = v / np.maximum(_norm(v, axis=1), 1e-300)[:, None]
            sd[r_out] = m[out] - sa[r_out, 0]
            where[r_out] = 0.5 * (pw + sa[r_out, :1] * u + qw)
            exact[r_out] = done[r_out] = True

    # a cylinder or a capsule with a cylinder on a parallel axis: A - B is a cylinder
    # (rounded by the capsule's radius), the origin's signed distance to it in closed form
    par = np.flatnonzero(~done & ((ka == 2) | (ka == 3)) & (kb == 3))
    if len(par):
        sd[par], where[par], exact[par], ok = _parallel_cylinders(*(x[par] for x in args))
        done[par] = ok

    # the rest by support functions: exact for box-box and capsule-box (all face normals
    # of A - B are among the starts), else refined by descent
    rest = np.flatnonzero(~done)
    if len(rest):
        sub = tuple(x[rest] for x in args)
        dirs = _axes(ra[rest], rb[rest], pb[rest] - pa[rest])
        f, u = _least_over(dirs, sub)
        polytope = ((ka[rest] == 0) | (ka[rest] == 2)) & (kb[rest] == 0)
        boxes = (ka[rest] == 0) & (kb[rest] == 0)
        curved = ~polytope & (-f < beyond)
        if curved.any():
            c = np.flatnonzero(curved)
            scale = np.maximum(np.abs(sa[rest[c]]).max(axis=1) + np.abs(sb[rest[c]]).max(axis=1), 1e-300)
            sc = tuple(x[c] for x in sub)
            f[c], u[c] = _gilbert(u[c], f[c], sc, scale)
            f[c], u[c] = _alternate(u[c], f[c], sc, scale)
            f[c], u[c] = _descend(u[c], f[c], sc, scale)
            # overlapping: h_D may have several local minima; descend from the best
            # few of the axes and an even spread of directions too
            o = np.flatnonzero(f[c] > 0)
            if len(o):
                co = c[o]
                so = tuple(x[o] for x in sc)
                starts = np.concatenate([dirs[co], np.broadcast_to(_SPREAD, (len(co),) + _SPREAD.shape)], axis=1)
                k = starts.shape[1]
                h, _, _ = _h_d(*(np.repeat(x, k, axis=0) for x in so), starts.reshape(-1, 3))
                best = np.argsort(h.reshape(len(co), k), axis=1)[:, :MULTI_STARTS]
                u0 = np.take_along_axis(starts, best[:, :, None], axis=1).reshape(-1, 3)
                f0 = np.take_along_axis(h.reshape(len(co), k), best, axis=1).ravel()
                rep = tuple(np.repeat(x, MULTI_STARTS, axis=0) for x in so)
                f1, u1 = _descend(u0, f0, rep, np.repeat(scale[o], MULTI_STARTS))
                f1 = f1.reshape(len(co), MULTI_STARTS)
                j = np.argmin(f1, axis=1)
                f_new = f1[np.arange(len(co)), j]
                u_new = u1.reshape(len(co), MULTI_STARTS, 3)[np.arange(len(co)), j]
                better = f_new < f[co]
                f[co[better]], u[co[better]] = f_new[better], u_new[better]
        _, wa, wb = _h_d(*sub, u)
        sd[rest] = -f
        where[rest] = 0.5 * (wa + wb)
        exact[rest] = polytope
        apart = boxes & (f < 0)          # no separating axis fails: the boxes are apart
        sd[rest[apart]] = np.nan
    boxes_apart = np.isnan(sd)
    return sd, where, exact, boxes_apart
