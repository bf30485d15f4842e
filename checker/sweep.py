"""Translational sweep verification (Fang et al.): which parts does a moving part hit, and when?

:func:`sweep` moves a set of parts (one part or an assembly) from their
placed poses along a direction ``D`` by a distance ``H`` and returns every
other part it would hit with the travel at first contact, plus the parts it
already overlaps at the start.

Method, pruning level by level before any exact test (the sweep-verification
and lightweight-CAD papers):

1. the moving parts' boxes in a frame whose z axis is ``D``, stretched by
   ``H`` along z, form one oriented box (the swept box);
2. assemblies whose world AABB misses the swept box's AABB drop all their
   parts; the rest are tested with the 15-axis separating-axis test against
   the swept box;
3. each surviving part's triangle tree is queried with the swept box in the
   part's frame; each candidate triangle, swept backwards by ``H``, queries
   the moving parts' trees: the result is the candidate triangle pairs;
4. exact continuous tests on those pairs: moving corners against fixed faces,
   fixed corners against moving faces (moving by ``-D``), and edge against
   edge (:mod:`cablecheck.checker.tritri`). Infinite planes are tested corner by corner.

Contact rule (touching versus hitting): a contact counts only when the motion
carries the parts into each other: a corner meets a face whose outward
normal opposes ``D`` (``D . n < 0``), or two edges meet while ``D`` points
into the fixed part across the contact normal (oriented by the fixed edge's
pseudonormal). So a part resting on a face and pulled away, or sliding along
a face parallel to ``D`` (grazing), is not hit; a part resting on a face and
pushed into it is hit at travel 0. For an open mesh (no outside) any
non-parallel contact counts.

Start overlap: surfaces that cross properly
(:func:`cablecheck.checker.tritri.triangles_cross`) or containment probes strictly
inside the other part (:mod:`cablecheck.checker.partset`); touching is not overlapping.

Exactness: the first-contact travel is exact (up to floating point) for the
triangle surfaces; boxes and meshes are their own surfaces, curved primitives
are inscribed tessellations within ``PartSet.error`` of the true surface.

Not here: reading scenes, poses from a simulation, printing.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cablecheck.checker.arrays import all_columns, ranges
from cablecheck.checker.bvh import obb_overlap, prefix_hits, transformed_aabb
from cablecheck.checker.partset import PROBE_DEPTH, TOUCH, PartSet, Placement
from cablecheck.checker.shapes import signed_distance, signed_distance_value_batch
from cablecheck.checker.tritri import EPS, edge_edge_contact, triangles_cross, vertex_face_contact

_ROUNDS = 16
"""Most candidate contacts tried per part before the earliest is reported unverified."""

STEP = 1e-4
"""Default verification step, relative to the moving parts' box diagonal."""

_ANGLE = 1e-12
"""|D . n| below this counts as sliding along a face (no contact)."""


@dataclass(frozen=True)
class SweepHit:
    """A part the moving set would hit.

    Attributes:
        part: the part hit.
        distance: travel at first contact (same units as the geometry).
        where: (3,) contact point on ``part``, world, at its placed pose.
        by: the moving part that touches it first.
    """

    part: str
    distance: float
    where: np.ndarray
    by: str


@dataclass(frozen=True)
class SweepResult:
    """The outcome of one sweep.

    Attributes:
        hits: parts hit, by travel then name.
        overlapping: parts the moving set already overlaps at the start, by name.
        candidates: parts that survived the box levels (for reports and benchmarks).
        warnings: notes about parts whose inside is undecided.
    """

    hits: tuple[SweepHit, ...]
    overlapping: tuple[str, ...]
    candidates: int
    warnings: tuple[str, ...]


def _frame(d: np.ndarray) -> np.ndarray:
    """(3, 3) rotation whose third column is the unit vector ``d``."""
    helper = np.eye(3)[int(np.argmin(np.abs(d)))]
    e1 = np.cross(helper, d)
    e1 /= np.linalg.norm(e1)
    return np.column_stack([e1, np.cross(d, e1), d])


def sweep(parts: PartSet, placed: Placement, moving: np.ndarray, direction: np.ndarray,
          distance: float, against: np.ndarray | None = None, step: float | None = None) -> SweepResult:
    """Sweep the parts ``moving`` ((P,) bool) along ``direction`` by ``distance``.

    Args:
        parts, placed: the prepared parts and their poses.
        moving: (P,) bool, the parts that move together.
        direction: (3,) non-zero direction (need not be unit).
        distance: travel, >= 0.
        against: (P,) bool, the parts to test (default: all others).
        step: travel beyond a candidate contact at which overlap must show for
            it to count as a hit (default ``STEP`` of the moving parts' size;
            the command line passes a quarter of the stated precision). A hit
            is then reported at the contact itself, exact; overlaps that
            appear within ``step`` after a mere touch are attributed to it.
    """
    d = np.asarray(direction, float)
    norm = float(np.linalg.norm(d))
    if not (norm > 0 and np.isfinite(norm)):
        raise ValueError("direction must be a finite non-zero vector")
    if not (distance >= 0 and np.isfinite(distance)):
        raise ValueError("distance must be finite and non-negative")
    d = d / norm
    moving = np.asarray(moving, bool)
    if not moving.any():
        raise ValueError("no part moves")
    if (moving & parts.plane).any():
        raise ValueError("an infinite plane cannot be swept")
    stat = ~moving if against is None else (~moving & np.asarray(against, bool))
    f = _frame(d)
    mv = np.flatnonzero(moving)
    half = parts.half()
    # 1. swept box in the sweep frame (x_s = f^T x_world)
    ft = np.repeat(f.T[None], len(mv), axis=0)
    m_lo, m_hi = transformed_aabb(parts.lo[mv], parts.hi[mv], ft @ placed.rot[mv],
                                  np.einsum("ij,nj->ni", f.T, placed.pos[mv]))
    part_lo_s, part_hi_s = m_lo, m_hi
    s_lo, s_hi = m_lo.min(axis=0), m_hi.max(axis=0)
    s_hi = s_hi + np.array([0.0, 0.0, distance])
    s_c, s_h = 0.5 * (s_lo + s_hi), 0.5 * (s_hi - s_lo)
    # 2. assemblies, then part OBBs
    w_lo, w_hi = transformed_aabb(s_lo[None], s_hi[None], f[None], np.zeros((1, 3)))
    asm_hit = all_columns((placed.asm_lo <= w_hi) & (w_lo <= placed.asm_hi))
    cand = np.flatnonzero(stat & ~parts.plane & prefix_hits(parts.assemblies, asm_hit))
    k = len(cand)
    if k:
        ok = obb_overlap(np.repeat((f @ s_c)[None], k, 0), np.repeat(f[None], k, 0),
                         np.repeat(s_h[None], k, 0), placed.centre[cand], placed.rot[cand], half[cand])
        cand = cand[ok]
    # 3. triangles of the candidates, then moving triangles near each
    rot_s = np.einsum("nji,jk->nik", placed.rot[cand], f)          # sweep frame -> part frame
    shift_s = -np.einsum("nji,nj->ni", placed.rot[cand], placed.pos[cand])
    q_lo, q_hi = transformed_aabb(np.repeat(s_lo[None], len(cand), 0), np.repeat(s_hi[None], len(cand), 0),
                                  rot_s, shift_s)
    qi, st = parts.forest.query(cand, q_lo, q_hi)
    st_part = parts.tri_part[st]
    st_world = placed.world(st_part, parts.tris[st])
    st_s = st_world @ f                                             # sweep-frame coordinates
    b_lo, b_hi = st_s.min(axis=1), st_s.max(axis=1)
    b_lo = b_lo - np.array([0.0, 0.0, distance])                    # swept backwards
    # which moving parts each fixed triangle may meet (sweep-frame boxes)
    pm = np.all((b_lo[:, None, :] <= part_hi_s[None] + [0, 0, 0]) &
                (part_lo_s[None] <= b_hi[:, None, :]), axis=2)
    ti, mj = np.nonzero(pm)
    mparts = mv[mj]
    rot_m = np.einsum("nji,jk->nik", placed.rot[mparts], f)
    shift_m = -np.einsum("nji,nj->ni", placed.rot[mparts], placed.pos[mparts])
    l_lo, l_hi = transformed_aabb(b_lo[ti], b_hi[ti], rot_m, shift_m)
    qq, mt = parts.forest.query(mparts, l_lo, l_hi)
    fixed = ti[qq]                         # row into st
    ms = mt                                 # moving triangle (global index)
    m_world = placed.world(parts.tri_part[ms], parts.tris[ms])
    f_world = st_world[fixed]
    f_part = st_part[fixed]
    m_part = parts.tri_part[ms]
    # 4a. start overlap: crossing surfaces, then containment probes
    over = np.zeros(len(parts.names), bool)
    now = np.all((m_world.min(axis=1) <= f_world.max(axis=1)) & (f_world.min(axis=1) <= m_world.max(axis=1)),
                 axis=1)
    cross = triangles_cross(m_world[now], f_world[now], parts.touch(m_part[now], f_part[now]))
    over[f_part[now][cross]] = True
    start_lo, start_hi = placed.lo[mv].min(axis=0), placed.hi[mv].max(axis=0)
    near = cand[~over[cand]]
    near = near[all_columns((placed.lo[near] <= start_hi) & (start_lo <= placed.hi[near]))]
    over |= _contained(parts, placed, mv, near)
    # 4b. first contact
    t_best = np.full(len(parts.names), np.inf)
    where = np.zeros((len(parts.names), 3))
    by = np.full(len(parts.names), -1)
    if len(ms):
        # only a fixed face meeting the motion head-on (D . n < 0) and a moving
        # face leading it (D . n > 0) can hold a first contact: every corner
        # and edge that meets first lies on such a pair of faces
        dn_f = np.einsum("nij,nj->ni", placed.rot[f_part], parts.normals[st[fixed]]) @ d
        dn_m = np.einsum("nij,nj->ni", placed.rot[m_part], parts.normals[ms]) @ d
        lead = ((dn_f < -_ANGLE) | ~parts.closed[f_part]) & ((dn_m > _ANGLE) | ~parts.closed[m_part])
        sel = np.flatnonzero(lead)
        t, p, pr = _contacts(parts, placed, d, distance, m_world[sel], f_world[sel], ms[sel],
                             st[fixed][sel], m_part[sel], f_part[sel])
        pr = sel[pr]
        _verify(parts, placed, mv, d, m_world, f_world, f_part, m_part, t, p, pr,
                _step(parts, mv, step, m_world), t_best, where, by)
    _planes(parts, placed, d, distance, mv, stat, t_best, where, by, over)
    hit_idx = np.flatnonzero(np.isfinite(t_best) & ~over)
    hits = sorted((SweepHit(parts.names[i], float(t_best[i]), where[i].copy(), parts.names[by[i]])
                   for i in hit_idx), key=lambda h: (h.distance, h.part))
    involved = set(cand.tolist()) | set(mv.tolist())
    warns = tuple(w for i, w in enumerate(parts.warnings) if any(
        f"part {parts.names[j]!r}" in w for j in involved))
    return SweepResult(tuple(hits), tuple(sorted(parts.names[i] for i in np.flatnonzero(over))),
                       len(cand), warns)


def _contacts(parts: PartSet, placed: Placement, d: np.ndarray, h: float, m_world: np.ndarray,
              f_world: np.ndarray, m_tri: np.ndarray, f_tri: np.ndarray, m_part: np.ndarray,
              f_part: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Exact contacts over triangle pairs: travels (k,), points (k, 3), pair rows (k,)."""
    n = len(m_world)
    m_n = np.einsum("nij,nj->ni", placed.rot[m_part], parts.normals[m_tri])
    f_n = np.einsum("nij,nj->ni", placed.rot[f_part], parts.normals[f_tri])
    f_closed = parts.closed[f_part]
    m_closed = parts.closed[m_part]
    dn_f = f_n @ d
    dn_m = m_n @ d
    into_f = np.where(f_closed, dn_f < -_ANGLE, np.abs(dn_f) > _ANGLE)
    into_m = np.where(m_closed, dn_m > _ANGLE, np.abs(dn_m) > _ANGLE)
    ts, pts, pair = [], [], []
    # corners against faces, only where the face meets the motion head-on
    r = np.flatnonzero(into_f)
    zero = np.zeros(len(r))
    for k in range(3):     # moving corner k against the fixed face
        t = vertex_face_contact(m_world[r, k], f_world[r], d, zero, h)
        ts.append(t), pts.append(m_world[r, k] + np.minimum(t, h)[:, None] * d), pair.append(r)
    r = np.flatnonzero(into_m)
    zero = np.zeros(len(r))
    for k in range(3):     # fixed corner k against the moving face (moving towards it)
        t = vertex_face_contact(f_world[r, k], m_world[r], -d, zero, h)
        ts.append(t), pts.append(f_world[r, k]), pair.append(r)
    # edges: 3 x 3 per pair, only pairs forming a face of the Minkowski difference
    rows = np.repeat(np.arange(n), 9)
    ii = np.tile(np.repeat(np.arange(3), 3), n)
    jj = np.tile(np.tile(np.arange(3), 3), n)
    a1n = m_n[rows]
    a2n = np.einsum("nij,nj->ni", placed.rot[m_part[rows]], parts.edge_normals[m_tri[rows], ii]) - a1n
    b1n = f_n[rows]
    b2n = np.einsum("nij,nj->ni", placed.rot[f_part[rows]], parts.edge_normals[f_tri[rows], jj]) - b1n
    keep = _minkowski_face(a1n, a2n, -b1n, -b2n)
    # open edges (one face) and open meshes: no arc to test, keep them
    keep |= (np.abs(a2n).sum(axis=1) == 0) | (np.abs(b2n).sum(axis=1) == 0)
    keep |= ~(f_closed[rows] & m_closed[rows])
    rows, ii, jj = rows[keep], ii[keep], jj[keep]
    a0, a1 = m_world[rows, ii], m_world[rows, (ii + 1) % 3]
    b0, b1 = f_world[rows, jj], f_world[rows, (jj + 1) % 3]
    t, p = edge_edge_contact(a0, a1, b0, b1, d, h)
    m = np.cross(a1 - a0, b1 - b0)
    pn = np.einsum("nij,nj->ni", placed.rot[f_part[rows]], parts.edge_normals[f_tri[rows], jj])
    side = np.sign(np.einsum("ni,ni->n", m, pn))
    mm = np.linalg.norm(m, axis=1)
    approach = side * (m @ d)
    closed_e = f_closed[rows] & m_closed[rows]
    ok = np.where(closed_e, (side != 0) & (approach < -_ANGLE * mm), np.abs(m @ d) > _ANGLE * mm)
    ts.append(np.where(ok, t, np.inf)), pts.append(p), pair.append(rows)
    t_all = np.concatenate(ts)
    p_all = np.concatenate(pts)
    pr = np.concatenate(pair)
    fin = np.isfinite(t_all)
    return t_all[fin], p_all[fin], pr[fin]


def _minkowski_face(a: np.ndarray, b: np.ndarray, c: np.ndarray, d: np.ndarray) -> np.ndarray:
    """(n,) bool: the Gauss arcs (a, b) and (c, d) of two edges cross (Gregorius 2013).

    a, b: normals of the faces on the moving part's edge; c, d: the negated
    normals on the fixed part's edge. Only such edge pairs can meet first
    along any direction: an edge-edge contact's normal lies on both arcs.
    Arcs that only touch at an end point count as crossing."""
    bxa = np.cross(b, a)
    dxc = np.cross(d, c)
    cba = np.einsum("ni,ni->n", c, bxa)
    dba = np.einsum("ni,ni->n", d, bxa)
    adc = np.einsum("ni,ni->n", a, dxc)
    bdc = np.einsum("ni,ni->n", b, dxc)
    # closed comparisons: arcs meeting at an end (parallel faces, face-face
    # contact along an edge) count, so no first contact is lost
    tol = 1e-12
    return (cba * dba <= tol) & (adc * bdc <= tol) & (cba * bdc >= -tol)


def _verify(parts: PartSet, placed: Placement, moving_parts: np.ndarray, d: np.ndarray, m_world: np.ndarray, f_world: np.ndarray,
            f_part: np.ndarray, m_part: np.ndarray, t: np.ndarray, p: np.ndarray, pr: np.ndarray,
            step: float, t_best: np.ndarray, where: np.ndarray, by: np.ndarray) -> None:
    """Keep, per fixed part, the first candidate contact after which the parts overlap.

    A candidate at travel t is confirmed when the surfaces cross properly at
    t + ``step``; rounds walk each part's candidates in travel order (all
    parts at once per round), skipping candidates within ``step`` of one
    already refuted. Touching without overlap (sliding, grazing) never
    confirms."""
    part = f_part[pr]
    order = np.lexsort((t, part))
    t, p, pr, part = t[order], p[order], pr[order], part[order]
    pair_order = np.argsort(f_part, kind="stable")
    pair_part = f_part[pair_order]
    floor = np.full(len(parts.names), -np.inf)
    for _ in range(_ROUNDS):
        live = (t > floor[part]) & ~np.isfinite(t_best[part])
        if not live.any():
            return
        idx = np.flatnonzero(live)
        first = idx[np.r_[True, part[idx][1:] != part[idx][:-1]]]
        fp, ft = part[first], t[first]
        travel = np.full(len(parts.names), np.nan)
        travel[fp] = ft + step
        lo = np.searchsorted(pair_part, fp)
        hi = np.searchsorted(pair_part, fp, side="right")
        cnt = hi - lo
        rows = pair_order[ranges(lo, cnt)]
        shifted = m_world[rows] + (travel[f_part[rows]])[:, None, None] * d
        crossing = triangles_cross(shifted, f_world[rows], parts.touch(m_part[rows], f_part[rows]))
        ok = np.zeros(len(parts.names), bool)
        ok[f_part[rows][crossing]] = True
        q = fp[~ok[fp]]     # coincident faces never cross: probes decide
        if len(q):
            qq, mm = np.repeat(q, len(moving_parts)), np.tile(moving_parts, len(q))
            shift = travel[qq][:, None] * d
            n = len(qq)
            deep = probes_inside_batch(parts, placed, np.concatenate([mm, qq]), np.concatenate([qq, mm]),
                                       np.concatenate([shift, -shift]))
            ok[qq[np.isfinite(deep[:n]) | np.isfinite(deep[n:])]] = True
        good = first[ok[fp]]
        t_best[part[good]] = t[good]
        where[part[good]] = p[good]
        by[part[good]] = m_part[pr[good]]
        floor[fp] = ft + 0.5 * step
    # candidates left unverified after the rounds: report the earliest, conservatively
    rest = np.flatnonzero((t > floor[part]) & ~np.isfinite(t_best[part]))
    if len(rest):
        first = rest[np.r_[True, part[rest][1:] != part[rest][:-1]]]
        t_best[part[first]] = t[first]
        where[part[first]] = p[first]
        by[part[first]] = m_part[pr[first]]


def _step(parts: PartSet, mv: np.ndarray, step: float | None, m_world: np.ndarray) -> float:
    """The verification step: given, or STEP of the moving size, and well above rounding."""
    size = float(np.linalg.norm(parts.hi[mv].max(axis=0) - parts.lo[mv].min(axis=0)))
    coords = float(np.abs(m_world).max()) if len(m_world) else 0.0
    base = STEP * size if step is None else step
    return max(base, 1e3 * EPS * coords)


def _planes(parts: PartSet, placed: Placement, d: np.ndarray, h: float, mv: np.ndarray,
            stat: np.ndarray, t_best: np.ndarray, where: np.ndarray, by: np.ndarray,
            over: np.ndarray) -> None:
    """Moving corners against infinite planes (solid below local z = 0)."""
    planes = np.flatnonzero(stat & parts.plane)
    if not len(planes):
        return
    sel = np.isin(parts.vert_part, mv)
    vp = parts.vert_part[sel]
    vw = placed.world(vp, parts.vertices[sel])
    for p in planes:     # a handful of planes per scene at most
        nrm = placed.rot[p][:, 2]
        z = (vw - placed.pos[p]) @ nrm
        if np.any(z < -TOUCH * float(parts.size[mv].max())):
            over[p] = True
            continue
        dn = float(nrm @ d)
        if dn >= -_ANGLE:
            continue
        t = np.maximum(z, 0.0) / -dn
        k = int(np.argmin(t))
        if t[k] <= h * (1 + EPS) and t[k] < t_best[p]:
            t_best[p] = t[k]
            where[p] = vw[k] + t[k] * d
            by[p] = vp[k]


def _contained(parts: PartSet, placed: Placement, mv: np.ndarray, cand: np.ndarray) -> np.ndarray:
    """(P,) bool: candidates holding a moving part's probe, or holding a probe inside a moving part."""
    out = np.zeros(len(parts.names), bool)
    c, m = np.repeat(cand, len(mv)), np.tile(mv, len(cand))
    # a probe lies in its part's box grown by PROBE_DEPTH of the size and counts
    # only inside the other part's box: pairs whose world boxes (so grown) miss
    # each other hold none
    g = 2 * PROBE_DEPTH * np.maximum(parts.size[c], parts.size[m])
    near = np.all((placed.lo[c] - g[:, None] <= placed.hi[m]) & (placed.lo[m] - g[:, None] <= placed.hi[c]), axis=1)
    c, m = c[near], m[near]
    n = len(c)
    if n:
        deep = probes_inside_batch(parts, placed, np.concatenate([m, c]), np.concatenate([c, m]))
        out[c[np.isfinite(deep[:n]) | np.isfinite(deep[n:])]] = True
    return out


def probes_inside_batch(parts: PartSet, placed: Placement, a: np.ndarray, b: np.ndarray,
                        shift: np.ndarray | None = None) -> np.ndarray:
    """:func:`probes_inside` for many pairs at once: (n,), +inf where it gives None.

    ``a``, ``b``: (n,) parts; ``shift``: (n, 3) translations of ``a``. All
    probes of all pairs are placed in one array (with their pair's row),
    transformed in one batched operation, and measured with one call per
    primitive type and per distinct mesh of ``b``."""
    a = np.asarray(a, np.int64)
    b = np.asarray(b, np.int64)
    out = np.full(len(a), np.inf)
    rows = np.flatnonzero(parts.closed[b] & ~parts.plane[a])
    if not len(rows):
        return out
    ps = parts.probe_start
    first = ps[a[rows]]
    cnt = ps[a[rows] + 1] - first
    row = np.repeat(rows, cnt)                            # pair row of each probe
    idx = ranges(first, cnt)
    # only a's probes inside b's box as a's frame sees it (the box's own box
    # there, a little grown) can be inside b: a large mesh beside a small
    # part has most of its probes left out before any is moved
    box = np.flatnonzero(~parts.plane[b[rows]])
    if len(box):
        ra, rb = placed.rot[a[rows[box]]], placed.rot[b[rows[box]]]
        gap = placed.pos[b[rows[box]]] - placed.pos[a[rows[box]]]
        if shift is not None:
            gap = gap - np.asarray(shift, float)[rows[box]]
        lo, hi = transformed_aabb(parts.lo[b[rows[box]]], parts.hi[b[rows[box]]], np.einsum("nji,njk->nik", ra, rb),
                                  np.einsum("nji,nj->ni", ra, gap))
        grow = 1e-9 * (1.0 + np.abs(lo).max(axis=1) + np.abs(hi).max(axis=1))
        row_lo = np.full((len(a), 3), -np.inf)
        row_hi = np.full((len(a), 3), np.inf)
        row_lo[rows[box]], row_hi[rows[box]] = lo - grow[:, None], hi + grow[:, None]
        local = parts.probes[idx]
        near = all_columns((local >= row_lo[row]) & (local <= row_hi[row]))
        row, idx = row[near], idx[near]
        if not len(row):
            return out
    pa, pb = a[row], b[row]
    world = placed.world(pa, parts.probes[idx][:, None, :])
    if shift is not None:
        world = world + np.asarray(shift, float)[row][:, None, :]
    pts = placed.local(pb, world)[:, 0]
    inbox = all_columns((pts >= parts.lo[pb]) & (pts <= parts.hi[pb])) | parts.plane[pb]
    row, pb, pts = row[inbox], pb[inbox], pts[inbox]
    if not len(row):
        return out
    key, kinds, size = parts.sd_groups
    kb = key[pb]
    sd = np.empty(len(row))
    for k in np.unique(kb):     # one call per primitive type or distinct mesh
        sel = np.flatnonzero(kb == k)
        stype, shape = kinds[k]
        if shape is not None:
            sd[sel] = signed_distance(shape, pts[sel])[0]
        else:
            sd[sel] = signed_distance_value_batch(stype, size[pb[sel]], pts[sel])
    start = np.flatnonzero(np.r_[True, row[1:] != row[:-1]])   # rows are sorted
    worst = np.minimum.reduceat(sd, start)
    r = row[start]
    out[r] = np.where(worst < -parts.touch(a[r], b[r]), worst, np.inf)
    return out


def probes_inside(parts: PartSet, placed: Placement, a: int, b: int,
                  shift: np.ndarray | None = None) -> float | None:
    """Deepest signed distance (< 0) of part ``a``'s probes inside part ``b``, else None.

    ``shift`` (3,) translates part ``a`` in the world first.
    Only probes inside ``b``'s box are measured; an open ``b`` has no inside."""
    if not parts.closed[b] or parts.plane[a]:
        return None
    sel = parts.probe_part == a
    world = placed.world(np.full(1, a), parts.probes[sel][None])
    if shift is not None:
        world = world + shift
    pts = placed.local(np.full(1, b), world)[0]
    tol = float(parts.touch(np.array([a]), np.array([b]))[0])
    if not parts.plane[b]:
        inbox = all_columns((pts >= parts.lo[b]) & (pts <= parts.hi[b]))
        pts = pts[inbox]
    if not len(pts):
        return None
    sd, _ = signed_distance(parts.shapes[b], pts)
    worst = float(sd.min())
    return worst if worst < -tol else None
