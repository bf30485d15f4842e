"""The skip rule's bound on cables against parts (cable-structure, keep-out).

After a full check every body centre gets a gap to every part: the least
value minus the clearance of the part's candidates on the elements next to
it, or where there is none the larger of the horizon and the elements'
floor (their boxes' distance from the part's box in its frame). Kept as a
dense (centres x parts) table, or for large scenes as sparse entries below
``FAR_HORIZONS`` horizons found through a k-d tree. :meth:`CentrePartGaps.clear`
tests many states at once, in each part's own frame and in the world;
:meth:`CentrePartGaps.failing` names the pairs that fail and
:meth:`CentrePartGaps.promote` leaves them to the caller.

Deliberately not here: cable pairs, part pairs, the run of states
(:class:`cablecheck.checker.advance.skip.Advancement`).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from cablecheck.checker.advance.common import FAR_HORIZONS, Layout, Start, bracket
from cablecheck.checker.arrays import ranges
from cablecheck.checker.interference.hits import PartCandidates


@dataclass(frozen=True, slots=True)
class DenseGaps:
    """The centre-part gaps of a dense start (:meth:`CentrePartGaps.start`);
    promoting a pair sets its gaps to inf in place.

    Attributes:
        g_pt: (N, P) ``g[i, k]`` of the package docstring less the rounding margin.
        g_kn: (P, N) the same, part-major (contiguous) for the fused pass.
        g2: (P, N) the squares of their positive parts.
        u0h: (P, N, 4) each centre in each part's frame at the start, homogeneous.
    """

    g_pt: np.ndarray
    g_kn: np.ndarray
    g2: np.ndarray
    u0h: np.ndarray


@dataclass(frozen=True, slots=True)
class SparseStart:
    """What a sparse start (:meth:`CentrePartGaps._start_sparse`) keeps:
    the entries listed at once and what listing the others on first use takes.

    Attributes:
        cap: the gap of a checked pair that is not listed, ``FAR_HORIZONS
            * horizon`` less the rounding margin.
        default: (P,) an unlisted pair's gap per part (inf: not checked).
        first: (part, centre, gap) entries of the active parts, listed at the start.
        gap_part: (P,) the check's gaps per part.
        candidates: the check's part candidates.
        rest: (P,) bool, the parts whose entries are listed on first use.
    """

    cap: float
    default: np.ndarray
    first: tuple[np.ndarray, np.ndarray, np.ndarray]
    gap_part: np.ndarray
    candidates: PartCandidates
    rest: np.ndarray


@dataclass(frozen=True, slots=True)
class SparseEntries:
    """The sparse entries listed so far (:meth:`CentrePartGaps._ensure_sparse`,
    then the bounded parts' floors per centre, :meth:`CentrePartGaps._refine`).

    Attributes:
        part, row, g: (M,) entries (part, centre, gap less the rounding margin).
        done: (N - 1,) bool, elements whose floors are listed.
        ok: every gap was positive when first listed (and the cap is).
    """

    part: np.ndarray
    row: np.ndarray
    g: np.ndarray
    done: np.ndarray
    ok: bool


@dataclass(frozen=True, slots=True)
class SparseTables:
    """The sparse gaps as the tests of one set of moving parts read them
    (:meth:`CentrePartGaps._sparse_tables`; promoted pairs inf).

    Attributes:
        g_still: (N,) each centre's least gap to the parts that did not move.
        mk: (K,) the parts that moved.
        u0h: (K, N, 4) the centres in their frames at the start, homogeneous.
        g_kn, g2: (K, N) the gaps to them and the squares of their positive parts.
        entries: (centre, part, gap) listed entries against the parts that
            did not move, sorted by centre.
        still_cap: the gap of the unlisted pairs against those parts (the cap).
    """

    g_still: np.ndarray
    mk: np.ndarray
    u0h: np.ndarray
    g_kn: np.ndarray
    g2: np.ndarray
    entries: tuple[np.ndarray, np.ndarray, np.ndarray]
    still_cap: float


class CentrePartGaps:
    """The centre-part gaps of one start.

    Args:
        layout: the run's layout.
        start: the state of the full check.
    """

    FAR_HORIZONS = FAR_HORIZONS

    def __init__(self, layout: Layout, start: Start):
        # the names the bound's arithmetic reads
        self._pts, self._rot, self._pos, self._seg_raw, self._s_c = start.pts, start.rot, start.pos, start.seg, start.s_c
        self._horizon, self._mu = start.horizon, start.mu
        self._cable, self._valid, self._offsets = layout.cable, layout.valid, layout.offsets
        self._rad, self._box, self._rho, self.clearance = layout.rad, layout.box, layout.rho, layout.clearance
        # what :meth:`start` computes: a dense table, or sparse entries listed on use
        self._dense: DenseGaps | None = None
        self._sp: SparseStart | None = None
        self._entries: SparseEntries | None = None          # sparse: listed on first use
        self._tables_cache: dict[bytes, SparseTables] = {}  # sparse: per set of moving parts
        self._promoted = np.zeros(0, np.int64)              # sparse: part * N + centre keys

    @property
    def _sparse(self) -> bool:
        """The gaps are kept sparse (the last start's choice)."""
        return self._sp is not None

    @property
    def _g_pt(self) -> np.ndarray:
        """(N, P) the dense table's gaps."""
        return self._dense.g_pt

    def ok_at_start(self) -> bool:
        """True when every gap is positive (sparse: the cap; the entries on first use)."""
        return self._sp.cap > 0 if self._sp is not None else bool(np.all(self._dense.g_pt > 0))

    def start(self, gap_part: np.ndarray, candidates: PartCandidates | None,
              active: tuple[np.ndarray, np.ndarray] | None, sparse: bool) -> tuple[np.ndarray, np.ndarray]:
        """The gaps ``g[i, k]`` of the package docstring (a dense table, or
        ``sparse`` entries: :meth:`_start_sparse`) from the check's gaps per
        part (inf for parts it does not check) and its candidates (None:
        every centre gets its part's gap); ``active`` as for
        :meth:`cablecheck.checker.advance.skip.Advancement.start`. Returns the active
        (centre, part) pairs."""
        self._promoted = np.zeros(0, np.int64)
        self._dense = self._sp = self._entries = None
        self._tables_cache = {}
        horizon, mu = self._horizon, self._mu
        if sparse:
            self._sp, structure = self._start_sparse(gap_part, horizon, candidates, active, mu)
            return structure
        n, n_p = len(self._pts), len(gap_part)
        u0 = (self._pts[None] - self._pos[:, None]) @ self._rot                  # R^T (x - t)
        if candidates is None:
            g = np.broadcast_to(gap_part, (n, n_p)).copy()
        else:
            base = np.full((n, n_p), float(horizon))
            if self._box is not None and n > 1:
                base = np.maximum(base, self._floor(u0).T)
            g = np.where(np.isfinite(gap_part)[None, :], base, np.inf)
            cab, s, part, value = candidates
            if len(value):
                lo, hi = self._bracket(cab, s)
                count = hi - lo + 1
                rows = ranges(lo, count)
                np.minimum.at(g, (rows, np.repeat(part, count)), np.repeat(value, count))
        structure = (np.zeros(0, np.int64), np.zeros(0, np.int64))
        if active is not None and len(active[0]):
            a_cab, a_part = (np.asarray(x, np.int64) for x in active)
            near = (self._cable[:, None] == a_cab[None, :]) & (g[:, a_part] < self.FAR_HORIZONS * horizon)
            rows, j = np.nonzero(near)
            structure = (rows, a_part[j])
            g[structure] = np.inf
        g_pt = g - mu
        # fused-pass data: each centre in each part's frame (homogeneous)
        u0h = np.concatenate([u0, np.ones(u0.shape[:2] + (1,))], axis=2)
        g_kn = np.ascontiguousarray(g_pt.T)
        self._dense = DenseGaps(g_pt, g_kn, np.where(g_kn > 0, g_kn, 0.0) ** 2, u0h)
        return structure

    def _start_sparse(self, gap_part: np.ndarray, horizon: float, candidates: tuple[np.ndarray, ...],
                      active: tuple[np.ndarray, np.ndarray] | None,
                      mu: float) -> tuple[SparseStart, tuple[np.ndarray, np.ndarray]]:
        """The centre-part gaps ``g[i, k]`` of the package docstring kept only
        where they are below ``cap = FAR_HORIZONS * horizon`` (every other
        checked pair counts as ``cap``: a smaller gap only proves less), as
        (centre, part, gap) entries sorted by part.

        Pairs are listed by a k-d tree of the element midpoints queried about
        each part's frame origin. Why that finds every floor below ``cap``:
        an element of half-length h lies in its bounding box in the part's
        frame, and that box lies within ``sqrt(3) h`` of the midpoint; the
        part's box lies within its bounding radius ``rho`` of the origin; so
        the boxes' distance is at least ``|mid - origin| - sqrt(3) h - rho``,
        and ``F[e, k]`` (that minus the cable radius and the clearance) is at
        least ``cap`` beyond the query radius. Candidates (values at most the
        horizon, below every floor's ``max(H, F)``) are entries of their own.
        Planes and other unbounded parts get every centre. Returns the
        start's record and the active (centre, part) pairs."""
        n_p = len(gap_part)
        cap = self.FAR_HORIZONS * horizon
        sp_cap = cap - mu
        default = np.where(np.isfinite(gap_part), sp_cap, np.inf)    # an unlisted pair's gap
        first = np.zeros(n_p, bool)
        if active is not None and len(active[0]):
            first[np.asarray(active[1], np.int64)] = True
        # the active parts' entries now (the caller needs the active pairs), the
        # others on first use (:meth:`_ensure_sparse`)
        part, rows, val = self._sparse_entries(gap_part, horizon, candidates, first)
        n = len(self._pts)
        structure = (np.zeros(0, np.int64), np.zeros(0, np.int64))
        if active is not None and len(active[0]):
            a_cab, a_part = (np.asarray(x, np.int64) for x in active)
            # (centre, active pair) for every entry of an active part on the pair's cable
            pair_of = {}
            for j, (c, q) in enumerate(zip(a_cab.tolist(), a_part.tolist())):
                pair_of.setdefault(q, []).append((j, c))
            hit_r, hit_j = [np.zeros(0, np.int64)], [np.zeros(0, np.int64)]
            for q, lst in pair_of.items():                         # the few active parts
                on = part == q
                for j, c in lst:
                    r = rows[on & (self._cable[rows] == c)]
                    hit_r.append(r)
                    hit_j.append(np.full(len(r), j, np.int64))
            hr, hj = np.concatenate(hit_r), np.concatenate(hit_j)
            o = np.lexsort((hj, hr))
            hr, hj = hr[o], hj[o]
            structure = (hr, a_part[hj])
            drop = np.isin(part * n + rows, a_part[hj] * n + hr)
            part, rows, val = part[~drop], rows[~drop], val[~drop]
        return SparseStart(sp_cap, default, (part, rows, val - mu), gap_part, candidates, ~first), structure

    def _ensure_sparse(self) -> bool:
        """The sparse entries of the last start that are cheap (once): the
        candidates and the unbounded parts' floors; the bounded parts'
        floors come per centre, when a centre first needs them
        (:meth:`_refine`). True when all gaps are positive."""
        if self._entries is None:
            sp, mu = self._sp, self._mu
            part, rows, val = self._sparse_entries(sp.gap_part, self._horizon, sp.candidates, sp.rest,
                                                   elem=np.zeros(0, np.int64))
            p0, r0, g0 = sp.first
            g = np.concatenate([g0, val - mu])
            self._entries = SparseEntries(np.concatenate([p0, part]), np.concatenate([r0, rows]), g,
                                          ~self._valid.copy(), bool(np.all(g > 0)) and sp.cap > 0)
        return self._entries.ok

    def _refined(self) -> np.ndarray:
        """(N,) bool: centres both of whose elements have their floors listed."""
        done = self._entries.done
        out = np.ones(len(self._pts), bool)
        out[:-1] &= done
        out[1:] &= done
        return out

    def _refine(self, centres: np.ndarray) -> None:
        """List the bounded parts' floors of the elements next to ``centres``
        (their gaps then as in :meth:`_start_sparse`)."""
        n = len(self._pts)
        e = np.concatenate([centres - 1, centres])
        e = np.unique(e[(e >= 0) & (e < n - 1)])
        ent = self._entries
        e = e[~ent.done[e]]
        if not len(e):
            return
        sp = self._sp
        part, rows, val = self._sparse_entries(sp.gap_part, self._horizon, sp.candidates, sp.rest, elem=e,
                                               lazy=True)
        done = ent.done.copy()
        done[e] = True
        self._entries = replace(ent, part=np.concatenate([ent.part, part]), row=np.concatenate([ent.row, rows]),
                                g=np.concatenate([ent.g, val - self._mu]), done=done)
        self._tables_cache = {}

    def _sparse_entries(self, gap_part: np.ndarray, horizon: float, candidates: tuple[np.ndarray, ...],
                        only: np.ndarray, elem: np.ndarray | None = None,
                        lazy: bool = False) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(part, centre, gap) entries below the cap of the parts ``only`` (P,) bool
        (see :meth:`_start_sparse`), the least per pair, sorted by part.
        ``elem``: the elements whose bounded parts' floors are listed (None:
        all); ``lazy``: those floors alone (no candidates, no unbounded parts)."""
        pts, n = self._pts, len(self._pts)
        cap = self.FAR_HORIZONS * horizon
        checked = np.isfinite(gap_part)
        box_lo, box_hi = self._box[0][:, 0], self._box[1][:, 0]
        seg = np.where(self._valid, self._seg_raw, 0.0)
        every = np.nonzero(self._valid)[0]
        elem = every if elem is None else elem
        mid = 0.5 * (pts[elem] + pts[elem + 1])
        bounded = checked & only & np.isfinite(self._rho)
        e_list, k_list = [np.zeros(0, np.int64)], [np.zeros(0, np.int64)]
        if bounded.any() and len(elem):
            reach = (cap + np.sqrt(3.0) * 0.5 * float(seg.max()) + float(self._rad.max()) + self.clearance
                     + 1e-9 * (1.0 + float(np.abs(pts).max())))
            kb = np.nonzero(bounded)[0]
            from scipy.spatial import cKDTree  # a fifth of a second to import: loaded where a tree is built

            # every (part, midpoint) pair within the largest radius, then each part's own
            found = cKDTree(self._pos[kb]).sparse_distance_matrix(
                cKDTree(mid), reach + float(self._rho[kb].max()), output_type="ndarray")
            on = found["v"] <= reach + self._rho[kb[found["i"]]]
            e_list.append(elem[found["j"][on].astype(np.int64)])
            k_list.append(kb[found["i"][on].astype(np.int64)])
        unbounded = np.nonzero(checked & only & ~np.isfinite(self._rho))[0]
        if len(unbounded) and len(every) and not lazy:
            e_list.append(np.tile(every, len(unbounded)))
            k_list.append(np.repeat(unbounded, len(every)))
        e, k = np.concatenate(e_list), np.concatenate(k_list)
        # F[e, k] as _floor computes it (the element's ends in the part's frame)
        rot, pos = self._rot[k], self._pos[k]
        a = np.einsum("ni,nij->nj", pts[e] - pos, rot)
        b = np.einsum("ni,nij->nj", pts[e + 1] - pos, rot)
        sep = np.maximum(np.maximum(np.minimum(a, b) - box_hi[k], box_lo[k] - np.maximum(a, b)), 0.0)
        f = np.sqrt(np.einsum("ni,ni->n", sep, sep)) - self._rad[e] - self.clearance
        rows = np.concatenate([e, e + 1])
        part = np.concatenate([k, k])
        val = np.maximum(horizon, np.concatenate([f, f]))
        cab, s, c_part, value = candidates
        if len(value) and not lazy:
            lo, hi = self._bracket(cab, s)
            count = hi - lo + 1
            rows = np.concatenate([rows, ranges(lo, count)])
            part = np.concatenate([part, np.repeat(np.asarray(c_part, np.int64), count)])
            val = np.concatenate([val, np.repeat(np.asarray(value, float), count)])
        keep = checked[part] & only[part] & (val < cap)
        rows, part, val = rows[keep], part[keep], val[keep]
        key = part * n + rows
        o = np.argsort(key)
        key, val = key[o], val[o]
        first = np.flatnonzero(np.r_[len(key) > 0, key[1:] != key[:-1]][:len(key)])
        if len(first):
            val = np.minimum.reduceat(val, first)                # the least per (part, centre)
        key = key[first]
        part, rows = key // n, key % n
        return part, rows, val

    def _floor(self, u0: np.ndarray) -> np.ndarray:
        """(P, N): per centre and part, the least over the elements next to
        the centre of ``F[e, k]`` (module docstring); u0 (P, N, 3) the
        centres in the parts' frames."""
        a, b = u0[:, :-1], u0[:, 1:]
        box_lo, box_hi = self._box
        sep = np.maximum(np.maximum(np.minimum(a, b) - box_hi, box_lo - np.maximum(a, b)), 0.0)
        f = np.sqrt(np.einsum("kei,kei->ke", sep, sep)) - self._rad[:-1] - self.clearance
        f = np.where(self._valid, f, np.inf)
        out = np.full(u0.shape[:2], np.inf)
        out[:, :-1] = f
        out[:, 1:] = np.minimum(out[:, 1:], f)
        return out

    def _bracket(self, cab: np.ndarray, s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """:func:`~cablecheck.checker.advance.common.bracket` at the start's arc lengths."""
        return bracket(self._s_c, self._cable, self._offsets, cab, s)

    def failing(self, x: np.ndarray, poses: np.ndarray, dq: np.ndarray,
                dp: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
        """The (centre, part) pairs whose condition fails at some of the
        states (x (N, 3, S), poses, dq (N, S), dp (P, S) as for :meth:`clear`):
        (centre, part, first failing state) arrays, and the first state at
        which a condition fails that names no pair (a centre moved past the
        sparse gaps' cap, or their gaps are not all positive; S when none).
        The state passes :meth:`clear` exactly when no pair fails at it and
        it is before that state."""
        s = x.shape[2]
        if self._sp is not None:
            return self._failing_sparse(x, poses, dq, dp)
        dense = self._dense
        bad = self._named(x, poses, dq, dp, dense.u0h, dense.g_kn, dense.g2)
        k, i = np.nonzero(bad.any(axis=2))
        return i, k, np.argmax(bad[k, i], axis=1), s

    def _failing_sparse(self, x: np.ndarray, poses: np.ndarray, dq: np.ndarray,
                        dp: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
        """:meth:`failing` on the sparse gaps (as :meth:`_parts_clear_sparse`)."""
        s = x.shape[2]
        z = np.zeros(0, np.int64)
        if not self._ensure_sparse():
            return z, z, z, 0
        t = self._tables_for(x, poses, dq, dp)
        mk = t.mk
        centre, part, first = [z], [z], [z]
        over = dq >= t.g_still[:, None]                                # (N, S)
        stop = s
        rows = np.nonzero(over.any(axis=1))[0]
        if len(rows):
            # a centre past the cap of the unlisted pairs names no pair
            cap = dq[rows] >= t.still_cap
            if cap.any():
                stop = int(np.argmax(cap.any(axis=0)))
            # the listed entries of the centres over their least gap
            e_row, e_part, e_g = t.entries
            lo = np.searchsorted(e_row, rows, "left")
            cnt = np.searchsorted(e_row, rows, "right") - lo
            at = ranges(lo, cnt)
            bad = dq[e_row[at]] >= e_g[at, None]
            hit = bad.any(axis=1)
            centre.append(e_row[at][hit])
            part.append(e_part[at][hit])
            first.append(np.argmax(bad[hit], axis=1))
        if len(mk):
            bad = self._moved_bad(x, poses, dq, dp[mk], mk, t.u0h, t.g_kn, t.g2)
            k, i = np.nonzero(bad.any(axis=2))
            centre.append(i)
            part.append(mk[k])
            first.append(np.argmax(bad[k, i], axis=1))
        return np.concatenate(centre), np.concatenate(part), np.concatenate(first), stop

    def promote(self, centre: np.ndarray, part: np.ndarray) -> None:
        """Leave (centre, part) pairs out of the bound from now until the
        next start: the caller evaluates them itself at every state."""
        if not len(centre):
            return
        if self._sp is not None:
            self._promoted = np.union1d(self._promoted, part * len(self._pts) + centre)
            self._tables_cache = {}
            return
        dense = self._dense
        dense.g_pt[centre, part] = np.inf
        dense.g_kn[part, centre] = np.inf
        dense.g2[part, centre] = np.inf

    def clear(self, x: np.ndarray, poses: np.ndarray, dq: np.ndarray, dp: np.ndarray) -> np.ndarray:
        """Cable-structure and keep-out conditions per state (S,); x (N, 3, S)
        the centres, dq (N, S) their displacements, dp (P, S) the parts'."""
        s = x.shape[2]
        if self._sp is not None:
            return self._parts_clear_sparse(x, poses, dq, dp)
        dense = self._dense
        bad = self._named(x, poses, dq, dp, dense.u0h, dense.g_kn, dense.g2)
        return ~bad.reshape(-1, s).any(axis=0)

    def _sparse_tables(self, moved: np.ndarray) -> SparseTables:
        """The :class:`SparseTables` of the parts that moved (``moved``, (P,)
        bool), promoted pairs left out (gap inf). Kept per set of moving
        parts (the last one alone)."""
        tag = moved.tobytes()
        if tag not in self._tables_cache:
            n = len(self._pts)
            ent = self._entries
            part, row, g = ent.part, ent.row, ent.g
            if len(self._promoted):
                g = np.where(np.isin(part * n + row, self._promoted), np.inf, g)
            still = ~moved[part]
            still_cap = float(self._sp.default[~moved].min(initial=np.inf))
            # a centre whose floors are not listed yet: the horizon (every
            # floor's gap max(H, F) is at least that)
            coarse = ~self._refined()
            near = self._horizon - self._mu
            g_still = np.full(n, still_cap)
            g_still[coarse] = min(still_cap, near)
            np.minimum.at(g_still, row[still], g[still])
            o = np.argsort(row[still], kind="stable")
            entries = (row[still][o], part[still][o], g[still][o])
            mk = np.nonzero(moved)[0]
            col = np.full(len(moved), -1, np.int64)
            col[mk] = np.arange(len(mk))
            g_kn = np.repeat(self._sp.default[mk][:, None], n, axis=1)
            g_kn[:, coarse] = np.minimum(g_kn[:, coarse], near)
            on = ~still
            np.minimum.at(g_kn, (col[part[on]], row[on]), g[on])
            if len(self._promoted):
                pk, pc = self._promoted // n, self._promoted % n
                m = col[pk] >= 0
                g_kn[col[pk[m]], pc[m]] = np.inf
            u0 = (self._pts[None] - self._pos[mk, None]) @ self._rot[mk]
            u0h = np.concatenate([u0, np.ones(u0.shape[:2] + (1,))], axis=2)
            g2 = np.where(g_kn > 0, g_kn, 0.0) ** 2
            self._tables_cache = {tag: SparseTables(g_still, mk, u0h, g_kn, g2, entries, still_cap)}
        return self._tables_cache[tag]

    def _tables_for(self, x: np.ndarray, poses: np.ndarray, dq: np.ndarray, dp: np.ndarray) -> SparseTables:
        """:meth:`_sparse_tables` for these states, after listing the floors
        of every centre that fails its coarse gap (the horizon) at one of
        them: a centre's test then is what the whole table's would be."""
        moved = (dp > 0).any(axis=1)
        t = self._sparse_tables(moved)
        mk = t.mk
        need = (dq >= t.g_still[:, None]).any(axis=1)
        if len(mk):
            need |= self._moved_bad(x, poses, dq, dp[mk], mk, t.u0h, t.g_kn, t.g2, touched=True).any(axis=(0, 2))
        need &= ~self._refined()
        if need.any():
            self._refine(np.nonzero(need)[0])
            t = self._sparse_tables(moved)
        return t

    def _moved_bad(self, x, poses, dq, dp, mk, u0h, g_kn, g2, touched: bool = False) -> np.ndarray:
        """:meth:`_named` against the moved parts mk (K, N, S); ``touched``:
        every centre of a failing element instead (both of a crossing one)."""
        return self._named(x, poses[:, mk], dq, dp, u0h, g_kn, g2, touched)

    def _named(self, x: np.ndarray, poses: np.ndarray, dq: np.ndarray, dp: np.ndarray, u0h: np.ndarray,
               g_kn: np.ndarray, g2: np.ndarray, touched: bool = False) -> np.ndarray:
        """(K, N, S): centre n is named against part k (the K parts of
        ``poses`` (S, K, 4, 4), ``dp`` (K, S), the tables u0h, g_kn, g2 their
        rows) at state s: it fails both its ``rel`` and its world bound, or
        it is the first centre of an element whose two centres pass by
        different ones (the element's points are bounded by neither: package
        docstring). A state fails exactly when a centre is named at it, and
        promoting the named centres leaves no element failing."""
        s = x.shape[2]
        # every centre as it would be had it moved rigidly with part k:
        # u0h[k] (N, 4) times the poses' top rows (4, 3 S), one product per part
        top = np.transpose(poses[:, :, :3, :], (1, 3, 2, 0)).reshape(len(dp), 4, 3 * s)
        w = np.matmul(u0h, top).reshape(len(dp), len(x), 3, s)
        w -= x
        rel = np.einsum("knis,knis->kns", w, w) >= g2[:, :, None]
        if not rel.any():
            return rel
        world = (dq + dp[:, None, :]) >= g_kn[:, :, None]
        bad = rel & world
        cross = (rel[:, :-1] & world[:, 1:]) | (world[:, :-1] & rel[:, 1:])
        cross &= self._valid[None, :, None]
        bad[:, :-1] |= cross
        if touched:
            bad[:, 1:] |= cross
        return bad

    def _parts_clear_sparse(self, x: np.ndarray, poses: np.ndarray, dq: np.ndarray, dp: np.ndarray) -> np.ndarray:
        """:meth:`clear` on the sparse gaps: parts that did not move in
        these states (dp 0, so ``rel`` is ``dq``) reduce to one least gap per
        centre; the parts that moved are tested as the dense table does, on
        their own columns (both kept per set of moving parts)."""
        s = x.shape[2]
        if not self._ensure_sparse():
            return np.zeros(s, bool)
        t = self._tables_for(x, poses, dq, dp)
        mk = t.mk
        ok = (dq < t.g_still[:, None]).all(axis=0)
        if len(mk):
            ok &= ~self._moved_bad(x, poses, dq, dp[mk], mk, t.u0h, t.g_kn, t.g2).reshape(-1, s).any(axis=0)
        return ok

