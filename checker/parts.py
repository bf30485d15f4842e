"""Part-part and keep-out interference between rigid parts (the steel-structure and lightweight-CAD papers).

:func:`check_parts` finds every pair of parts that overlaps (hard) or comes
within the clearance (soft) for one set of poses; :class:`PartChecker` runs it
step after step, checking pairs on one rigid body once (they cannot change)
and replaying that answer at every later step. ``assemblies=False`` pairs the
part boxes by one sort and sweep instead, with the same records (to compare;
``benchmarks/bench_parts.py`` times both).

Layered filtering, as in the lightweight-CAD paper: assembly boxes grown by the clearance (the
parts' boxes are paired by descending the assembly tree, so two assemblies
whose boxes do not overlap contribute no pairs; with a ``focus`` assembly,
the others are first pruned against the focus's box), world boxes of parts,
the 15-axis test of their oriented boxes grown by the clearance, the triangle trees
(each part's tree queried with the other's box, then each candidate triangle
queried against the other part's tree), and only then exact triangle tests.

Two primitives (box, sphere, capsule, cylinder, ellipsoid) are measured on
their true shapes by :func:`cablecheck.checker.convex.convex_pairs` (exact, or a signed
distance never above the true one); only two boxes that are apart go on to
their (exact) triangles. Every other pair (a mesh on either side), per pair:

- overlap, hard, when any of these is found (each a certificate, never a
  guess): surfaces crossing properly (:func:`cablecheck.checker.tritri.triangles_cross`,
  whether or not any vertex lies inside: a pin through a plate, a bar through
  a bracket's foot); a containment probe of one part strictly inside the
  other (a part inside another, coincident parts; 002's containment); a point
  of a mesh's triangles more than the touching tolerance inside a curved
  primitive's true shape. The reported ``min_distance`` is minus a lower
  bound on the penetration depth (no translation shorter than it separates
  the parts): the deepest point of one part found inside the other, among
  the probes, the midpoints of the runs of edges through the other part
  (edges cut at their piercings of its faces, :func:`_edge_runs`: the
  steel-structure paper's outline edges against faces) and the deepest
  point of a mesh's triangles in a curved primitive; at least the touching
  tolerance (a crossing is hard however shallow the points found);
- else the least distance: between triangles (exact; meshes and boxes have
  no tessellation error), or for a mesh beside a curved primitive from the
  mesh's triangles to the primitive's true shape (:func:`_true_surface`:
  per triangle its edges' exact segment distances and the support point of
  the primitive towards its plane, so exact), soft below the clearance. So a
  curved primitive near a mesh is hard only where a point of the mesh lies
  inside it, and never clear while one does;
- touching (shared faces, shared edges, a corner on a face, parts meshed
  flush against each other, within the touching tolerance) is contact, not
  interference: mating parts of an assembly touch by design, so no record.

Infinite planes are tested against the other part's lowest point along
their normal: a primitive's support point (exact), a mesh's lowest vertex
(exact). A pair involving a keep-out zone is of type ``keepout``
with ``a`` the entering part and ``b`` the zone (two zones: in input order);
other pairs are ``part-part`` with ``a`` before ``b`` in input order. ``where``
is the deepest edge run's midpoint, the crossing, the deepest point of a
mesh in a curved primitive or the midpoint of the closest points, world
coordinates; ``s`` is 0 (parts have no arc length).

Not here: cables (:mod:`cablecheck.checker.interference`), time and events.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from cablecheck.checker.arrays import all_columns, ranges
from cablecheck.checker.bvh import aabb_pairs, assembly_pairs, obb_overlap, prefix_hits, transformed_aabb
from cablecheck.checker.closest import cross, row_norm
from cablecheck.checker.convex import CONVEX, convex_pairs, support
from cablecheck.checker.hullbound import hull_separations
from cablecheck.checker.partset import PartSet, Placement
from cablecheck.checker.records import Interference, PairType, severity_of
from cablecheck.checker.shapes import segment_signed_distance_batch
from cablecheck.checker.sweep import probes_inside_batch
from cablecheck.checker.tritri import edge_piercings, triangle_distance, triangles_cross


def candidate_pairs(parts: PartSet, placed: Placement, clearance: float,
                    focus: np.ndarray | None = None, pair_mask=None,
                    assemblies: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """Pairs (i < j, sorted) of non-plane parts whose boxes come within ``clearance``.

    With ``assemblies``, the part boxes are paired through the assembly
    boxes (:func:`cablecheck.checker.bvh.assembly_pairs`: assemblies whose boxes, grown
    by the clearance, do not overlap contribute no pairs); without, by one
    sort and sweep over all parts. Same pairs either way. With ``focus``
    ((P,) bool), only pairs of one focus part and one other, after pruning the
    others by assembly boxes against the focus's box. ``pair_mask`` (see
    :func:`check_parts`) is applied before the oriented-box test."""
    fin = ~parts.plane
    keep = fin
    empty = np.zeros(0, np.int64), np.zeros(0, np.int64)
    if focus is not None:
        focus = np.asarray(focus, bool)
        f = focus & fin
        if not f.any():
            return empty
        lo = placed.lo[f].min(axis=0) - clearance
        hi = placed.hi[f].max(axis=0) + clearance
        asm_hit = all_columns((placed.asm_lo <= hi) & (lo <= placed.asm_hi))
        keep = fin & (focus | prefix_hits(parts.assemblies, asm_hit))
    if assemblies:
        i, j = assembly_pairs(parts.assemblies, placed.lo, placed.hi, placed.asm_lo, placed.asm_hi,
                              keep, 0.5 * clearance)
    else:
        idx = np.flatnonzero(keep)
        a, b = aabb_pairs(placed.lo[idx], placed.hi[idx], 0.5 * clearance)
        i, j = idx[a], idx[b]
    i, j = _sorted(np.minimum(i, j), np.maximum(i, j))
    if focus is not None:
        one = focus[i] != focus[j]
        i, j = i[one], j[one]
    if pair_mask is not None and len(i):
        ok = pair_mask(i, j)
        i, j = i[ok], j[ok]
    return _boxes_overlap(parts, placed, clearance, i, j)


def candidate_pairs_of(parts: PartSet, placed: Placement, clearance: float, focus: np.ndarray | None,
                       i: np.ndarray, j: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The given pairs (i < j) of non-plane parts whose oriented boxes, grown
    by the clearance, overlap (sorted; with ``focus``, one focus part each)."""
    i, j = np.asarray(i, np.int64), np.asarray(j, np.int64)
    keep = ~parts.plane[i] & ~parts.plane[j]
    if focus is not None:
        focus = np.asarray(focus, bool)
        keep &= focus[i] != focus[j]
    i, j = _sorted(i[keep], j[keep])
    return _boxes_overlap(parts, placed, clearance, i, j)


def _sorted(i: np.ndarray, j: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Pairs in (i, j) order."""
    order = np.lexsort((j, i))
    return i[order], j[order]


def _boxes_overlap(parts: PartSet, placed: Placement, clearance: float,
                   i: np.ndarray, j: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The pairs whose oriented boxes, grown by half the clearance each, overlap."""
    if len(i):
        half = parts.half() + 0.5 * clearance
        ok = obb_overlap(placed.centre[i], placed.rot[i], half[i], placed.centre[j], placed.rot[j], half[j])
        i, j = i[ok], j[ok]
    return i, j


def _world_triangles(parts: PartSet, placed: Placement, part: np.ndarray, tri: np.ndarray) -> np.ndarray:
    """Triangles ``tri`` (n,) of parts ``part`` (n,) in the world, (n, 3, 3):
    each distinct triangle transformed once (a triangle belongs to one part),
    however many pairs it is in."""
    if len(tri) < 64:
        return placed.world(part, parts.tris[tri])
    u, first, inv = np.unique(tri, return_index=True, return_inverse=True)
    return placed.world(part[first], parts.tris[u])[inv.ravel()]


def _triangle_pairs(parts: PartSet, placed: Placement, i: np.ndarray, j: np.ndarray,
                    clearance: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Triangle pairs (tri of i, tri of j, pair row) whose boxes come within ``clearance`` (scalar or (n,))."""
    clearance = np.broadcast_to(np.asarray(clearance, float), (len(i),))[:, None]
    g = 0.5 * clearance
    # j's grown box in i's frame
    rel = np.einsum("nji,njk->nik", placed.rot[i], placed.rot[j])
    shift = np.einsum("nji,nj->ni", placed.rot[i], placed.pos[j] - placed.pos[i])
    q_lo, q_hi = transformed_aabb(parts.lo[j] - g, parts.hi[j] + g, rel, shift)
    row, ti = parts.forest.query(i, q_lo - g, q_hi + g)
    # each candidate triangle of i, grown, in j's frame
    tw = _world_triangles(parts, placed, i[row], ti)
    # corner by corner (numpy reduces a 3-long axis slowly; min and max are exact)
    t_lo = np.minimum(np.minimum(tw[:, 0], tw[:, 1]), tw[:, 2]) - clearance[row]
    t_hi = np.maximum(np.maximum(tw[:, 0], tw[:, 1]), tw[:, 2]) + clearance[row]
    # a world AABB in j's frame: transform its centre and half extents
    c = 0.5 * (t_lo + t_hi)
    h = 0.5 * (t_hi - t_lo)
    rj = placed.rot[j[row]]
    cl = placed.local(j[row], c[:, None, :])[:, 0]
    hl = np.einsum("nji,nj->ni", np.abs(rj), h)
    r2, tj = parts.forest.query(j[row], cl - hl, cl + hl)
    return ti[r2], tj, row[r2]


TILE_TRIANGLES = 200_000
"""Triangles :meth:`PartChecker.check_pairs_many` lays out at most in one
set: the parts of its pairs once per state, so a robot's torso mesh of
9,159 triangles at a batch's 116 states was 1.06 million triangles, their
normals and probes built for one call (0.64 s of the Baxter's 2.2 s of
checks); a larger batch is checked that many states a call."""

FIRST_PASS = 4
"""Triangle pairs of a part pair measured first (those whose boxes lie
nearest), their least distance bounding the pair's from above."""


def _least_distances(a: np.ndarray, b: np.ndarray, row: np.ndarray,
                     err: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`triangle_distance` of triangle pairs ``a``, ``b`` (n, 3, 3) of
    part pairs ``row``, where it can matter: each row's ``FIRST_PASS`` pairs
    whose boxes lie nearest are measured first, and the least of those
    bounds the row's least distance from above; a pair whose boxes lie
    farther than that plus the row's tessellation error ``err`` (n,) (a
    curved primitive's true surface may lie that much nearer) can hold
    neither that least nor a triangle the curved check needs, and answers
    inf (its closest points 0). Every row's least distance, its pair and
    closest points are those of measuring every pair, to the bit: a mesh
    resting against a box within the clearance had all its triangles within
    the clearance of the box's measured at every state (the zoo's Spot arm,
    a tool on its forearm: 1.9 of its 6.5 s)."""
    n = len(row)
    d = np.full(n, np.inf)
    p, q = np.zeros((n, 3)), np.zeros((n, 3))
    if n == 0:
        return d, p, q
    gap = np.maximum(np.maximum(a.min(axis=1) - b.max(axis=1), b.min(axis=1) - a.max(axis=1)), 0.0)
    gap = row_norm(gap)                                  # the boxes' distance: no more than the triangles'
    # and one triangle wholly on one side of the other's plane is at least that far from it
    gap = np.maximum(gap, np.maximum(_plane_separation(a, b), _plane_separation(b, a)))
    o = np.lexsort((gap, row))
    head = np.r_[0, np.flatnonzero(row[o][1:] != row[o][:-1]) + 1]
    rank = np.arange(n) - np.repeat(head, np.diff(np.r_[head, n]))
    first = o[rank < FIRST_PASS]
    d[first], p[first], q[first] = triangle_distance(a[first], b[first])
    upper = np.full(int(row.max()) + 1, np.inf)
    np.minimum.at(upper, row[first], d[first])
    # rounding: the boxes' distance and the triangles' each err by a few ulp of the coordinates
    slack = 1e-9 * (1.0 + np.abs(a).max(axis=(1, 2)) + np.abs(b).max(axis=(1, 2)))
    rest = np.ones(n, bool)
    rest[first] = False
    rest &= gap <= upper[row] + err + slack
    if rest.any():
        d[rest], p[rest], q[rest] = triangle_distance(a[rest], b[rest])
    return d, p, q


def _plane_separation(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(n,) how far triangles ``b`` (n, 3, 3) lie wholly on one side of the
    planes of triangles ``a``: the least distance of their corners to the
    plane where all three are on one side, else 0 (and 0 for a degenerate
    ``a``): no more than the triangles' distance."""
    n = cross(a[:, 1] - a[:, 0], a[:, 2] - a[:, 0])
    length = row_norm(n)
    h = np.einsum("ikj,ij->ik", b - a[:, None, 0], n) / np.where(length > 0.0, length, 1.0)[:, None]
    one_side = (h.min(axis=1) > 0.0) | (h.max(axis=1) < 0.0)
    return np.where(one_side & (length > 0.0), np.abs(h).min(axis=1), 0.0)


def _first_per_row(row: np.ndarray, value: np.ndarray) -> np.ndarray:
    """Indices of the least ``value`` of each distinct ``row`` (rows ascending)."""
    if not len(row):
        return np.zeros(0, np.int64)
    order = np.lexsort((value, row))
    return order[np.r_[True, row[order][1:] != row[order][:-1]]]


def _edge_runs(parts: PartSet, placed: Placement, n: int, i: np.ndarray, j: np.ndarray, row: np.ndarray,
               ti: np.ndarray, tj: np.ndarray, a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Points inside the other part along edges that pierce it, per pair row.

    For the crossing triangle pairs given (triangle ``ti`` of part
    ``i[row]`` against ``tj`` of ``j[row]``, world corners ``a``, ``b``),
    every edge of either triangle is cut at all its piercings of the other
    part's triangles (:func:`cablecheck.checker.tritri.edge_piercings`); the midpoint of
    each run between two consecutive piercings is measured against the other
    part's true shape. An edge whose ends are outside the other part enters
    and leaves it, so a crossing with no corner inside has such a run
    inside. A point of one part at depth ``t`` inside the other means no
    translation shorter than ``t`` separates them: ``-sd`` is a lower bound
    on the penetration depth.

    Returns:
        deep: (n,) the least signed distance of those midpoints per pair
            row (inf where none is inside a closed part).
        at: (n, 3) that midpoint (world).
    """
    deep = np.full(n, np.inf)
    at = np.zeros((n, 3))
    m = len(row)
    if not m:
        return deep, at
    src, dst = np.concatenate([a, b]), np.concatenate([b, a])
    side = np.repeat(np.array([0, 1]), m)               # 0: an edge of i's triangle, 1: of j's
    r2, tri = np.concatenate([row, row]), np.concatenate([ti, tj])
    pair, edge, s = edge_piercings(src, dst)
    if not len(pair):
        return deep, at
    # the piercings of one edge (row, side, triangle, edge) in order along it
    cols = (r2[pair], side[pair], tri[pair], edge)
    order = np.lexsort((s,) + cols[::-1])
    same = np.ones(len(order) - 1, bool)
    for c in cols:
        cs = c[order]
        same &= cs[1:] == cs[:-1]
    first, second = order[:-1][same], order[1:][same]
    if not len(first):
        return deep, at
    pm, em = pair[first], edge[first]
    mid = 0.5 * (s[first] + s[second])
    p0 = src[pm, em]
    pts = p0 + mid[:, None] * (src[pm, (em + 1) % 3] - p0)
    rr = r2[pm]
    other = np.where(side[pm] == 0, j[rr], i[rr])
    sd, _ = parts.signed_distance(other, placed.local(other, pts[:, None, :])[:, 0])
    sd = np.where(parts.closed[other], sd, np.inf)
    best = _first_per_row(rr, sd)
    deep[rr[best]] = sd[best]
    at[rr[best]] = pts[best]
    return deep, at


def _in_triangle(p: np.ndarray, a: np.ndarray, b: np.ndarray, c: np.ndarray, nrm: np.ndarray) -> np.ndarray:
    """(m,) bool: points p (m, 3) of the planes of triangles a b c (unnormalised normals ``nrm``) lie in them (closed)."""
    out = np.ones(len(p), bool)
    for u, v in ((a, b), (b, c), (c, a)):
        out &= np.einsum("mj,mj->m", np.cross(v - u, p - u), nrm) >= 0.0
    return out


def _true_surface(parts: PartSet, placed: Placement, prim: np.ndarray,
                  tri: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Least signed distance of each triangle (a mesh's) to a curved primitive's true shape.

    The signed distance to a convex solid S is convex, so over a triangle T
    its least value is reached on an edge of T, or inside T where the plane
    P of T is nearest S (or cuts it):

    - edges: the least signed distance along each edge, exact per primitive
      (:func:`cablecheck.checker.shapes.segment_signed_distance_batch`);
    - S wholly on one side of P: the distance from P to S is the height of
      S's support point towards P (:func:`cablecheck.checker.convex.support`); when its
      foot on P lies in T, that is T's distance (if not, a point of P nearest
      S in T would make a segment of such points reaching T's edges, which
      the edges then give);
    - S cut by P: the segment between S's lowest and highest support points
      along P's normal lies in S and meets P at a point z of S; if S's
      section by P reaches T's inside without touching its edges it lies
      wholly inside T, so z is in T: its signed distance (<= 0) is then T's
      overlap (a point of T in S, so minus it is a lower bound on the
      penetration).

    Args:
        prim: (m,) the primitive part of each row (box, sphere, capsule,
            cylinder, ellipsoid).
        tri: (m, 3, 3) triangles (world).

    Returns:
        value: (m,) the least signed distance (exact to the primitives'
            segment distances, about 1e-13 of an edge; an overlap through
            T's inside: the signed distance of a point of T in S, <= 0).
        x: (m, 3) the point of T where it is reached (world).
        q: (m, 3) the point of S's surface nearest x (world).
    """
    m = len(prim)
    t = placed.local(prim, tri)
    kind, size = parts.convex_kind[prim], parts.sd_groups[2][prim]
    # the three edges, one call per primitive type
    a, b = t.reshape(-1, 3), t[:, [1, 2, 0]].reshape(-1, 3)
    k3, s3 = np.repeat(kind, 3), np.repeat(size, 3, axis=0)
    ev, et = np.empty(3 * m), np.empty(3 * m)
    for k in np.unique(kind):
        sel = np.flatnonzero(k3 == k)
        ev[sel], et[sel] = segment_signed_distance_batch(CONVEX[k], s3[sel], a[sel], b[sel])
    best = np.argmin(ev.reshape(m, 3), axis=1) + 3 * np.arange(m)
    value = ev[best]
    x = a[best] + et[best, None] * (b[best] - a[best])
    # the face: S's support points along the plane's normal
    nrm = np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])
    ln = row_norm(nrm)
    flat = ln > 0
    u = nrm / np.where(flat, ln, 1.0)[:, None]
    u = np.where(flat[:, None], u, [0.0, 0.0, 1.0])
    h = np.einsum("mj,mj->m", u, t[:, 0])
    _, low = support(kind, size, -u)
    _, high = support(kind, size, u)
    lo_h = np.einsum("mj,mj->m", u, low) - h
    hi_h = np.einsum("mj,mj->m", u, high) - h
    front, behind = lo_h >= 0.0, hi_h <= 0.0
    cut = ~front & ~behind
    frac = np.where(cut, -lo_h / np.where(cut, hi_h - lo_h, 1.0), 0.0)
    z = low + frac[:, None] * (high - low)
    pick = np.where(front[:, None], low, np.where(behind[:, None], high, z))
    foot = pick - (np.einsum("mj,mj->m", u, pick) - h)[:, None] * u
    face = flat & _in_triangle(foot, t[:, 0], t[:, 1], t[:, 2], nrm)
    face_val = np.where(front, lo_h, -hi_h)
    rows = np.flatnonzero(face & cut)
    if len(rows):
        face_val[rows] = parts.signed_distance(prim[rows], foot[rows])[0]
    lower = face & (face_val < value)
    value = np.where(lower, face_val, value)
    x = np.where(lower[:, None], foot, x)
    _, q = parts.signed_distance(prim, x)
    world = placed.world(prim, np.stack([x, q], axis=1))
    return value, world[:, 0], world[:, 1]


def _triangle_values(parts: PartSet, placed: Placement, i: np.ndarray, j: np.ndarray,
                     clearance: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Signed values (n,), places (n, 3) and hard flags (n,) of part pairs
    with a mesh (or two boxes apart), from their triangles and probes.

    Hard (an overlap found): surfaces crossing, a probe strictly inside, a
    point of a mesh's triangles more than the touching tolerance inside a
    curved primitive's true shape. The value is then minus a lower bound on
    the penetration depth, the deepest point of one part found inside the
    other (probes, runs of edges through the other, the mesh's triangles in a
    curved primitive), but at least the touching tolerance. Else the least
    distance: between triangles (exact for meshes and boxes), or to a curved
    primitive's true shape (:func:`_true_surface`; pairs whose tessellations
    are farther apart than the clearance and both errors keep that distance
    less the errors, a lower bound past the clearance). ``where``: the
    deepest point's run or the curved primitive's nearest point where one of
    those is the deepest found, else the crossing or the closest points."""
    n = len(i)
    dist = np.full(n, np.inf)
    where = np.zeros((n, 3))
    crossing = np.zeros(n, bool)
    touch = parts.touch(i, j)
    err = parts.error[i] + parts.error[j]
    run_deep, run_at = np.full(n, np.inf), np.zeros((n, 3))
    ti, tj, row = _triangle_pairs(parts, placed, i, j, clearance + err)
    d = np.zeros(0)
    p = q = np.zeros((0, 3))
    rest = np.zeros(0, bool)
    if len(row):
        a = _world_triangles(parts, placed, i[row], ti)
        b = _world_triangles(parts, placed, j[row], tj)
        cr = triangles_cross(a, b, touch[row])
        crossing[row[cr]] = True
        where[row[cr]] = 0.5 * (a[cr].mean(axis=1) + b[cr].mean(axis=1))
        run_deep, run_at = _edge_runs(parts, placed, n, i, j, row[cr], ti[cr], tj[cr], a[cr], b[cr])
        rest = ~cr & ~crossing[row]
        r = row[rest]
        d, p, q = _least_distances(a[rest], b[rest], r, err[r])
        first = _first_per_row(r, d)
        dist[r[first]] = d[first]
        where[r[first]] = 0.5 * (p[first] + q[first])
    # containment probes of every pair, both ways, in one batch
    deep = probes_inside_batch(parts, placed, np.concatenate([i, j]), np.concatenate([j, i]))
    deep = np.minimum(deep[:n], deep[n:])
    value = dist - err                      # curved rows far from the clearance keep this lower bound
    hard = np.isfinite(deep) | crossing
    # a mesh beside a curved primitive (not already found overlapping): its
    # triangles against the primitive's true shape
    curved = (err > 0) & ~hard & (value < clearance + touch)
    true_deep = np.full(n, np.inf)
    if curved.any() and rest.any():
        r = row[rest]
        use = curved[r]
        r, d = r[use], d[use]
        prim_i = parts.error[i[r]] > 0                   # the curved part is i (else j)
        mesh_tri = np.where(prim_i, tj[rest][use], ti[rest][use])
        # each mesh triangle once per pair, at its nearest tessellation triangle
        key = _first_per_row(r * len(parts.tris) + mesh_tri, d)
        r, d, mesh_tri, prim_i = r[key], d[key], mesh_tri[key], prim_i[key]
        # only triangles that can hold the pair's least true distance (the
        # tessellation lies inside the true shape, within ``err`` of it)
        need = d - err[r] <= dist[r]
        r, mesh_tri, prim_i = r[need], mesh_tri[need], prim_i[need]
        prim = np.where(prim_i, i[r], j[r])
        mesh = np.where(prim_i, j[r], i[r])
        v, x, xq = _true_surface(parts, placed, prim, _world_triangles(parts, placed, mesh, mesh_tri))
        best = _first_per_row(r, v)
        rb = r[best]
        true_deep[rb] = v[best]
        value[rb] = np.maximum(v[best], -touch[rb])
        where[rb] = 0.5 * (x[best] + xq[best])
        hard |= true_deep < -touch
    true_hard = np.where(true_deep < -touch, true_deep, np.inf)
    worst = np.minimum(np.minimum(deep, run_deep), true_hard)
    run_best = (run_deep <= deep) & (run_deep <= true_hard) & np.isfinite(run_deep)
    where = np.where(run_best[:, None], run_at, where)
    value = np.where(hard, -np.maximum(-np.minimum(worst, 0.0), touch), value)
    return value, where, hard


def check_parts(parts: PartSet, placed: Placement, clearance: float,
                focus: np.ndarray | None = None,
                pair_mask=None, assemblies: bool = True,
                pairs: tuple[np.ndarray, np.ndarray] | None = None) -> list[Interference]:
    """Interference between parts at one set of poses.

    Args:
        parts, placed: prepared parts and their poses.
        clearance: soft distance (same units), >= 0.
        focus: (P,) bool: check only these parts against the others.
        pair_mask: optional function (i, j) -> (n,) bool choosing which
            candidate pairs to test (e.g. only parts on different bodies).
        assemblies: prune by assembly boxes before part boxes (False: part
            boxes only; the records are the same, for comparison).
        pairs: (i, j) arrays, i < j: test these pairs alone (no box broad
            phase over all parts; ``pair_mask`` must not be given). Each
            pair's record is the one the check of all pairs gives it: the
            broad phase only drops pairs whose boxes are farther apart than
            the clearance, which have no record.
    """
    return [r for _, _, r in _check_indexed(parts, placed, clearance, focus, pair_mask, assemblies, pairs)]


def _check_indexed(parts: PartSet, placed: Placement, clearance: float, focus, pair_mask, assemblies: bool,
                   pairs) -> list[tuple[int, int, Interference]]:
    """:func:`check_parts`'s records with the two parts' indices each."""
    if pairs is not None:
        i, j = candidate_pairs_of(parts, placed, clearance, focus, *pairs)
        listed = np.zeros((len(parts.names),) * 2, bool)
        listed[pairs[0], pairs[1]] = listed[pairs[1], pairs[0]] = True
        pair_mask = lambda a, b: listed[a, b]    # noqa: E731  (the planes' pairs)
    else:
        i, j = candidate_pairs(parts, placed, clearance, focus, pair_mask, assemblies)
    out: list[tuple[int, int, Interference | None]] = []
    n = len(i)
    if n:
        value, where, hard = _measured(parts, placed, i, j, clearance)
        touch = parts.touch(i, j)
        for k in np.flatnonzero(hard | ((touch < value) & (value < clearance))):  # records only
            out.append((int(i[k]), int(j[k]), _record(parts, int(i[k]), int(j[k]), float(value[k]), where[k],
                                                      clearance)))
    out.extend(_plane_records(parts, placed, clearance, focus, pair_mask))
    return [x for x in out if x[2] is not None]


def pair_values(parts: PartSet, placed: Placement, i: np.ndarray, j: np.ndarray, reach: float,
                exact_below: float | None = None) -> np.ndarray:
    """Lower bounds (n,) on the distance between the shapes the part-part
    check measures of parts i and j (n,) at one placement: what the check's
    own measures give (two primitives: :func:`cablecheck.checker.convex.convex_pairs`;
    a mesh, or two boxes apart: :func:`_triangle_values`, triangles within
    ``reach`` of each other) less both tessellation errors, at most ``reach``
    where nothing comes within it; negative for an overlap; 0 for a pair with
    a plane (not measured here).

    With ``exact_below``: a pair with a mesh whose vertices' convex hulls
    are farther apart than that (:func:`cablecheck.checker.hullbound.hull_lower_bounds`,
    the hull holding the triangles) keeps the hulls' distance, a lower bound
    of its triangles', without measuring them; the others are measured.

    A pair's distance drops by at most how far one part moves relative to
    the other, so a pair whose bound exceeds the clearance by more than that
    move has no record (`cablecheck.run.stepcheck`: active part pairs between checks)."""
    return pair_values_axes(parts, placed, i, j, reach, exact_below)[0]


def pair_values_axes(parts: PartSet, placed: Placement, i: np.ndarray, j: np.ndarray, reach: float,
                     exact_below: float | None = None) -> tuple[np.ndarray, np.ndarray]:
    """:func:`pair_values`, and (n, 3) for the pairs the convex hulls
    answered the world direction that separates them (from j's hull to i's;
    :func:`hull_separations_along` follows it), zero for the others."""
    i, j = np.asarray(i, np.int64), np.asarray(j, np.int64)
    out = np.zeros(len(i))                                   # a plane's pairs: not measured here
    axes = np.zeros((len(i), 3))
    rows = np.flatnonzero(~parts.plane[i] & ~parts.plane[j])
    if exact_below is not None and len(rows):
        kind = parts.convex_kind
        hulled = rows[(kind[i[rows]] < 0) | (kind[j[rows]] < 0)]
        if len(hulled):
            bound, u = _hull_values(parts, placed, i[hulled], j[hulled], reach)
            far = bound > exact_below
            out[hulled[far]] = np.minimum(bound[far], reach)
            axes[hulled[far]] = u[far]
            rows = np.setdiff1d(rows, hulled[far])
    if len(rows):
        value, _, hard = _measured(parts, placed, i[rows], j[rows], reach)
        out[rows] = np.where(hard, np.minimum(value, 0.0), np.minimum(value, reach))
    return out - parts.error[i] - parts.error[j], axes


def hull_separations_along(parts: PartSet, poses: np.ndarray, a: int, b: int, axis: np.ndarray,
                           at: np.ndarray) -> np.ndarray:
    """(S,) lower bounds on the distance between the triangles of parts a
    and b at poses (S, P, 4, 4), less both tessellation errors: their hulls'
    separation along ``axis`` (a world direction from b's hull to a's at
    poses ``at`` (P, 4, 4)), the axis carried along with a, and, apart,
    with b (the better of the two at each state). Whatever the direction,
    two solids' projections on it separated by ``g`` are at least ``g``
    apart: no bound on how far a part moved is needed, so two links beside a
    joint keep their separating plane however far their far ends swing."""
    poses = np.asarray(poses, float)
    ha, hb = parts.hull_points(a), parts.hull_points(b)
    ra, ta = poses[:, a, :3, :3], poses[:, a, :3, 3]
    rb, tb = poses[:, b, :3, :3], poses[:, b, :3, 3]
    best = np.full(len(poses), -np.inf)
    for r, start in ((ra, at[a, :3, :3]), (rb, at[b, :3, :3])):
        fixed = start.T @ np.asarray(axis, float)                      # the axis in that part's frame
        u = np.einsum("sij,j->si", r, fixed)                           # (S, 3) the axis carried along
        low_a = (np.einsum("si,sij,kj->sk", u, ra, ha)).min(axis=1) + np.einsum("si,si->s", u, ta)
        high_b = (np.einsum("si,sij,kj->sk", u, rb, hb)).max(axis=1) + np.einsum("si,si->s", u, tb)
        best = np.maximum(best, low_a - high_b)
    return best - parts.error[a] - parts.error[b]


HULL_TOLERANCE = 0.02
"""How near the hulls' distance (a share of the reach) their bound in
:func:`pair_values` is taken: a bound this much low restarts a pair's
condition that much sooner, no more."""


def _hull_values(parts: PartSet, placed: Placement, i: np.ndarray, j: np.ndarray,
                 reach: float) -> tuple[np.ndarray, np.ndarray]:
    """(n,) lower bounds on the distance between the triangles of parts i
    and j (n,): their convex hulls' (:meth:`PartSet.hull_points`, in the
    world), within ``HULL_TOLERANCE`` of ``reach`` of it; and the world
    directions (n, 3) that prove them."""

    def padded(part: np.ndarray) -> np.ndarray:
        hulls = [parts.hull_points(int(k)) for k in part.tolist()]      # the few active pairs' parts
        m = max(len(h) for h in hulls)
        return placed.world(part, np.stack([np.concatenate([h, np.repeat(h[-1:], m - len(h), axis=0)])
                                            for h in hulls]))

    return hull_separations(padded(i), padded(j), HULL_TOLERANCE * reach)


def _measured(parts: PartSet, placed: Placement, i: np.ndarray, j: np.ndarray,
              beyond: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Signed values (n,), places (n, 3) and hard flags (n,) of pairs of
    parts i and j (n,, no plane): two primitives on their true shapes
    (:mod:`cablecheck.checker.convex`), two boxes apart and meshes by their
    triangles (:func:`_triangle_values`); measured exactly up to ``beyond``
    (past it a lower bound may stand)."""
    n = len(i)
    value = np.full(n, np.inf)
    where = np.zeros((n, 3))
    kind = parts.convex_kind
    conv = np.flatnonzero((kind[i] >= 0) & (kind[j] >= 0))
    tri = np.ones(n, bool)
    if len(conv):
        size = parts.sd_groups[2]
        a, b = i[conv], j[conv]
        sd, w, _, apart = convex_pairs(kind[a], size[a], placed.rot[a], placed.pos[a],
                                       kind[b], size[b], placed.rot[b], placed.pos[b], beyond)
        value[conv], where[conv] = sd, w
        tri[conv[~apart]] = False
    hard = value < -parts.touch(i, j)
    rows = np.flatnonzero(tri)
    if len(rows):
        value[rows], where[rows], hard[rows] = _triangle_values(parts, placed, i[rows], j[rows], beyond)
    return value, where, hard


def _record(parts: PartSet, a: int, b: int, d: float, where: np.ndarray, clearance: float) -> Interference | None:
    sev = severity_of(d, clearance)
    if sev is None:
        return None
    if parts.keepout[a] or parts.keepout[b]:
        if parts.keepout[a] and not parts.keepout[b]:
            a, b = b, a
        kind = PairType.KEEPOUT
    else:
        kind = PairType.PART_PART
    return Interference(kind, parts.names[a], parts.names[b], float(d), sev, np.asarray(where, float).copy(), 0.0)


def _plane_records(parts: PartSet, placed: Placement, clearance: float, focus, pair_mask) -> list:
    planes = np.flatnonzero(parts.plane)
    out = []
    if not len(planes):
        return out
    with_verts = np.unique(parts.vert_part)
    for p in planes:     # a handful of planes per scene at most
        # the parts this plane is checked against, before touching their vertices
        q = with_verts
        if focus is not None:
            q = q[np.asarray(focus, bool)[q] != bool(focus[p])]
        if pair_mask is not None and len(q):
            q = q[np.asarray(pair_mask(np.minimum(p, q), np.maximum(p, q)), bool)]
        if not len(q):
            continue
        normal = placed.rot[p][:, 2]
        # primitives: their lowest point along the plane's normal is a support point (exact)
        qc = q[parts.convex_kind[q] >= 0]
        if len(qc):
            down = np.einsum("nji,j->ni", placed.rot[qc], -normal)
            _, sup = support(parts.convex_kind[qc], parts.sd_groups[2][qc], down)
            low = placed.world(qc, sup[:, None, :])[:, 0]
            zc = (low - placed.pos[p]) @ normal
            for part, zz, w, t in zip(qc.tolist(), zc.tolist(), low, parts.touch(qc, qc).tolist()):
                if abs(zz) > t:
                    a, b = min(p, part), max(p, part)
                    out.append((a, b, _record(parts, a, b, float(zz), w, clearance)))
        # meshes: their lowest vertex
        q = q[parts.convex_kind[q] < 0]
        if not len(q):
            continue
        sel = np.flatnonzero(np.isin(parts.vert_part, q))
        vp = parts.vert_part[sel]
        vw = placed.world(vp, parts.vertices[sel][:, None, :])[:, 0]
        z = (vw - placed.pos[p]) @ normal
        order = np.lexsort((z, vp))
        first = order[np.r_[True, vp[order][1:] != vp[order][:-1]]]
        lowest = vp[first]
        touch = parts.touch(lowest, lowest)
        for v, part, t in zip(first.tolist(), lowest.tolist(), touch.tolist()):
            if abs(z[v]) > t:
                a, b = min(p, part), max(p, part)
                out.append((a, b, _record(parts, a, b, float(z[v]), vw[v], clearance)))
    return out


class PartChecker:
    """Part-part checks step after step, reusing what cannot change.

    The first :meth:`check` tests every pair; pairs of parts on the same
    rigid body (``PartSet.groups``) are answered then and replayed at every
    later step without being tested again (their ``where`` follows the body). The prepared parts (trees,
    probes) are reused throughout.
    """

    def __init__(self, parts: PartSet, clearance: float, focus: np.ndarray | None = None,
                 skip: np.ndarray | None = None, assemblies: bool = True):
        """``skip``: (P, P) bool, pairs never checked (e.g. parts of a parent
        and a child body joined by a joint: MuJoCo skips those too, links of
        an arm overlap at their joints by design). ``assemblies``: see
        :func:`check_parts` (False only to compare)."""
        self.parts = parts
        self.assemblies = assemblies
        self.clearance = clearance
        self.focus = focus
        self._group = parts.group_index
        n = len(parts.names)
        self._skip = np.zeros((n, n), bool) if skip is None else np.asarray(skip, bool)
        self._static: tuple[list[Interference], np.ndarray, np.ndarray] | None = None
        self._tiled: dict[tuple, PartSet] = {}
        # the oriented-box test's centres and grown half extents, per part (see _boxes_overlap)
        flat = parts.plane[:, None]                                  # (planes: never boxed)
        self._mid = 0.5 * (np.where(flat, 0.0, parts.lo) + np.where(flat, 0.0, parts.hi))
        self._grown = parts.half() + 0.5 * clearance

    def check(self, poses: np.ndarray) -> list[Interference]:
        """Records for poses (P, 4, 4)."""
        placed = self.parts.place(poses)
        grp, skip = self._group, self._skip
        if self._static is None:
            found = check_parts(self.parts, placed, self.clearance, self.focus,
                                lambda i, j: (grp[i] == grp[j]) & ~skip[i, j], self.assemblies)
            # keep each place in part a's frame: the pair rides its body
            index = {n: k for k, n in enumerate(self.parts.names)}
            ka = np.array([index[r.a] for r in found], np.int64)
            wa = np.array([r.where for r in found], float).reshape(-1, 1, 3)
            self._static = (found, ka, placed.local(ka, wa) if len(found) else wa)
        moving = check_parts(self.parts, placed, self.clearance, self.focus,
                             lambda i, j: (grp[i] != grp[j]) & ~skip[i, j], self.assemblies)
        return self._replay(placed) + moving

    def check_pairs(self, poses: np.ndarray, i: np.ndarray, j: np.ndarray) -> list[Interference]:
        """The records of the moving pairs (i, j) (i < j, from
        :meth:`moving_pairs`) alone at poses (P, 4, 4): what :meth:`check`
        gives those pairs."""
        if not len(i):
            return []
        fast, si, sj = self._primitive_pairs_many(np.asarray(poses, float)[None], np.asarray(i, np.int64),
                                                  np.asarray(j, np.int64))
        found = fast[0]
        if len(si):
            found = found + _check_indexed(self.parts, self.parts.place(poses), self.clearance, self.focus, None,
                                           True, (si, sj))
        return [r for _, _, r in self._in_pair_order(found)]

    def check_pairs_many(self, poses: np.ndarray, i: np.ndarray, j: np.ndarray) -> list[list[Interference]]:
        """:meth:`check_pairs` at S states at once (poses (S, P, 4, 4)), to
        the bit: the pairs of two primitives at all the states in one call
        (`_primitive_pairs_many`), the others' parts laid out once per state
        (`_triangle_pairs_many`), so a batch of states costs about one call's
        numpy overhead, and two boxes apart (a hand's palm above its table)
        send only their own pair to the triangles."""
        n_s = len(poses)
        if not len(i) or not n_s:
            return [[] for _ in range(n_s)]
        # the pairs of two primitives at every state at once; the rest (a mesh, a plane, two boxes
        # apart at some state) by their triangles, laid out once per state for them alone
        fast, i, j = self._primitive_pairs_many(np.asarray(poses, float), np.asarray(i, np.int64),
                                                np.asarray(j, np.int64))
        if not len(i):
            return [[r for _, _, r in found] for found in fast]
        slow = self._triangle_pairs_many(poses, i, j)
        return [[r for _, _, r in self._in_pair_order(a + b)] for a, b in zip(fast, slow)]

    def _in_pair_order(self, found: list[tuple[int, int, Interference]]) -> list[tuple[int, int, Interference]]:
        """(i, j, record) of one state, two lists' worth, in the order :func:`check_parts` gives
        them: the pairs without a plane by (i, j), then the planes' in the order found."""
        plane = self.parts.plane
        return sorted(found, key=lambda x: (1, 0, 0) if plane[x[0]] or plane[x[1]] else (0, x[0], x[1]))

    def _triangle_pairs_many(self, poses: np.ndarray, i: np.ndarray, j: np.ndarray
                             ) -> list[list[tuple[int, int, Interference]]]:
        """:func:`check_parts` of pairs (i, j) at S states at once (poses (S, P, 4, 4)), each record with
        its two parts: the pairs' parts laid out once per state in one :meth:`PartSet.tiled` set
        (built once per choice of parts), so a batch of states costs about one call's numpy overhead."""
        n_s = len(poses)
        out: list[list[tuple[int, int, Interference]]] = [[] for _ in range(n_s)]
        used, local = np.unique(np.concatenate([i, j]), return_inverse=True)
        k = len(used)
        key = tuple(used.tolist())
        # at most TILE_TRIANGLES triangles laid out: a large mesh is checked a few states a call
        tris = int(np.isin(self.parts.tri_part, used).sum())
        most = max(1, TILE_TRIANGLES // max(tris, 1))
        view = self._tiled.get(key)
        if view is None or len(view.names) < min(n_s, most) * k:      # laid out for the longest batch seen
            view = self._tiled[key] = self.parts.tiled(used, min(max(n_s, 32), most))
        copies = len(view.names) // k
        li, lj = local[:len(i)], local[len(i):]
        focus = None if self.focus is None else np.tile(np.asarray(self.focus, bool)[used], copies)
        all_poses = np.asarray(poses, float)[:, used]
        for lo in range(0, n_s, copies):
            poses = all_poses[lo:lo + copies]
            n = len(poses)
            if copies > n:                                  # the copies past the states stay unused
                poses = np.concatenate([poses, np.broadcast_to(poses[-1:], (copies - n,) + poses.shape[1:])])
            shift = (k * np.arange(n))[:, None]
            vi, vj = (li[None] + shift).ravel(), (lj[None] + shift).ravel()
            vi, vj = np.minimum(vi, vj), np.maximum(vi, vj)
            placed = view.place(poses.reshape(-1, 4, 4))
            for a, b, rec in _check_indexed(view, placed, self.clearance, focus, None, True, (vi, vj)):
                out[lo + a // k].append((int(used[a % k]), int(used[b % k]), rec))
        return out

    def pair_values(self, poses: np.ndarray, i: np.ndarray, j: np.ndarray, reach: float,
                    exact_below: float | None = None) -> np.ndarray:
        """:func:`pair_values` of pairs (i, j) at poses (P, 4, 4)."""
        return self.pair_values_axes(poses, i, j, reach, exact_below)[0]

    def pair_values_axes(self, poses: np.ndarray, i: np.ndarray, j: np.ndarray, reach: float,
                         exact_below: float | None = None) -> tuple[np.ndarray, np.ndarray]:
        """:func:`pair_values_axes` of pairs (i, j) at poses (P, 4, 4)."""
        if not len(i):
            return np.zeros(0), np.zeros((0, 3))
        return pair_values_axes(self.parts, self.parts.place(poses), i, j, reach, exact_below)

    def hull_separations(self, poses: np.ndarray, a: int, b: int, axis: np.ndarray,
                         at: np.ndarray) -> np.ndarray:
        """:func:`hull_separations_along` of the pair (a, b) at poses (S, P, 4, 4)."""
        return hull_separations_along(self.parts, poses, a, b, axis, at)

    def _primitive_pairs_many(self, poses: np.ndarray, i: np.ndarray, j: np.ndarray
                              ) -> tuple[list[list[tuple[int, int, Interference]]], np.ndarray, np.ndarray]:
        """The records, per state of poses (S, P, 4, 4), of the pairs of two
        primitives (no plane) among (i, j): the oriented-box test and
        :func:`cablecheck.checker.convex.convex_pairs` on those pairs at all the
        states in one call, straight from the poses (what :func:`check_parts`
        does with the same rows, whose answers depend on each row alone), each
        record with its two parts, in pair order; and the pairs (i < j, in
        pair order) left to their triangles: a mesh or a plane in them, or two
        boxes apart at some state (convex_pairs leaves their distance to the
        caller)."""
        parts, kind = self.parts, self.parts.convex_kind
        i, j = np.minimum(i, j), np.maximum(i, j)
        order = np.lexsort((j, i))
        i, j = i[order], j[order]
        n_s = len(poses)
        out: list[list[tuple[int, int, Interference]]] = [[] for _ in range(n_s)]
        prim = (kind[i] >= 0) & (kind[j] >= 0)
        left_i, left_j = i[~prim], j[~prim]
        i, j = i[prim], j[prim]
        if self.focus is not None:
            focus = np.asarray(self.focus, bool)
            keep = focus[i] != focus[j]
            i, j = i[keep], j[keep]
        n = len(i)
        if not n:
            return out, left_i, left_j
        a, b = np.tile(i, n_s), np.tile(j, n_s)
        rot_a, rot_b = poses[:, i, :3, :3].reshape(-1, 3, 3), poses[:, j, :3, :3].reshape(-1, 3, 3)
        pos_a, pos_b = poses[:, i][..., :3, 3].reshape(-1, 3), poses[:, j][..., :3, 3].reshape(-1, 3)
        # Placement's box centres and the grown oriented-box test, as check_parts
        mid, half = self._mid, self._grown
        c_a = np.einsum("nij,nj->ni", rot_a, mid[a]) + pos_a
        c_b = np.einsum("nij,nj->ni", rot_b, mid[b]) + pos_b
        near = np.flatnonzero(obb_overlap(c_a, rot_a, half[a], c_b, rot_b, half[b]))
        if not len(near):
            return out, left_i, left_j
        size = parts.sd_groups[2]
        ka, kb = a[near], b[near]
        value, where, _, apart = convex_pairs(kind[ka], size[ka], rot_a[near], pos_a[near],
                                              kind[kb], size[kb], rot_b[near], pos_b[near], self.clearance)
        if apart.any():
            # two boxes apart at some state: that pair by its triangles at every state
            gone = np.zeros(n, bool)
            gone[near[apart] % n] = True
            kept = ~gone[near % n]
            near, ka, kb, value, where = near[kept], ka[kept], kb[kept], value[kept], where[kept]
            left_i, left_j = _sorted(np.concatenate([left_i, i[gone]]), np.concatenate([left_j, j[gone]]))
        touch = parts.touch(ka, kb)
        rec_k = np.flatnonzero((value < -touch) | ((touch < value) & (value < self.clearance)))
        # one record per state and pair: plain Python values, taken in one pass each
        for a_k, b_k, v_k, w_k, s_k in zip(ka[rec_k].tolist(), kb[rec_k].tolist(), value[rec_k].tolist(),
                                            where[rec_k], (near[rec_k] // n).tolist()):
            rec = _record(parts, a_k, b_k, v_k, w_k, self.clearance)
            if rec is not None:
                out[s_k].append((a_k, b_k, rec))
        return out, left_i, left_j

    def moving_pairs(self) -> tuple[np.ndarray, np.ndarray]:
        """(i, j) arrays, i < j: the part pairs that can move relative to
        each other (on different rigid bodies), as :meth:`check` tests them."""
        # only pairs across groups are formed (no P x P intermediate): in group
        # order, each part meets the parts of the later groups
        grp = self._group
        order = np.argsort(grp, kind="stable")
        g = grp[order]
        end = np.searchsorted(g, g, side="right")          # end of each part's group in ``order``
        cnt = len(g) - end
        a = order[np.repeat(np.arange(len(g)), cnt)]
        b = order[ranges(end, cnt)]
        i, j = np.minimum(a, b), np.maximum(a, b)
        keep = ~self._skip[i, j]
        i, j = i[keep], j[keep]
        o = np.lexsort((j, i))
        return i[o], j[o]

    @property
    def has_same_body_records(self) -> bool:
        """The first :meth:`check` found same-body records (replayed since)."""
        return self._static is not None and len(self._static[0]) > 0

    def replay(self, poses: np.ndarray) -> list[Interference]:
        """The same-body records alone at poses (P, 4, 4): what :meth:`check`
        returns when no moving pair can be within the clearance. Needs a
        :meth:`check` first."""
        return self.replay_many(np.asarray(poses, float)[None])[0]

    def replay_many(self, poses: np.ndarray) -> list[list[Interference]]:
        """:meth:`replay` at S states at once (poses (S, P, 4, 4)), to the
        bit: the places of all the states' records moved in one product."""
        found, ka, local = self._static
        if not len(found):
            return [[] for _ in range(len(poses))]
        poses = np.asarray(poses, float)
        n_s, k = len(poses), len(ka)
        rigid = poses[:, ka]                                  # (S, K, 4, 4)
        rot = rigid[..., :3, :3].reshape(n_s * k, 3, 3)
        pts = np.broadcast_to(local[None], (n_s,) + local.shape).reshape(n_s * k, 1, 3)
        # Placement.world's arithmetic, the states stacked
        world = np.einsum("nij,nkj->nki", rot, pts) + rigid[..., :3, 3].reshape(n_s * k, 1, 3)
        world = world.reshape(n_s, k, 3)
        fields = [(r.type, r.a, r.b, r.min_distance, r.severity, r.s, r.s_b) for r in found]
        return [[Interference(t, a, b, d, sev, w, s_, sb) for (t, a, b, d, sev, s_, sb), w in zip(fields, ws)]
                for ws in world]

    def _replay(self, placed) -> list[Interference]:
        found, ka, local = self._static
        world = placed.world(ka, local)[:, 0] if len(found) else local[:, 0]
        return [replace(r, where=w) for r, w in zip(found, world)]
