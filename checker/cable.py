"""Cable centrelines as dynamic discrete points: resampling, arc length, bends.

The discrete-point paper (Ju et al., 2016) represents a cable by ordered points on its centreline at
spacing ``l`` that move with the cable. Two constructions are offered:

- :func:`resample` puts points at equal arc-length spacing (at most ``l``)
  along the polyline, both ends included: the paper's construction.
- :func:`densify` keeps every given point (the simulated body centres) and
  splits each element longer than ``l`` into equal parts, so the polyline's
  geometry is unchanged; this is what the checker uses (SPEC, "Algorithms").

It also holds :func:`self_pair_excluded`, the single definition of which pairs
of places on one cable are too close along the cable to count as self
interference, shared with the simulation side's filtering of MuJoCo's self
contacts, and :func:`bend_radius`.

Deliberately not here: distances between cables or to parts
(:mod:`cablecheck.checker.interference`), smoothing or splines (the points are the truth).
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from cablecheck.checker.arrays import ranges, within
from cablecheck.checker.closest import cross, row_norm

TAUT_STRAIN = 0.01
"""Stretch beyond which a cable is taut (SPEC: 1 %)."""


def taut_margin(length, rest_length):
    """The 1 % stretch allowance minus the stretch: negative when taut (same units)."""
    return TAUT_STRAIN * rest_length - (length - rest_length)


def arc_length(points: np.ndarray) -> np.ndarray:
    """Cumulative arc length (n,) of a polyline (n, 3), starting at 0; of
    each of m polylines (m, n, 3) at once, (m, n)."""
    p = np.asarray(points, dtype=float)
    if p.ndim == 3:
        s = np.zeros(p.shape[:2])
        np.cumsum(row_norm(np.diff(p, axis=1)), axis=1, out=s[:, 1:])
        return s
    seg = row_norm(np.diff(p.reshape(-1, 3), axis=0))
    return np.concatenate([[0.0], np.cumsum(seg)])


def element_pairs_within(pa: np.ndarray, pb: np.ndarray, reach: np.ndarray
                         ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The element pairs of polylines pa (S, na + 1, 3) and pb (S, nb + 1, 3)
    whose bounding spheres (about each element's middle, half its length
    across) come within ``reach`` (S,) of each other, state by state (inf:
    every pair): (state, element of a, element of b, gap), each (n,), in no
    particular order. The gap, the middles' distance less both half lengths,
    is no more than the elements' own distance.

    Found by sweep, not by every pair: each state's middles projected on the
    axis along which b's spread most (a distance shrinks under projection),
    an element of a is paired with those of b whose projections lie within
    the reach and both half lengths of its own (b's longest taken); only
    those pairs' gaps are computed. Two hoses lying side by side pair a few
    elements of b with each of a, not all of them."""
    n_s = len(pa)
    ma, mb = 0.5 * (pa[:, 1:] + pa[:, :-1]), 0.5 * (pb[:, 1:] + pb[:, :-1])
    ha, hb = 0.5 * row_norm(pa[:, 1:] - pa[:, :-1]), 0.5 * row_norm(pb[:, 1:] - pb[:, :-1])
    scale = 1.0 + np.abs(pa).max(axis=(1, 2), initial=0.0) + np.abs(pb).max(axis=(1, 2), initial=0.0)
    reach = np.asarray(reach, float) + 1e-9 * scale                                # rounding
    n_a, n_b = ma.shape[1], mb.shape[1]
    if n_s == 0 or n_a == 0 or n_b == 0:
        z = np.zeros(0, np.int64)
        return z, z, z, np.zeros(0)
    axis = np.argmax(mb.max(axis=1) - mb.min(axis=1), axis=1)                      # (S,)
    xa = np.take_along_axis(ma, axis[:, None, None], axis=2)[..., 0]               # (S, Ea)
    xb = np.take_along_axis(mb, axis[:, None, None], axis=2)[..., 0]               # (S, Eb)
    width = np.where(np.isfinite(reach), reach, 0.0) + hb.max(axis=1) + 1e-9 * scale   # (S,), a margin
    # the states laid apart along one line (state k from k * apart), b's projections sorted in each
    apart = 4.0 * float(np.max(scale + np.abs(width) + ha.max(axis=1))) + 1.0
    shift = apart * np.arange(n_s)
    order = np.argsort(xb, axis=1, kind="stable")
    line = (np.take_along_axis(xb, order, axis=1) + shift[:, None]).ravel()
    pad = 4.0 * np.spacing(apart * n_s)                                            # the shift's rounding
    at = xa + shift[:, None]
    w = (width[:, None] + ha) + pad
    own = np.repeat(np.arange(n_s) * n_b, n_a)                                     # each state's own run
    everything = np.repeat(~np.isfinite(reach), n_a)
    lo = np.where(everything, own, np.maximum(np.searchsorted(line, (at - w).ravel(), "left"), own))
    hi = np.where(everything, own + n_b, np.minimum(np.searchsorted(line, (at + w).ravel(), "right"), own + n_b))
    count = np.maximum(hi - lo, 0)                              # none where the reach is below -ha - hb
    flat_b = ranges(lo, count)
    k = flat_b // n_b
    ia = np.repeat(np.arange(n_s * n_a) % n_a, count)
    ib = order.ravel()[flat_b]
    gap = row_norm(ma[k, ia] - mb[k, ib]) - ha[k, ia] - hb[k, ib]
    o = gap <= reach[k]
    return k[o], ia[o], ib[o], gap[o]


def resample(points: np.ndarray, spacing: float) -> tuple[np.ndarray, np.ndarray]:
    """Points at equal arc-length spacing along a polyline, both ends included.

    The number of intervals is ``ceil(length / spacing)`` (at least one), so
    the actual spacing is the largest value not above ``spacing`` that divides
    the length evenly. Corners of the polyline between two new points are cut,
    by at most ``spacing / 2`` times the sine of half the turning angle; use
    :func:`densify` to keep them.

    Args:
        points: (n, 3) polyline, n >= 2; zero-length pieces are allowed.
        spacing: target spacing l > 0.

    Returns:
        pts: (m, 3) resampled points, m >= 2.
        s: (m,) their arc lengths.
    """
    p = np.asarray(points, dtype=float).reshape(-1, 3)
    if len(p) < 2:
        raise ValueError("a polyline needs at least two points")
    if not spacing > 0:
        raise ValueError(f"spacing must be positive, got {spacing}")
    s = arc_length(p)
    total = s[-1]
    n_int = max(1, int(np.ceil(total / spacing * (1.0 - 1e-12))))
    s_new = total * np.arange(n_int + 1) / n_int
    s_new[-1] = total
    # Segment containing each new point; zero-length pieces are never chosen
    # because searchsorted('right') skips repeated arc lengths.
    k = np.clip(np.searchsorted(s, s_new, side="right") - 1, 0, len(p) - 2)
    seg_len = s[k + 1] - s[k]
    ok = seg_len > 0
    u = np.where(ok, s_new - s[k], 0.0) / np.where(ok, seg_len, 1.0)
    pts = p[k] + np.clip(u, 0.0, 1.0)[:, None] * (p[k + 1] - p[k])
    pts[0], pts[-1] = p[0], p[-1]
    return pts, s_new


def polyline_arc_lengths(step: np.ndarray, offsets: np.ndarray) -> np.ndarray:
    """Arc length (N,) of every point along its own polyline.

    ``step`` (N - 1,): the length of element i (points i, i + 1; anything
    where the two are on different polylines); ``offsets`` (C + 1,) as for
    :func:`densify_batch`. Each polyline's lengths are summed on their own,
    so they do not depend on the polylines before it (the same bits as
    :func:`arc_length`, whichever polylines are batched together).
    """
    offsets = np.ascontiguousarray(offsets, dtype=np.int64)
    return _arc_layout(offsets.tobytes())(step)


@lru_cache(maxsize=16)
def _arc_layout(offsets: bytes) -> "ArcLayout":
    """The layout of these offsets, prepared once (a run uses a handful)."""
    return ArcLayout(np.frombuffer(offsets, dtype=np.int64))


def tile_offsets(offsets: np.ndarray, states: int) -> np.ndarray:
    """Offsets (S C + 1,) of S states of concatenated points, each laid out
    by ``offsets`` (C + 1,): every cable of every state a polyline of its own."""
    offsets = np.asarray(offsets, np.int64)
    n = int(offsets[-1])
    starts = (offsets[:-1][None, :] + n * np.arange(states)[:, None]).ravel()
    return np.append(starts, states * n)


class ArcLayout:
    """:func:`polyline_arc_lengths` for one set of offsets, prepared once.

    One padded row per polyline, summed along the rows; polylines of about
    the same length share a pad (within a factor 2: no long pad for many
    short lines), a few groups at most.
    """

    def __init__(self, offsets: np.ndarray):
        offsets = np.asarray(offsets, dtype=np.int64)
        counts = np.diff(offsets)
        self.n = int(offsets[-1]) if len(offsets) else 0
        self._groups = []
        self._block = None
        if self.n == 0:
            return
        if len(counts) and np.all(counts == counts[0]):
            # every polyline as long: the points reshape into the pad's rows
            self._block = (len(counts), int(counts[0]))
            return
        group = np.floor(np.log2(np.maximum(counts, 1))).astype(np.int64)
        for g in np.unique(group):
            lines = np.flatnonzero(group == g)
            cnt = counts[lines]
            row = np.repeat(np.arange(len(lines)), cnt)
            pos = within(cnt)
            idx = offsets[lines][row] + pos                    # the points of these polylines
            later = pos > 0                                    # element i - 1 leads to point i
            self._groups.append(((len(lines), int(cnt.max())), row[later], pos[later], idx[later] - 1,
                                 row, pos, idx))

    def __call__(self, step: np.ndarray) -> np.ndarray:
        if self._block is not None:
            rows, cnt = self._block
            pad = np.zeros((rows, cnt))
            lead = np.zeros(rows * cnt)
            lead[1:] = step[: rows * cnt - 1]                   # element i - 1 before point i
            pad[:, 1:] = lead.reshape(rows, cnt)[:, 1:]
            return np.cumsum(pad, axis=1).ravel()
        out = np.zeros(self.n)
        for shape, r_in, p_in, e_in, row, pos, idx in self._groups:
            pad = np.zeros(shape)
            pad[r_in, p_in] = step[e_in]
            out[idx] = np.cumsum(pad, axis=1)[row, pos]
        return out


PIECES_STRETCH = 0.02
"""An element keeps the pieces of its rest length stretched by this share
(`rest_pieces`) while it stretches no further: its number of pieces does not
change as it stretches and relaxes a little about a multiple of the spacing,
which would end every proven-clear run (the zoo's Tiago: 22 of its 26 full
checks). Above the 1 % a cable is called taut at."""


def element_pieces(length: np.ndarray, spacing: np.ndarray, least: np.ndarray | float = 1.0) -> np.ndarray:
    """Pieces (as floats, at least 1 and at least ``least``) an element of
    this length is split into so none is longer than ``spacing``:
    ``ceil(length / spacing)``, less a relative 1e-12 so an element of
    exactly k spacings is not split in k + 1. The one formula of
    :func:`densify_batch` and of the skip rule's test that an element still
    splits alike (:mod:`cablecheck.checker.advance`). An infinite spacing gives 1
    piece (or ``least``)."""
    return np.maximum(np.maximum(np.ceil(length / spacing * (1.0 - 1e-12)), 1.0), least)


def rest_pieces(rest: np.ndarray, offsets: np.ndarray, spacing: np.ndarray) -> np.ndarray:
    """(N - 1,) the least pieces of each element (points i, i + 1 of one
    polyline; 1 between polylines): those of its rest length, from the
    material coordinates ``rest`` (N,), stretched by `PIECES_STRETCH`, at
    its polyline's ``spacing`` (C,). Never fewer than its length needs while
    it stretches no further, so the points' error bound holds all the same."""
    offsets = np.asarray(offsets, np.int64)
    cable = np.repeat(np.arange(len(offsets) - 1), np.diff(offsets))
    valid = cable[:-1] == cable[1:]
    rest = np.asarray(rest, float)
    length = np.where(valid, np.abs(np.diff(rest)) * (1.0 + PIECES_STRETCH), 0.0)
    return np.where(valid, element_pieces(length, np.asarray(spacing, float)[cable[:-1]]), 1.0)


def densify_batch(
    points: np.ndarray, offsets: np.ndarray, spacing: np.ndarray, source: bool = False,
    keep: np.ndarray | None = None, least: np.ndarray | None = None,
) -> tuple[np.ndarray, ...]:
    """:func:`densify` for many polylines at once.

    Args:
        points: (N, 3) all polylines' points, concatenated.
        offsets: (C + 1,) start of each polyline in ``points``; polyline c is
            ``points[offsets[c]:offsets[c + 1]]`` with at least 2 points.
        spacing: (C,) largest allowed element length per polyline.
        keep: (N,) bool, or None (all): only the kept input points emit
            (themselves and the points inside the element after them), each
            exactly as without ``keep`` (arc lengths along the whole
            polyline); ``new_offsets`` then counts the emitted points.
        least: (N - 1,) the least pieces of each element (`rest_pieces`),
            or None (those its length needs).

    Returns:
        pts: (M, 3) densified points, concatenated.
        s: (M,) arc length of each along its own polyline.
        cable: (M,) polyline index of each point.
        new_offsets: (C + 1,) start of each polyline in ``pts``.
        src, own, frac: with ``source``, (M,) the input point each
            densified point starts from (it lies on the element from ``src``
            to ``src + 1``), (M,) bool, the point is that input point itself,
            and (M,) its fraction of the way along that element (0 for own).
    """
    p = np.asarray(points, dtype=float).reshape(-1, 3)
    offsets = np.asarray(offsets, dtype=np.int64)
    n_c = len(offsets) - 1
    cable_of_pt = np.repeat(np.arange(n_c), np.diff(offsets))
    seg_len = row_norm(np.diff(p, axis=0))
    # Element i joins point i to i+1 when both are on the same polyline.
    valid = cable_of_pt[:-1] == cable_of_pt[1:]
    lim = np.asarray(spacing, dtype=float)[cable_of_pt[:-1]]
    pieces = np.where(valid, element_pieces(seg_len, lim, 1.0 if least is None else least).astype(np.int64), 0)
    step = np.where(valid, seg_len, 0.0)
    s_pt = polyline_arc_lengths(step, offsets)
    if keep is None and np.all(pieces <= 1):  # nothing to split
        out = (p.copy(), s_pt, cable_of_pt, offsets.copy())
        return out + ((np.arange(len(p)), np.ones(len(p), bool), np.zeros(len(p))) if source else ())
    # Each point emits itself, then pieces-1 interior points of its element.
    emit = np.ones(len(p), dtype=np.int64)
    emit[:-1] += np.maximum(pieces - 1, 0)
    if keep is not None:
        emit = np.where(keep, emit, 0)
    total = int(emit.sum())
    src = np.repeat(np.arange(len(p)), emit)
    first = np.cumsum(emit) - emit
    j = np.arange(total) - first[src]  # 0 for the point itself, then 1..pieces-1
    nxt = np.minimum(src + 1, len(p) - 1)
    frac = j / np.maximum(np.r_[pieces, 1][src], 1)
    pts = p[src] + frac[:, None] * (p[nxt] - p[src])
    s = s_pt[src] + frac * np.r_[step, 0.0][src]
    cable = cable_of_pt[src]
    new_offsets = np.concatenate([[0], np.cumsum(np.bincount(cable, minlength=n_c))])
    return (pts, s, cable, new_offsets) + ((src, j == 0, frac) if source else ())


def material_coordinates(s: np.ndarray, src: np.ndarray, frac: np.ndarray, has_rest: np.ndarray,
                         rest: np.ndarray) -> np.ndarray:
    """Where densified points lie along their cable's own material.

    A point a fraction ``frac`` of the way along the element from input
    point ``src`` to ``src + 1`` lies at ``rest[src] + frac (rest[src + 1] -
    rest[src])``: the rest (unstretched) arc length of the material there,
    which stretching does not change. Where ``has_rest`` (M,) is False the
    current arc length ``s`` is taken as it is (no rest shape known).

    Args:
        s, src, frac: (M,) as :func:`densify_batch` returns them.
        has_rest: (M,) bool, the point's cable has rest coordinates.
        rest: (N,) rest arc length of every input point (any value where
            its cable has none).
    """
    if not has_rest.any():
        return s
    nxt = np.minimum(src + 1, len(rest) - 1)
    m = rest[src] + frac * (rest[nxt] - rest[src])
    return np.where(has_rest, m, s)


def densify(points: np.ndarray, spacing: float) -> tuple[np.ndarray, np.ndarray]:
    """Keep every point; split elements longer than ``spacing`` evenly.

    The polyline's shape is unchanged (no corner is cut) and no element of the
    result is longer than ``spacing``. Zero-length elements stay as repeated
    points.

    Args:
        points: (n, 3) polyline, n >= 2.
        spacing: largest allowed element length l > 0.

    Returns:
        pts: (m, 3) with m >= n.
        s: (m,) arc lengths.
    """
    p = np.asarray(points, dtype=float).reshape(-1, 3)
    if len(p) < 2:
        raise ValueError("a polyline needs at least two points")
    if not spacing > 0:
        raise ValueError(f"spacing must be positive, got {spacing}")
    pts, s, _, _ = densify_batch(p, np.array([0, len(p)]), np.array([float(spacing)]))
    return pts, s


def self_pair_excluded(s_a: np.ndarray, s_b: np.ndarray, radius: float | np.ndarray,
                       clearance: float = 0.0) -> np.ndarray:
    """True where two places on one cable are too close along it to interfere.

    Two places whose arc lengths differ by less than ``pi * radius +
    clearance`` are never self interference. Neighbouring points or elements
    of a cable are always within ``2r`` of each other (the paper's spacing is
    ``2r``, and a bent cable brings them closer still), so they would always
    "interfere". Beyond them, the tightest bend a cable can take without
    kinking has its centreline radius equal to ``r`` (the inner surface then
    has radius 0); on such a bend two places come within ``2r`` of each other
    only when their arc lengths differ by less than ``pi * r``: at exactly
    ``pi * r`` (a half turn) the two legs of the U just touch, which is the
    first real self contact. Soft interference reaches ``clearance`` further:
    on a straight cable two places ``ds`` apart along it are ``ds - 2r`` apart
    as surfaces, which is below the clearance whenever ``ds < 2r +
    clearance``, so the window grows by the clearance too (otherwise every
    straight cable with a clearance above ``(pi - 2) r`` would be in soft
    self interference). A U bent that tight still reads hard from there on,
    its legs lying together. At the paper's spacing ``2r`` and no clearance
    this excludes exactly the adjacent points and keeps every point two or
    more places away.

    The rule is about places, whatever finds them: method ``points`` applies
    it to its discrete points and element midpoints, method ``exact`` to
    every place of two elements (the nearest pair at least the window apart,
    :func:`cablecheck.checker.closest.segment_segment_apart`), and so do the comparison
    with MuJoCo's contacts and the wear map (docs/self-check.md). The arc
    length is along the centreline as it is now: the bend argument above is
    about the cable's present shape.

    Args:
        s_a, s_b: arc lengths (broadcastable arrays), same units as radius.
        radius: the cable's radius (scalar or broadcastable array).
        clearance: the soft-interference distance, same units.

    Returns:
        bool array of the broadcast shape.
    """
    return np.abs(np.asarray(s_a, dtype=float) - np.asarray(s_b, dtype=float)) < self_pair_window(radius, clearance)


def self_pair_window(radius, clearance: float = 0.0):
    """``pi * radius + clearance``: the arc-length separation below which
    :func:`self_pair_excluded` drops a pair of places of one cable."""
    return np.pi * np.asarray(radius, dtype=float) + clearance


def bend_radius(points: np.ndarray) -> np.ndarray:
    """Local bend radius at each point from its two neighbours, (n,).

    At an interior point it is the circumradius of the triangle formed with its
    neighbours, ``|c| / (2 sin phi)`` with ``c`` the chord between the
    neighbours and ``phi`` the turning angle. When the cable turns by more than
    a right angle within two elements (a kink), the circumradius would grow
    again, so ``|c| / 2`` is used instead; it joins continuously at 90 degrees
    and is 0 for a full fold-back. Straight runs and zero-length neighbours
    give ``inf``, and so do the two ends (no neighbour on one side).

    Args:
        points: (n, 3) centreline points.

    Returns:
        (n,) bend radius, same units as the points.
    """
    p = np.asarray(points, dtype=float).reshape(-1, 3)
    out = np.full(len(p), np.inf)
    if len(p) < 3:
        return out
    a = p[1:-1] - p[:-2]
    b = p[2:] - p[1:-1]
    r, nonzero = _turn_radius(a, b, row_norm(a), row_norm(b), row_norm(p[2:] - p[:-2]))
    out[1:-1] = np.where(nonzero, r, np.inf)
    return out


def _turn_radius(a: np.ndarray, b: np.ndarray, la: np.ndarray, lb: np.ndarray,
                 lc: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Bend radius at interior points from their edges a, b (m, 3), the edges'
    lengths la, lb and the chord length lc (m,) (see `bend_radius`); and
    where both edges have length. The one formula behind `bend_radius` and
    `CableMeasures`, so both round alike."""
    area = row_norm(cross(a, b))
    dot = np.einsum("ij,ij->i", a, b)
    nonzero = (la > 0) & (lb > 0)
    sin_phi = np.where(nonzero, area, 0.0) / np.where(nonzero, la * lb, 1.0)
    # Straight when the turning angle is below rounding noise.
    bent = nonzero & (sin_phi > 1e-12)
    r_circ = np.where(bent, lc, 1.0) / np.where(bent, 2.0 * sin_phi, 1.0)
    return np.where(dot >= 0.0, np.where(bent, r_circ, np.inf), 0.5 * lc), nonzero


class CableMeasures:
    """Length and smallest bend radius of every cable in one pass over the
    concatenated body centres (the run loop's per-step measures).

    The same floating-point operations per element and per point as
    :func:`arc_length` and :func:`bend_radius` (so the same bits):
    ``lengths[c] == arc_length(p_c)[-1]`` and ``min_bend[c] ==
    np.min(bend_radius(p_c))``; ``tests/test_cable.py`` checks it.

    Args:
        offsets: (C + 1,) start of each cable in the concatenated points;
            every cable has at least 2 points.
    """

    def __init__(self, offsets: np.ndarray):
        offsets = np.asarray(offsets, np.int64)
        counts = np.diff(offsets)
        n = int(offsets[-1])
        self._none = len(counts) == 0
        if self._none:
            return
        self._starts = offsets[:-1]
        self._ends = offsets[1:] - 1
        self._arc = ArcLayout(offsets)
        cable = np.repeat(np.arange(len(counts)), counts)
        valid = cable[:-1] == cable[1:]
        self._single = len(counts) == 1
        # interior points (both neighbours on the same cable); the rest stay inf
        self._interior = (valid[:-1] & valid[1:]) if n >= 3 else np.zeros(0, bool)
        self._r = np.full(n, np.inf)
        self._offsets = offsets
        self._tiled: dict[int, CableMeasures] = {}

    def many(self, pts: np.ndarray, at_points: bool = False) -> tuple[np.ndarray, ...]:
        """(lengths (S, C), smallest bend radii (S, C)) of S states of the
        concatenated points (S, N, 3), in one pass (the same bits as calling
        this per state: every cable of every state is measured on its own).
        With ``at_points``, also the bend radius at every point (S, N), the
        bits of :func:`bend_radius` per cable."""
        s = len(pts)
        if self._none:
            return (np.zeros((s, 0)), np.zeros((s, 0))) + ((np.zeros((s, 0)),) if at_points else ())
        tiled = self._tiled.get(s)
        if tiled is None:
            tiled = self._tiled[s] = CableMeasures(tile_offsets(self._offsets, s))
        lengths, bend = tiled(np.asarray(pts, float).reshape(-1, 3))
        out = (lengths.reshape(s, -1), bend.reshape(s, -1))
        return out + ((tiled._r.reshape(s, -1).copy(),) if at_points else ())

    def __call__(self, pts: np.ndarray, seg: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """(lengths (C,), smallest bend radius (C,)) of the concatenated
        points (N, 3); ``seg``: ``row_norm(pts[1:] - pts[:-1])`` when known."""
        if self._none:
            return np.zeros(0), np.zeros(0)
        d = pts[1:] - pts[:-1]
        if seg is None:
            seg = row_norm(d)
        lengths = np.cumsum(seg)[-1:] if self._single else self._arc(seg)[self._ends]
        r = self._r
        if len(self._interior):
            rr, nonzero = _turn_radius(d[:-1], d[1:], seg[:-1], seg[1:], row_norm(pts[2:] - pts[:-2]))
            r[1:-1] = np.where(nonzero & self._interior, rr, np.inf)
        bend = r.min(keepdims=True) if self._single else np.minimum.reduceat(r, self._starts)
        return lengths, bend
