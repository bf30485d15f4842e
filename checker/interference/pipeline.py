"""The interference check of one scene state, step after step: :class:`Checker`.

:func:`check_state` runs the discrete-point distance method (Ju et al., 2016)
on all cables and parts of one instant and returns one
:class:`~cablecheck.checker.records.Interference` per interfering pair. :class:`Checker`
does the same step after step for one set of parts, preparing what depends
only on the parts once; each call then takes the cables and the parts'
poses. The check is a pipeline of the package's modules: discretise
(:mod:`~cablecheck.checker.interference.discrete`), chunk (:mod:`~cablecheck.checker.interference.broad`),
cable pairs (:mod:`~cablecheck.checker.interference.cablepairs`), cables against parts
(:mod:`~cablecheck.checker.interference.structure`), bend and taut
(:mod:`~cablecheck.checker.interference.single`), reduce (:mod:`~cablecheck.checker.interference.hits`).

Deliberately not here: any distance arithmetic of its own, part-part
interference, events over time and comparison with MuJoCo.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from cablecheck.checker.interference import cablepairs, discrete, structure
from cablecheck.checker.interference.broad import Chunks
from cablecheck.checker.interference.cablepairs import cable_pairs_exact, cable_pairs_points
from cablecheck.checker.interference.discrete import DenseStates, discretise, points_error
from cablecheck.checker.interference.exclusions import ExclusionTable, exclusion_arrays
from cablecheck.checker.interference.hits import Gaps, Hits
from cablecheck.checker.interference.single import single_cable
from cablecheck.checker.interference.structure import PartTable, structure_exact, structure_points
from cablecheck.checker.records import PART_TYPES, Interference, NearMiss, PairType
from cablecheck.checker.scene_state import CableState, CheckConfig, Exclusion, PartState

_EYE3 = np.eye(3)
_EXCL_KEEP = 256
"""Cable selections whose exclusion tables a checker keeps (a full check's, and one per cable)."""


@dataclass(frozen=True)
class Checked:
    """What one check found.

    Attributes:
        records: one record per interfering (type, a, b) pair, worst first.
        gaps: with a horizon, how far every pair stayed from the clearance
            (what the skip rule of :mod:`cablecheck.checker.advance` starts from);
            None when not available (method ``exact``, face-plane, or no
            horizon).
        near_misses: method ``points``: the cable-part pairs at or past the
            clearance by less than the points may over-state
            (:meth:`Hits.near_misses`), for an exact measure to decide; no records.
    """

    records: list[Interference]
    gaps: Gaps | None
    near_misses: list[NearMiss] = field(default_factory=list)


class Checker:
    """A reusable checker for one set of parts: :func:`check_state` step after step.

    What depends only on the parts (their shapes, bounds, keep-out flags,
    mesh grouping) is prepared once; each :meth:`check` takes the cables and
    the parts' poses of one instant. ``Checker(parts, config).check(cables,
    None, exclusions)`` is exactly ``check_state(cables, parts, config,
    exclusions)``.

    Args:
        parts: the parts (names, shapes, keep-out flags; their poses are the
            default for :meth:`check`).
        config: method, spacing, clearance.
        horizon: with method ``points`` (not face-plane), candidates are also
            evaluated up to ``clearance + horizon`` (and self pairs and
            attachment windows up to ``stretch`` of arc length inside their
            exclusion), only to return with :meth:`check_with_gaps` how far
            every pair stays from the clearance (a
            :class:`~cablecheck.checker.interference.hits.Gaps` record); the records do
            not change (severity and the exclusion windows stay tied to the
            clearance). See :mod:`cablecheck.checker.advance` for the use.
        stretch: see ``horizon``.
    """

    def __init__(self, parts: Sequence[PartState], config: CheckConfig = CheckConfig(),
                 horizon: float = 0.0, stretch: float = 0.0):
        self.parts = list(parts)
        self.config = config
        self._tab = PartTable(self.parts) if self.parts else None
        self._pidx = {p.name: i for i, p in enumerate(self.parts)}
        self.horizon = float(horizon)
        self.stretch = float(stretch)
        self._excl_cache: dict = {}

    @property
    def bounds_gaps(self) -> bool:
        """True when :meth:`check_with_gaps` returns gaps (points, not face-plane, horizon > 0)."""
        return self.config.method == "points" and not self.config.face_plane and self.horizon > 0.0

    def part_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """((K, 3), (K, 3)): each part's axis-aligned bounds in its own frame
        (a plane: lo -inf, hi (inf, inf, 0))."""
        if self._tab is None:
            return np.zeros((0, 3)), np.zeros((0, 3))
        return self._tab.lo.copy(), self._tab.hi.copy()

    def part_radius(self) -> np.ndarray:
        """(K,) largest distance of any point of each part from its frame's
        origin (inf for planes): a rotation by R moves it at most ||R - R0|| times this."""
        lo, hi = self.part_bounds()
        corner = np.maximum(np.abs(lo), np.abs(hi))
        return np.sqrt(np.einsum("ij,ij->i", corner, corner))

    def _exclusion_table(self, cable_names: Sequence[str], exclusions: Sequence[Exclusion]) -> ExclusionTable:
        """The windows of these cables against this checker's parts
        (:meth:`~cablecheck.checker.interference.exclusions.ExclusionArrays.table`)."""
        # a run passes the same windows at every check: the list's arrays are
        # built once, and the last few cable selections are kept
        arrays = exclusion_arrays(exclusions)
        names = tuple(cable_names)
        cache = self._excl_cache
        if cache.get("arrays") is not arrays:
            cache.clear()
            cache["arrays"] = arrays
            cache["parts"] = arrays.part_map(self._pidx)
        table = cache.get(names)
        if table is None:
            table = arrays.table(names, cache["parts"], len(self.parts))
            if len(cache) > _EXCL_KEEP:
                del cache[next(k for k in cache if isinstance(k, tuple))]
            cache[names] = table
        return table

    def densify_many(self, pts: np.ndarray, offsets: np.ndarray, radii: np.ndarray,
                     rest: np.ndarray | None = None, keep: np.ndarray | None = None) -> DenseStates:
        """:func:`cablecheck.checker.interference.discrete.densify_many` at this checker's spacing."""
        return discrete.densify_many(pts, offsets, radii, self.config.spacing, rest, keep)

    def near_entries(self, pts: np.ndarray, poses: np.ndarray, offsets: np.ndarray, radii: np.ndarray,
                     active: tuple[np.ndarray, np.ndarray], near_errors: np.ndarray | None = None
                     ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """:func:`cablecheck.checker.interference.structure.near_entries` on this
        checker's parts at its clearance (plus the largest of ``near_errors``,
        (C,), where :meth:`structure_many` looks for near misses too): the
        (state, centre, part) entries of :meth:`structure_many` whose points
        may come near the part, for body centres pts (S, N, 3) of cables
        ``offsets`` (C + 1,) and ``radii`` (C,), the parts' poses (S, K, 4, 4)."""
        if self._tab is None:
            z = np.zeros(0, np.int64)
            return z, z, z
        cable = np.repeat(np.arange(len(offsets) - 1), np.diff(offsets))
        limit = self.config.clearance + (0.0 if near_errors is None else float(np.max(near_errors, initial=0.0)))
        return structure.near_entries(self._tab, pts, poses, cable[:-1] == cable[1:],
                                      np.asarray(radii, float)[cable], limit, active)

    def structure_many(self, names: Sequence[str], radii: np.ndarray, dense: DenseStates,
                       poses: np.ndarray, exclusions: Sequence[Exclusion],
                       active: tuple[np.ndarray, ...], near_errors: np.ndarray | None = None):
        """:func:`cablecheck.checker.interference.structure.structure_many` on this checker's parts."""
        excl = self._exclusion_table(names, exclusions).excl if self._tab is not None else None
        return structure.structure_many(self._tab, self.config, excl, names, radii, dense, poses, active,
                                        near_errors)

    def cable_pairs_many(self, names: Sequence[str], radii: np.ndarray, dense: DenseStates,
                         active: tuple[np.ndarray, np.ndarray]) -> list[list[Interference]]:
        """:func:`cablecheck.checker.interference.cablepairs.cable_pairs_many` at this checker's clearance."""
        return cablepairs.cable_pairs_many(self.config.clearance, names, radii, dense, active)

    def check(
        self,
        cables: Sequence[CableState],
        poses: np.ndarray | Sequence[np.ndarray] | None = None,
        exclusions: Sequence[Exclusion] = (),
        horizon: float | None = None,
    ) -> list[Interference]:
        """Check one scene state; see :func:`check_state` and :meth:`check_with_gaps`."""
        return self.check_with_gaps(cables, poses, exclusions, horizon).records

    def check_with_gaps(
        self,
        cables: Sequence[CableState],
        poses: np.ndarray | Sequence[np.ndarray] | None = None,
        exclusions: Sequence[Exclusion] = (),
        horizon: float | None = None,
    ) -> Checked:
        """Check one scene state: its records and, with a horizon, its gaps.

        Args:
            cables: the cables' centrelines.
            poses: (K, 4, 4) part -> world transforms in the order of the
                parts, or None for the parts' own poses. Rotations must be
                orthonormal (as :class:`~cablecheck.checker.scene_state.PartState`
                requires).
            exclusions: arc-length windows where a cable may touch a part.
            horizon: this call's horizon instead of the checker's (0: no
                gaps, the plain check).
        """
        config = self.config
        horizon = self.horizon if horizon is None else float(horizon)
        bounded = self.bounds_gaps and horizon > 0.0
        parts = self.parts
        tab = None
        if self._tab is not None:
            if poses is not None:
                poses = np.asarray(poses, dtype=float).reshape(-1, 4, 4)
                if len(poses) != len(parts) or not np.all(np.isfinite(poses)):
                    raise ValueError(f"poses must be {len(parts)} finite 4x4 matrices")
                rot = poses[:, :3, :3]
                # np.allclose(R^T R, I, atol=1e-9) without its per-call overhead
                err = np.abs(np.einsum("kji,kjl->kil", rot, rot) - _EYE3)
                if not np.all(err <= 1e-9 + 1e-5 * _EYE3):
                    raise ValueError("a pose rotation is not orthonormal")
            tab = self._tab.posed(poses)
        hits = Hits()
        cable_names = [c.name for c in cables]
        part_names = [p.name for p in parts]
        if len(set(cable_names)) != len(cable_names):
            raise ValueError("cable names must be unique")
        if cables:
            table = self._exclusion_table(cable_names, exclusions)
            excl, ex_c, ex_lo, ex_hi = table.excl, table.cable, table.lo, table.hi
            exact = config.method == "exact"
            cuts = (np.concatenate([ex_c, ex_c]), np.concatenate([ex_lo, ex_hi])) if exact \
                else (np.zeros(0, np.int64), np.zeros(0))
            errors = near_miss_errors(cables, config)
            dp = discretise(cables, config, cuts)
            has_next = np.concatenate([dp.cable[:-1] == dp.cable[1:], [False]])
            limit = config.clearance + (horizon if bounded else 0.0)
            reach = 2.0 * float(dp.radius.max()) + (config.clearance if exact else limit)  # of the cable pairs
            if exact:
                ch = Chunks(dp.p, dp.s, dp.cable, has_next, dp.seg, reach)
                cable_pairs_exact(dp, ch, config.clearance, hits)
            else:
                ch = Chunks(dp.p, dp.s, dp.cable, has_next, np.arange(len(dp.p)), reach)
                cable_pairs_points(dp, ch, config.clearance, hits, limit, self.stretch if bounded else 0.0)
            if tab is not None:
                if exact:
                    structure_exact(dp, ch, tab, config, excl, hits)
                else:
                    # windows narrowed by the stretch: points that may enter
                    # or leave a window bound the gaps too
                    near = (excl[0], excl[1] + self.stretch, excl[2] - self.stretch, excl[3]) if bounded else None
                    # up to the points' own error farther: the near misses, and the gaps counted
                    # from the clearance plus that error (Hits.gaps)
                    structure_points(dp, ch, tab, config, excl, hits, limit + float(errors.max(initial=0.0)), near)
            single_cable(cables, config.clearance, hits)
        found = hits.gaps(config.clearance, horizon, len(parts), errors if cables else None) if bounded else None

        def names(ptype: PairType) -> list[str]:
            return part_names if ptype in PART_TYPES else cable_names

        near_misses = hits.near_misses(config.clearance, errors, cable_names, part_names) \
            if cables and errors.max(initial=0.0) > 0.0 else []
        return Checked(hits.records(config.clearance, cable_names, names), found, near_misses)


def cable_cable_exact(cables: Sequence[CableState], config: CheckConfig) -> list[Interference]:
    """The cable-cable records :meth:`Checker.check` gives these cables with
    method exact and no parts, to the bit, without their self pairs, bends
    or tautness (a second opinion on one pair of cables: the search along
    each cable was most of its cost)."""
    config = CheckConfig(method="exact", spacing=config.spacing, clearance=config.clearance)
    hits = Hits()
    if len(cables) > 1:
        dp = discretise(cables, config, (np.zeros(0, np.int64), np.zeros(0)))
        has_next = np.concatenate([dp.cable[:-1] == dp.cable[1:], [False]])
        ch = Chunks(dp.p, dp.s, dp.cable, has_next, dp.seg, 2.0 * float(dp.radius.max()) + config.clearance)
        cable_pairs_exact(dp, ch, config.clearance, hits, self_pairs=False)
    names = [c.name for c in cables]
    return hits.records(config.clearance, names, lambda _: names)


def near_miss_errors(cables: Sequence[CableState], config: CheckConfig) -> np.ndarray:
    """(C,) per cable, how far past the clearance a cable-part pair may read by
    method ``points`` and still be inside it (:func:`points_error`); 0 for
    method ``exact`` and the paper's face-plane distance (no near misses)."""
    if config.method != "points" or config.face_plane:
        return np.zeros(len(cables))
    return np.array([points_error(c.radius, config.spacing) for c in cables], float)


def check_state(
    cables: Sequence[CableState],
    parts: Sequence[PartState],
    config: CheckConfig = CheckConfig(),
    exclusions: Sequence[Exclusion] = (),
) -> list[Interference]:
    """Check one scene state; one record per interfering (type, a, b) pair.

    A pair interferes when its signed ``min_distance`` (SPEC "Report") is
    below ``config.clearance``: hard below 0, soft from 0 up to the
    clearance. Records are sorted worst first. To check many states of the
    same parts, :class:`Checker` prepares the parts once.

    Args:
        cables: the cables' centrelines.
        parts: posed parts (keep-out parts give ``keepout`` records).
        config: method, spacing, clearance.
        exclusions: arc-length windows where a cable may touch a part.

    Returns:
        list of :class:`~cablecheck.checker.records.Interference`.
    """
    return Checker(parts, config).check(cables, None, exclusions)
