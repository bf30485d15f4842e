"""Cables against parts (cable-structure and keep-out), one state or many.

Method ``points`` (the discrete-point distance method, Ju et al., 2016): a
point's signed distance to the part's surface (negative inside, so
containment comes for free), minus the cable radius. Method ``exact``: the
least signed distance along each element (:mod:`cablecheck.checker.shapes`), so contact
between two discrete points is never missed.

The parts are prepared once as arrays (:class:`PartTable`); the broad phase
(:func:`cablecheck.checker.interference.broad.chunk_part_pairs`) gives (item, part)
candidates, cut to the part's inflated local box and the exclusion windows
before any exact work. Narrow phases are batched per shape type (all
primitives' segment searches in one call); meshes per mesh, the parts
sharing one mesh in one call through the mesh's own tree.
:func:`structure_many` takes given (body centre, part) pairs over many states
at once and shares :func:`point_values` with the single-state pass;
:func:`near_entries` keeps of those pairs, state by state, the ones whose
elements come near enough to the part's box for a point to be evaluated.

Deliberately not here: part-part interference (:mod:`cablecheck.checker.parts`), cable
pairs, the reduction to records (:mod:`cablecheck.checker.interference.hits`).
"""

from __future__ import annotations

import copy
from collections.abc import Sequence

import numpy as np

from cablecheck.checker.arrays import all_columns
from cablecheck.checker.closest import row_norm
from cablecheck.checker.interference.broad import chunk_part_pairs
from cablecheck.checker.interference.discrete import DenseStates
from cablecheck.checker.interference.hits import TYPE_ORDER, near_misses_of, worst_records
from cablecheck.checker.records import Interference, PairType
from cablecheck.checker.scene_state import CheckConfig, PartState
from cablecheck.checker.shapes import (
    SHAPE_CODE,
    ShapeType,
    distance_bounds,
    face_plane_distance,
    face_plane_distance_batch,
    primitive_bounds,
    segment_signed_distance,
    segment_signed_distance_mixed,
    signed_distance,
    signed_distance_value_batch,
    size_rows,
)

_TYPES = list(ShapeType)
"""Shape types by their codes (SHAPE_CODE)."""
_STRUCTURE, _KEEPOUT = TYPE_ORDER.index(PairType.CABLE_STRUCTURE), TYPE_ORDER.index(PairType.KEEPOUT)


class PartTable:
    """Parts as arrays: what does not change between calls (shapes, bounds,
    keep-out flags) is built once; :meth:`posed` adds rotations and
    translations for one call."""

    def __init__(self, parts: Sequence[PartState]):
        k = len(parts)
        self.parts = parts
        self.names = [pt.name for pt in parts]
        self.size = size_rows([pt.shape for pt in parts])
        self.type = np.array([SHAPE_CODE[pt.shape.type] for pt in parts], dtype=np.int64).reshape(k)
        self.lo, self.hi = primitive_bounds(self.type, self.size)
        for n in np.nonzero(self.type == SHAPE_CODE[ShapeType.MESH])[0]:
            self.lo[n], self.hi[n] = parts[n].shape.local_bounds()
        self.keepout = np.array([pt.keepout for pt in parts], dtype=bool)
        # Parts sharing one mesh are answered in one call: group id per part.
        groups: dict[int, int] = {}
        self.mesh_group = np.array([groups.setdefault(id(pt.shape.mesh), len(groups)) if pt.shape.mesh is not None
                                    else -1 for pt in parts], dtype=np.int64).reshape(k)
        self.mesh_shapes = [None] * len(groups)
        for pt in parts:
            if pt.shape.mesh is not None:
                self.mesh_shapes[groups[id(pt.shape.mesh)]] = pt.shape
        self.is_plane = self.type == SHAPE_CODE[ShapeType.PLANE]
        # Bounding spheres of the finite parts, in their own frames.
        self.finite = np.nonzero(~self.is_plane)[0]
        self.planes = np.nonzero(self.is_plane)[0]
        fin = self.finite
        self.c_loc = 0.5 * (self.lo[fin] + self.hi[fin])
        self.half_diag = 0.5 * row_norm(self.hi[fin] - self.lo[fin])
        self.rot = np.array([pt.pose[:3, :3] for pt in parts]).reshape(k, 3, 3)
        self.trans = np.array([pt.pose[:3, 3] for pt in parts]).reshape(k, 3)

    def rows(self, idx: np.ndarray) -> PartTable:
        """The parts ``idx`` (n,) of this table, in that order (a part may
        repeat): each array's rows taken, the same bits, nothing built again
        from the parts (a batch's thousands of copies of a few parts)."""
        idx = np.asarray(idx, np.int64)
        out = copy.copy(self)
        at = idx.tolist()
        out.parts = [self.parts[k] for k in at]
        out.names = [self.names[k] for k in at]
        out.size, out.type, out.lo, out.hi = (x[idx] for x in (self.size, self.type, self.lo, self.hi))
        out.keepout, out.mesh_group, out.is_plane = self.keepout[idx], self.mesh_group[idx], self.is_plane[idx]
        out.finite = np.nonzero(~out.is_plane)[0]
        out.planes = np.nonzero(out.is_plane)[0]
        fin = out.finite
        out.c_loc = 0.5 * (out.lo[fin] + out.hi[fin])
        out.half_diag = 0.5 * row_norm(out.hi[fin] - out.lo[fin])
        out.rot, out.trans = self.rot[idx], self.trans[idx]
        return out

    def posed(self, poses: np.ndarray | None) -> PartTable:
        """This table with poses (K, 4, 4) (None: the parts' own poses)."""
        if poses is None:
            return self
        out = copy.copy(self)
        out.rot = np.ascontiguousarray(poses[:, :3, :3])
        out.trans = np.ascontiguousarray(poses[:, :3, 3])
        return out

    def to_local(self, k: np.ndarray, x: np.ndarray) -> np.ndarray:
        """World points x (n, 3) into the frames of parts k (n,)."""
        return to_local(x, self.trans.take(k, axis=0), self.rot.take(k, axis=0))


def to_local(x: np.ndarray, trans: np.ndarray, rot: np.ndarray) -> np.ndarray:
    """World points x (n, 3) into frames of translations (n, 3) and rotations (n, 3, 3): R^T (x - t)."""
    return np.einsum("ni,nij->nj", x - trans, rot)


def excluded(cable: np.ndarray, part: np.ndarray, s: np.ndarray, excl: tuple) -> np.ndarray:
    """True where (cable, part, material coordinate s) falls in an exclusion window."""
    key_e, smin, smax, n_parts = excl
    out = np.zeros(len(s), dtype=bool)
    if len(key_e) == 0 or len(s) == 0:
        return out
    key = cable * n_parts + part
    lo = np.searchsorted(key_e, key, side="left")
    hi = np.searchsorted(key_e, key, side="right")
    cnt = hi - lo
    if cnt.sum() == 0:
        return out
    rows = np.repeat(np.arange(len(s)), cnt)
    first = np.cumsum(cnt) - cnt
    w = lo[rows] + np.arange(len(rows)) - first[rows]
    inside = (s[rows] >= smin[w]) & (s[rows] <= smax[w])
    return np.bincount(rows, weights=inside, minlength=len(s)) > 0


def point_distances(tab: PartTable, pk: np.ndarray, loc: np.ndarray, face_plane: bool,
                     limit: np.ndarray | None = None, group: np.ndarray | None = None) -> np.ndarray:
    """Signed distance (n,) of local points ``loc`` to parts ``pk``, batched by type.

    With ``limit`` (n,): a mesh may answer a point that provably lies beyond
    its limit with a lower bound above it instead (see
    :func:`cablecheck.checker.shapes.signed_distance`); callers keep only values below.
    With ``group`` (n,) ids too (each group against one part), the caller
    wants only each group's least value exact: a mesh point whose lower
    bound exceeds another point's upper bound in its group may likewise be
    answered by a bound, above the group's least value."""
    d = np.full(len(pk), np.inf)
    code = tab.type.take(pk)
    # the points of each type (each in increasing order) from one stable sort
    order = np.argsort(code, kind="stable")
    bounds = np.r_[0, np.cumsum(np.bincount(code, minlength=len(_TYPES)))]
    for c in np.flatnonzero(np.diff(bounds)):
        stype = _TYPES[c]
        sel = order[bounds[c]:bounds[c + 1]]
        if stype is ShapeType.MESH:
            grp = tab.mesh_group.take(pk.take(sel))
            for g in np.unique(grp):
                sk = sel[grp == g]
                shape = tab.mesh_shapes[g]
                lim = None if limit is None else limit[sk]
                lower = None
                if lim is not None and group is not None and not face_plane:
                    # each group's most promising point (least upper bound)
                    # exactly first: the others then need be exact only below it
                    lower, hi = distance_bounds(shape, loc[sk])
                    ids, inv = np.unique(group[sk], return_inverse=True)
                    o = np.lexsort((hi, inv))
                    lead = o[np.r_[True, inv[o][1:] != inv[o][:-1]]]
                    lead = lead[hi[lead] < lim[lead]]
                    d[sk[lead]] = signed_distance(shape, loc[sk[lead]])[0]
                    least = np.full(len(ids), np.inf)
                    least[inv[lead]] = d[sk[lead]]
                    lim = np.minimum(lim, least[inv])
                    rest = np.ones(len(sk), bool)
                    rest[lead] = False
                    sk, lim, lower = sk[rest], lim[rest], lower[rest]
                d[sk] = face_plane_distance(shape, loc[sk]) if face_plane else \
                    signed_distance(shape, loc[sk], lim, lower)[0]
        elif face_plane:
            d[sel] = face_plane_distance_batch(stype, tab.size.take(pk.take(sel), axis=0), loc.take(sel, axis=0))
        else:
            d[sel] = signed_distance_value_batch(stype, tab.size.take(pk.take(sel), axis=0), loc.take(sel, axis=0))
    return d


def point_values(tab: PartTable, k: np.ndarray, loc: np.ndarray, rad: np.ndarray, cable: np.ndarray,
                 m: np.ndarray, excl: tuple, limit: float, face_plane: bool, group: np.ndarray | None = None,
                 excl_record: tuple | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """Values of points against parts: the one kernel of :func:`structure_points` and :func:`structure_many`.

    A point (local coordinates ``loc`` in part k, its cable's radius, cable
    and material coordinate m) is kept when it lies within ``rad + limit``
    of the part's local box and outside the exclusion windows ``excl``;
    its value is the signed distance to the part minus the radius
    (:func:`point_distances`, with ``group`` as there), kept below ``limit``.

    Returns:
        (index of the points kept, their values, and with ``excl_record``
        whether each lies outside those windows too, else None).
    """
    thr = (rad + limit)[:, None]
    inb = (loc >= tab.lo.take(k, axis=0) - thr) & (loc <= tab.hi.take(k, axis=0) + thr)
    keep = inb[:, 0] & inb[:, 1] & inb[:, 2]
    keep &= ~excluded(cable, k, m, excl)
    idx = np.flatnonzero(keep)
    k, loc, rad = k.take(idx), loc.take(idx, axis=0), rad.take(idx)
    rec = None if excl_record is None else ~excluded(cable.take(idx), k, m.take(idx), excl_record)
    v = point_distances(tab, k, loc, face_plane, rad + limit, None if group is None else group.take(idx)) - rad
    o = v < limit
    return idx[o], v[o], None if rec is None else rec[o]


def structure_points(dp, ch, tab, config, excl, hits, limit=None, excl_near=None) -> None:
    """Signed distance of every candidate point to its part, minus r.

    With ``limit`` (>= clearance), candidates up to ``limit``; with
    ``excl_near`` (narrower windows), points inside ``excl`` but outside
    ``excl_near`` are kept too: both only bound the gaps, never records."""
    limit = config.clearance if limit is None else limit
    margin = float(dp.radius.max()) + limit
    it, pk = chunk_part_pairs(tab, ch, margin, box=True)
    if len(it) == 0:
        return
    loc = tab.to_local(pk, dp.p.take(it, axis=0))
    o, v, rec = point_values(tab, pk, loc, dp.radius.take(it), dp.cable.take(it), dp.m.take(it),
                             excl if excl_near is None else excl_near, limit, config.face_plane,
                             excl_record=None if excl_near is None else excl)
    it, pk = it.take(o), pk.take(o)
    _add_structure(hits, tab, dp.cable.take(it), pk, v, dp.p.take(it, axis=0), dp.s.take(it), rec)


def structure_exact(dp, ch, tab, config, excl, hits) -> None:
    """Least signed distance along every candidate element to its part, minus r."""
    if len(dp.seg) == 0:
        return
    # Chunk spheres hold whole elements: the margin needs no half length.
    margin = float(dp.radius.max()) + config.clearance
    i0, pk = chunk_part_pairs(tab, ch, margin, box=True)
    structure_exact_pairs(dp, tab, config, excl, hits, i0, pk)


def structure_exact_pairs(dp, tab, config, excl, hits, i0: np.ndarray, pk: np.ndarray,
                          below: np.ndarray | None = None) -> None:
    """:func:`structure_exact` on given (element, part) candidates (element
    i0 joins points i0 and i0 + 1): any superset of the broad phase's
    candidates gives the same records (the filters below only drop elements
    farther than the clearance). ``below`` (n,): each candidate measured
    only where it may come below that (at most the clearance) instead:
    the least value of a pair stays exact where it is below its ``below``."""
    p, s = dp.p, dp.s
    if len(i0) == 0:
        return
    a = tab.to_local(pk, p[i0])
    b = tab.to_local(pk, p[i0 + 1])
    # Cuts were inserted at the window ends, so an element is in a window
    # exactly when its midpoint is.
    keep = np.flatnonzero(~excluded(dp.cable[i0], pk, 0.5 * (dp.m[i0] + dp.m[i0 + 1]), excl))
    limit = config.clearance if below is None else np.minimum(below[keep], config.clearance)
    within, mid = segments_within(tab, pk[keep], a[keep], b[keep], dp.radius[i0[keep]], limit, midpoints=True)
    near = keep[within]
    pk, i0, a, b = pk[near], i0[near], a[near], b[near]
    # a centreline farther than the limit plus the radius is no record: a mesh need not say how far
    keep_limit = np.broadcast_to(np.asarray(limit, float), (len(keep),))[within] + dp.radius[i0]
    d, t = segment_distances(tab, pk, a, b, mid, keep_limit * (1 + 1e-9) + 1e-12 * (1.0 + np.abs(keep_limit)))
    where = p[i0] + t[:, None] * (p[i0 + 1] - p[i0])
    s_at = s[i0] + t * (s[i0 + 1] - s[i0])
    _add_structure(hits, tab, dp.cable[i0], pk, d - dp.radius[i0], where, s_at)


def segments_within(tab: PartTable, pk: np.ndarray, a: np.ndarray, b: np.ndarray, rad: np.ndarray,
                    limit: float | np.ndarray, midpoints: bool = False) -> np.ndarray | tuple[np.ndarray, np.ndarray]:
    """Indices of the local segments ``a b`` (n, 3) whose signed distance to
    parts ``pk`` (n,), less ``rad`` (n,), may lie below ``limit`` (scalar or (n,)): those
    within ``rad + limit`` of the part's local box whose midpoint's distance
    less half their length (signed distance is 1-Lipschitz, so that bounds
    the segment's from below) is below it too. The others need no search.
    ``midpoints``: also those segments' midpoints' signed distances (exact:
    each an upper bound on its segment's unsigned distance, for
    :func:`segment_distances`)."""
    limit = np.broadcast_to(np.asarray(limit, float), (len(pk),))
    thr = (rad + limit)[:, None]
    box = all_columns((np.maximum(a, b) >= tab.lo[pk] - thr) & (np.minimum(a, b) <= tab.hi[pk] + thr))
    idx = np.flatnonzero(box)
    half = 0.5 * row_norm(b[idx] - a[idx])
    mid = point_distances(tab, pk[idx], 0.5 * (a[idx] + b[idx]), False, limit[idx] + half + rad[idx])
    kept = mid - half - rad[idx] < limit[idx]
    return (idx[kept], mid[kept]) if midpoints else idx[kept]


def segment_distances(tab: PartTable, pk: np.ndarray, a: np.ndarray, b: np.ndarray,
                      mid: np.ndarray | None = None, cap: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Least signed distance (n,) of local segments ``a b`` (n, 3) to parts
    ``pk`` (n,), and the parameter (n,) of the deepest or nearest point:
    each mesh's rows in one call, all primitives' in one. ``mid`` (n,): the
    segments' midpoints' signed distances, where the caller has them
    (:func:`segments_within`): a mesh then searches only the faces that may
    come within them; and with ``cap`` (n,), distances past it are not kept:
    a mesh may answer them at the cap (`segment_signed_distance`)."""
    d = np.full(len(pk), np.inf)
    t = np.zeros(len(pk))
    is_mesh = tab.type[pk] == SHAPE_CODE[ShapeType.MESH]
    sel = np.nonzero(is_mesh)[0]
    grp = tab.mesh_group[pk[sel]]
    for g in np.unique(grp):
        sk = sel[grp == g]
        d[sk], t[sk] = segment_signed_distance(tab.mesh_shapes[g], a[sk], b[sk], None if mid is None else mid[sk],
                                               None if mid is None or cap is None else cap[sk])
    # All primitives in one call (box and cylinder share one line search).
    sel = np.nonzero(~is_mesh)[0]
    if len(sel):
        d[sel], t[sel] = segment_signed_distance_mixed(
            tab.type[pk[sel]], tab.size[pk[sel]], a[sel], b[sel])
    return d, t


def _add_structure(hits, tab, cable, part, value, where, s, record=None) -> None:
    ko = tab.keepout[part]
    for kind, o in ((PairType.CABLE_STRUCTURE, ~ko), (PairType.KEEPOUT, ko)):
        hits.add(kind, cable[o], part[o], value[o], where[o], s[o], None, None if record is None else record[o])


def near_entries(tab: PartTable, pts: np.ndarray, poses: np.ndarray, valid: np.ndarray, rad: np.ndarray,
                 limit: float, active: tuple[np.ndarray, np.ndarray]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The (state, centre, part) entries of active (centre, part) pairs at
    S states some of whose points may pass :func:`point_values`'s box test.

    The points of an entry (:func:`active_points`) lie on the elements next
    to its centre: in part k's frame (an affine map) inside the
    axis-aligned box of the centre and its neighbours on those elements.
    Where that box lies farther than ``rad + limit`` outside the part's
    local box on some axis, so does every such point, and the box test
    drops them all; a margin of 1e-9 of the scene's extent covers the
    rounding of the points' own coordinates (each a few ulp).

    Args:
        pts: (S, N, 3) body centres; poses: (S, K, 4, 4) the parts' poses.
        valid: (N - 1,) element i joins centres i and i + 1 of one cable.
        rad: (N,) the cable radius at each centre.
        limit: the values kept (the clearance).
        active: (centre, part) arrays.
    """
    ci, pi = (np.asarray(x, np.int64) for x in active)
    n_s, n = pts.shape[:2]
    if n_s == 0 or len(ci) == 0:
        z = np.zeros(0, np.int64)
        return z, z, z
    before = np.where((ci > 0) & valid[np.maximum(ci - 1, 0)], ci - 1, ci)     # the elements' far ends
    after = np.where((ci < n - 1) & valid[np.minimum(ci, n - 2)], ci + 1, ci)
    rot = poses[:, pi, :3, :3]                                                 # (S, E, 3, 3)
    trans = poses[:, :, :3, 3][:, pi]                                          # (S, E, 3)
    u = [np.einsum("sei,seij->sej", pts[:, c] - trans, rot) for c in (before, ci, after)]
    lo = np.minimum(np.minimum(u[0], u[1]), u[2])
    hi = np.maximum(np.maximum(u[0], u[1]), u[2])
    scale = max(float(np.abs(pts).max()), float(np.abs(trans).max()))
    thr = (rad[ci] + limit + 1e-9 * (1.0 + scale))[:, None]
    near = ((hi >= tab.lo[pi] - thr) & (lo <= tab.hi[pi] + thr)).all(axis=2)      # (S, E)
    state, e = np.nonzero(near)
    return state, ci[e], pi[e]


def active_points(src: np.ndarray, own: np.ndarray, ci: np.ndarray, pi: np.ndarray,
                  n: int, states: int, si: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(point, part) pairs of discrete points and the parts they are active
    for, sorted by part and then point, each once: a point is active for part
    k when (its centre, k) is an active entry or, for a point inside an
    element (not ``own``), when (the element's far centre, k) is.

    The points of centre g are a run (its own point, then those inside the
    element after it, :func:`cablecheck.checker.cable.densify_batch`), so an entry's
    points are one run too: from past the previous centre's own point to the
    next centre's. The runs of a part's entries (over every state), merged
    where they overlap, are expanded at once: the cost grows with the pairs
    found, not with the points times the parts.

    Args:
        src, own: (M,) each point's body centre counted over all states
            (nondecreasing, every present centre's own point first) and
            whether the point is that centre itself. Points may be those of
            some centres only (``densify_many``'s ``keep``): every entry's
            centre and both its neighbours must be present.
        ci, pi: the active entries (centre in a state, part).
        n: body centres per state.
        states: S, the states.
        si: the state of each entry, or None (each entry in every state).
    """
    if len(ci) == 0:
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    start = np.flatnonzero(own)                 # the own point of every present centre, in order
    present = src[start]
    end = np.r_[start[1:], len(src)]             # up to the next present centre's own point
    if si is None:
        g = (np.arange(states, dtype=np.int64)[:, None] * n + np.asarray(ci, np.int64)[None, :]).ravel()
        k = np.broadcast_to(np.asarray(pi, np.int64), (states, len(ci))).ravel()
    else:
        g = np.asarray(si, np.int64) * n + np.asarray(ci, np.int64)
        k = np.asarray(pi, np.int64)
    o = np.lexsort((g, k))
    g, k = g[o], k[o]
    at = np.searchsorted(present, g)
    before = np.maximum(at - 1, 0)
    # past the previous centre's own point (its points inside the element up to g)
    lo = np.where((at > 0) & (present[before] == g - 1), start[before] + 1, start[at])
    hi = end[at]
    # merge the runs of a part that overlap (sorted by centre, both ends grow)
    new = np.r_[True, (k[1:] != k[:-1]) | (lo[1:] >= hi[:-1])]
    first = np.flatnonzero(new)
    last = np.r_[first[1:], len(new)] - 1
    lo, hi, k = lo[first], hi[last], k[first]
    size = hi - lo
    total = int(size.sum())
    it = np.repeat(lo - (np.cumsum(size) - size), size) + np.arange(total)
    return it, np.repeat(k, size)


def structure_many(tab: PartTable | None, config: CheckConfig, excl: tuple, names: Sequence[str],
                   radii: np.ndarray, dense: DenseStates, poses: np.ndarray,
                   active: tuple[np.ndarray, ...], near_errors: np.ndarray | None = None
                   ) -> list[list[Interference]] | tuple[list[list[Interference]], list[list[Interference]]]:
    """The full check's cable-structure and keep-out records at many
    states at once, from the discrete points next to given body centres
    (method ``points``; to the bit).

    Against part k only the points on elements next to an active
    (centre, k) entry are evaluated: the centre itself and the points
    inside its two elements. A record is the worst of those places (the
    caller knows the others to be clear).

    Args:
        names, radii: the cables' names and radii (C,).
        dense: the states' discrete points (:meth:`densify_many`).
        poses: (S, K, 4, 4) the parts' poses at every state.
        excl: the exclusion table (:meth:`Checker._exclusion_table`).
        active: (centre index in a state, part index) arrays, each entry
            in every state; or (state, centre, part) arrays, each entry in
            its own state (:func:`near_entries`).
        near_errors: (C,) per cable, what its points may over-state
            (:func:`~cablecheck.checker.interference.pipeline.near_miss_errors`):
            the near misses are found too (as :meth:`Hits.near_misses`).

    Returns:
        per state, its records (worst first); with ``near_errors``, and per
        state its near misses.
    """
    n_s, n, n_c, n_k = dense.states, dense.centres, dense.cables, (0 if tab is None else len(tab.names))
    out: list[list[Interference]] = [[] for _ in range(n_s)]
    si = np.asarray(active[0], np.int64) if len(active) == 3 else None
    ci, pi = (np.asarray(x, np.int64) for x in active[-2:])
    if n_s == 0 or len(ci) == 0 or tab is None:
        return out if near_errors is None else (out, [[] for _ in range(n_s)])
    radii = np.asarray(radii, float)
    p, s, src, own = dense.p, dense.s, dense.src, dense.own
    state, cab = dense.poly // n_c, dense.poly % n_c
    it, k = active_points(src, own, ci, pi, n, n_s, si)
    q = state[it] * n_k + k
    rot = np.ascontiguousarray(poses[:, :, :3, :3]).reshape(-1, 3, 3)
    trans = np.ascontiguousarray(poses[:, :, :3, 3]).reshape(-1, 3)
    loc = to_local(p[it], trans[q], rot[q])
    # only the worst place per (state, cable, part) becomes a record
    group = (state[it] * n_c + cab[it]) * n_k + k
    err = None if near_errors is None else np.asarray(near_errors, float)
    limit = config.clearance + (0.0 if err is None else float(err.max(initial=0.0)))
    o, v, _ = point_values(tab, k, loc, radii[cab[it]], cab[it], dense.m[it], excl, limit,
                           config.face_plane, group)
    it, k = it[o], k[o]
    kind = np.where(tab.keepout[k], _KEEPOUT, _STRUCTURE)
    records = worst_records(n_s, state[it], kind, cab[it], k, v, p[it], s[it], np.full(len(v), np.nan),
                            config.clearance, names, lambda _: tab.names)
    if err is None:
        return records
    return records, near_misses_of(n_s, state[it], kind, cab[it], k, v, s[it], config.clearance, err[cab[it]],
                                   names, tab.names)

