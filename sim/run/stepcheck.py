"""The checks of a run, a batch of consecutive step states at a time.

For every state: the cables' lengths and smallest bend radii, and the
records a full check would return, compared with MuJoCo's own contacts for
the same positions when the scene validates. States the skip rule proves clear
(:mod:`cablecheck.checker.advance`) get only their single-cable records (bend, taut),
the replayed same-body part records and the records of the *active* pairs:
pairs that were inside (or within a tenth of the horizon of) the clearance
at the last full check, which the skip rule leaves out and which are
checked on their own (a cable lying on an arm link or held in a part just
inside its attachment window, two leads crossing, a table just under a
robot base or a hinge pin through its knuckles would otherwise stop all
skipping; a part pair is checked whole, as the full check would). Pairs
whose bound fails after a full check join them (*promoted*: a cable
sliding towards one part, two leads drawing near) while they are few
(``PROMOTE_SHARE``, ``PROMOTE_MIN``), so the cost of a step grows with
what came near, not with the scene. The other states are checked in full.

Why batches: a cable has a few dozen body centres, so numpy's cost per call,
not the arrays' size, is what a step costs. The skip rule and the measures
are evaluated for the whole batch in one vectorised pass; after a full
check the states behind it are tested again against it. The answers are
those of checking the states one at a time, in order.

This module does not step the simulation, track events, record or report
(see :mod:`cablecheck.run.runner`); it only needs the simulation to detect contacts.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from typing import Protocol

import numpy as np

from cablecheck.build.built import Built
from cablecheck.build.checkview import DEFAULT_PRECISION_M, part_set, part_shapes, selection, start_part_poses
from cablecheck.checker.advance import Advancement, PartSolids, part_pair_bounds
from cablecheck.checker.advance.partpairs import PartPairGaps
from cablecheck.checker.cable import CableMeasures, rest_pieces, taut_margin
from cablecheck.checker.events import AllowList, AllowRule
from cablecheck.checker.interference import Checker, single_records_many
from cablecheck.checker.interference.discrete import around_centres, points_error
from cablecheck.checker.interference.excused import ExcusedLog, ExcusedWorst
from cablecheck.checker.interference.margins import Closest, MarginLog
from cablecheck.checker.interference.structure import PartTable, point_distances
from cablecheck.checker.parts import PartChecker
from cablecheck.checker.recheck import Recheck, cables_by_state
from cablecheck.checker.interference.hits import record_order
from cablecheck.checker.records import PART_TYPES, Interference, PairType
from cablecheck.checker.refine import (
    deepest_candidates,
    near_miss_records,
    refined_cable_records,
    refined_records,
    refined_self_records,
)
from cablecheck.checker.scene_state import CableState, CheckConfig, Exclusion, PartState
from cablecheck.checker.shapes import Shape
from cablecheck.checker.validation import SimulatorPairs, Validation, ValidationSummary
from cablecheck.detection.contacts import Contacts, RawContacts
from cablecheck.detection.hullgap import HullGaps
from cablecheck.detection.mesh import hull_parts
from cablecheck.report.document import AdvanceOutcome
from cablecheck.run.loop import StepState
from cablecheck.scene.allow import covers

BATCH = 32
"""Consecutive states checked together at the start of a run (a run's states
arrive this many at a time); each later batch doubles, up to :data:`BATCH_MAX`."""

BATCH_MAX = 256
"""The longest batch. A proven-clear state costs mostly numpy's per-call
overhead of the batch's calls (the bound, measures, twist, active pairs), so
it shrinks as the batch grows (the door scene's check per step with fixed
batches of 32 states 1.0, 64 0.86, 128 0.77, 256 0.73, side by side in one
run on a loaded machine; the robot cell's check 0.68-0.70 s with batches of
at most 128, 0.61-0.67 s with 256, 0.59-0.62 s with 512, three runs each
side by side, but 512 leaves more of the run's last batch to check after
the simulation ends). A stop request waits for the batch being checked:
the first batches stay short so a run stopped early stops at once, and a
run's last batch, or an interrupted one's, is shorter."""


def next_batch(size: int, steps_left: int, every: int = 1, least: int = BATCH, most: int = BATCH_MAX) -> int:
    """The next batch's length after one of `size` states, with `steps_left`
    simulation steps still to come (a state every `every` steps): twice the
    last, up to `most`, but at most half the states still to come (and
    never under `least`), so the batches shrink towards the run's end. The
    states of a run's last batch can only be checked once the simulation
    has made them all: with the simulation stepped ahead
    (:mod:`cablecheck.run.ahead`) that check is the run's tail, and on the
    zoo's Fetch a last batch of 185 states took 0.27 s after the simulation
    had ended. Any batch length gives the same answers
    (tests/test_stepcheck.py)."""
    states_left = -(-max(int(steps_left), 0) // max(int(every), 1))
    return max(least, min(2 * size, most, -(-states_left // 2)))


ADVANCE_HORIZON_RADII = 2.0
"""Conservative advancement: candidates are evaluated up to the clearance
plus this many (largest) cable radii at a full check..."""

ACTIVE_RESTARTS = 32
"""Restarts of the active part pairs' condition in one batch of proven-clear
states (`StepChecks._active_part_records`): pairs that keep near the clearance
are then checked at their failing states in one call."""

ACTIVE_HORIZONS = 0.1
"""Cable-structure, keep-out, self and cable-cable pairs whose gap at a full
check is below this many horizons, and moving part pairs whose box bound is,
are *active*: checked on their own at every state instead of bounding the
skip (cablecheck.checker.advance)."""

PROMOTE_SHARE = 1.0
"""Pairs whose bound fails after a full check are checked on their own
(promoted, :meth:`cablecheck.checker.advance.Advancement.clear_run_local`) until the
next full check, while they number at most this share of the body centres;
past it a full check costs less. Measured (2026-11-29): at 0.25, 29 of the
50 full checks of the crossing harness (cablecheck.bench.crossing, 64 x
1,000, 2,624 centres) ended on it, each about 95 ms; at 1.0 none, 35 full
checks, its check 17.6 -> 16.4 s (2.0: the same 35); the lattice harness 8
-> 6 full checks, 3.29 -> 3.09 s; a hose on an arm (under PROMOTE_MIN
centres) is unchanged."""

PROMOTE_MIN = 64
"""... and at least this many whatever the scene's size: a few dozen pairs
evaluated at every state cost a batch about what one does (numpy's
per-call overhead), far less than the full checks they spare a small scene
(the door scene: 5 full checks with a budget of 5 pairs, 1 with 64)."""

CHUNK_POINTS = 1_000_000
"""The discrete points (summed over states) the states proven clear are
evaluated in at most at once: a long cable lying on a part keeps its every
point active, and a batch of 256 states of a 150 m wire at 1 mm spacing
would hold 38 million points (gigabytes) in one pass. Fewer states a pass
give the same records: each proven-clear state is evaluated on its own."""

MARGIN_INTERVAL = 0.05
"""Closest approaches (:class:`cablecheck.checker.interference.margins.MarginLog`)
are sampled about this often in simulated seconds (and at a batch's first
and last state), then refined around each pair's best sample: on the robot
cell a sampled state costs about as much as ten proven clear ones."""

ALLOWED_INTERVAL = MARGIN_INTERVAL
"""Allowed part-part pairs (`[[allow]]`: a table turning on its bearing, a
hinge pin in its knuckles) are measured at the first checked state of each
interval of this many simulated seconds, not at every state: they make no
event, and the report keeps only each one's worst over those states
(`allowed`, with this interval). A mesh ring turning on a cylinder it sits
5 mm into (thousands of crossing triangle pairs at every state) made the
checks of a rotary table 27 times its simulation; a pair's worst between
two samples may be missed, as the closest approaches' may."""

MARGIN_REACH_CLEARANCES = 3.0
"""Closest approaches are kept out to this many clearances ..."""

MARGIN_REACH_RADII = 2.0
"""... and at least this many of the largest cable radii (a scene whose
clearance is 0 still reports its margins)."""

ADVANCE_STRETCH_RADII = 1.0
"""... and up to this many (smallest) cable radii of arc length inside the
exclusion windows (the total change of element lengths a skipped step allows).
Why 1 and not the 0.25 of earlier rounds: a hose whose tension varies (the
zoo's Fetch, taut in its moves) changed its elements' lengths by more than a
quarter radius every few dozen steps, and each time a full check followed (45
on the Fetch, 16 at 1.0, 14 at 2.0; taut_pull 27 -> 19); the wider windows
cost the 64 x 1,000 harness nothing measurable (check 3.4-3.7 s a simulated
second either way) and no record changes (the examples' reports identical but
for this number)."""


class Detector(Protocol):
    """MuJoCo's own contacts for a state (see :class:`cablecheck.detection.detector.Detector`)."""

    def collide_many(self, qposes: list[np.ndarray], poses: tuple[np.ndarray, np.ndarray] | None = None
                     ) -> list[RawContacts]: ...

    def read_many(self, raws: list[RawContacts]) -> list[Contacts]: ...


@dataclass(frozen=True)
class StepResult:
    """What the checks found at one state.

    Attributes:
      records: every record of the step (cable and part records).
      cable_records: the cable records alone (what validation compares).
      strain: (C,) per cable, length over rest length minus 1.
      bend: (C,) per cable, smallest bend radius, m.
      full: the pairwise checks ran (False: proven clear).
      contacts: MuJoCo's contacts at this state when it was validated.
      agreement: the validation's agreement at this state, or None.
      near: at a full check with the skip rule, every candidate the checker
        evaluated up to its horizon, as ((cable, s, part, value - clearance)
        for parts, (cable a, s_a, cable b, s_b, value - clearance) for cable
        pairs; built part indices, metres), else None.
      near_misses: method points: the cable-part pairs read at or past the
        clearance by less than the points' error (no records: `StepChecks.run`
        measures them with method exact, and leaves them empty).
    """

    records: list[Interference]
    cable_records: list[Interference]
    strain: np.ndarray
    bend: np.ndarray
    full: bool
    contacts: Contacts | None = None
    agreement: float | None = None
    near: tuple | None = None
    near_misses: tuple = ()


@dataclass(frozen=True)
class _PairsAt:
    """Part pairs split at a full check (`StepChecks._records_at`): their parts
    (used), all parts' poses there and the memo slot their records are checked
    in (`StepChecks._pair_records`)."""

    used: np.ndarray
    poses: np.ndarray
    slot: str


@dataclass(frozen=True)
class ApartPair:
    """An active part pair apart, as last measured (`StepChecks._pair_gaps`).

    Attributes:
        a, b: its parts (built indices).
        gaps: its part-pair condition, started there.
        axis: the world direction its convex hulls were found apart along
            there (from b's to a's), or None (measured by its triangles).
        at: (P, 4, 4) the poses there.
    """

    a: int
    b: int
    gaps: PartPairGaps
    axis: np.ndarray | None
    at: np.ndarray


@dataclass(frozen=True)
class ChecksOutcome:
    """What a run's checks say at its end, beside their events.

    Attributes:
      advance: the skip rule's distances and counts, or None when it was off.
      validation: the comparison with MuJoCo's contacts, or None when off.
      part_warnings: what preparing the parts found (open meshes, ...).
      hull_warnings: cables the simulation held on a concave part's convex hull.
      excused: every attachment window that came below the clearance of
        the part it excuses, with its worst moment.
      closest: every cable-part and cable-cable pair that came within
        ``margin_reach``, with its closest approach (sampled, see
        :data:`MARGIN_INTERVAL`).
      margin_reach, margin_interval: how far and how often closest
        approaches were measured (metres, seconds).
      allowed_interval: how often allowed part-part pairs were measured
        (seconds: :data:`ALLOWED_INTERVAL`).
    """

    advance: AdvanceOutcome | None
    validation: ValidationSummary | None
    part_warnings: tuple[str, ...]
    hull_warnings: tuple[str, ...]
    excused: tuple[ExcusedWorst, ...] = ()
    closest: tuple[Closest, ...] = ()
    margin_reach: float = 0.0
    margin_interval: float = MARGIN_INTERVAL
    allowed_interval: float = ALLOWED_INTERVAL


class StepChecks:
    """Everything prepared once for checking a built scene's states.

    Args:
      built: the built scene.
      config: method, spacing and clearance.
      only: an assembly path for ``--only`` (see :class:`cablecheck.run.runner.RunOptions`), or None.
      advance: use the skip rule.
      detector: MuJoCo's detection (``collide_many(qposes, poses)`` for a
        batch's states and their body poses, then ``read_many(raws)`` to
        name their contacts: a :class:`cablecheck.detection.detector.Detector`), or None (no
        validation).
      lap: lap(stage) ends a timed stage ("check", "sim", "validate").
    """

    def __init__(self, built: Built, config: CheckConfig, only: str | None, advance: bool,
                 detector: Detector | None,
                 lap: Callable[[str], None] = lambda stage: None):
        scene = built.scene
        self.built = built
        self.config = config
        self.detector = detector
        self.lap = lap
        self.shapes = shapes = part_shapes(built)
        # Rigid parts against each other: prepared once, same-body pairs checked once.
        self.rigid = rigid = part_set(built, tolerance=DEFAULT_PRECISION_M, shapes=shapes)
        focus = selection(rigid, only, "--only") if only is not None else None
        skipped_pairs = part_pairs_skipped(built)
        self.part_checker = PartChecker(rigid, scene.check.clearance, focus, skipped_pairs)
        self.exclusions = attachment_exclusions(built, shapes)
        # With --only, cables are checked against that assembly's parts alone.
        self.checked_parts = checked = (np.ones(len(built.parts), bool) if focus is None
                                        else np.asarray(focus, bool))
        self.focus_names = None if focus is None else {p.name for p, keep in zip(built.parts, checked) if keep}
        offsets = np.concatenate([[0], np.cumsum([c.count for c in built.cables])])  # cable starts in pts
        # material coordinate (rest arc length) of every body centre: the exclusion windows' measure
        self._rest = np.concatenate([c.rest_s for c in built.cables]) if built.cables else np.zeros(0)
        radii = np.array([c.radius for c in built.cables], float)
        self.horizon = ADVANCE_HORIZON_RADII * float(radii.max()) if (advance and len(radii)) else 0.0
        self.stretch = ADVANCE_STRETCH_RADII * float(radii.min()) if len(radii) else 0.0
        # Parts prepared once; each state passes their poses.
        self.checker = Checker([PartState(p.name, sh, np.eye(4), p.keepout)
                                for p, sh, keep in zip(built.parts, shapes, checked) if keep], config,
                               horizon=self.horizon, stretch=self.stretch)
        self.advance: Advancement | None = None
        self._apart_gaps: list[ApartPair] = []   # one condition per active pair apart (`_pair_gaps`)
        self._pair_gaps_args: tuple = ()            # the parts' radii and solids, with the skip rule
        self._active_split = False                  # the active pairs split at a full check
        self._value_memo: dict[tuple[int, int], tuple] = {}   # (i, j) -> poses of i, j and their value
        self._pair_records_memo: dict[str, tuple] = {}  # slot -> its last pairs, their parts' poses, records
        # the active part pairs within the clearance at the last full check, and apart
        self._active_near = self._active_apart = (np.zeros(0, np.int64), np.zeros(0, np.int64))
        # the allowed ones among them, measured at the sampled states alone (ALLOWED_INTERVAL)
        self._allowed_near = (np.zeros(0, np.int64), np.zeros(0, np.int64))
        self._allowed_start = _PairsAt(np.zeros(0, np.int64), np.zeros((0, 4, 4)), "allowed")
        self._allowed_memo: dict[tuple[str, str], bool] = {}   # (a, b) part names -> an allowed pair
        self._allowed_slot = np.nan         # the ALLOWED_INTERVAL slot of the last state checked
        # the near pairs' parts, their poses and records where they were split (`_start_active_gaps`)
        self._near_start = _PairsAt(np.zeros(0, np.int64), np.zeros((0, 4, 4)), "near")
        if self.checker.bounds_gaps:
            corner = np.maximum(np.abs(rigid.lo), np.abs(rigid.hi))
            rho = np.sqrt(np.einsum("ij,ij->i", corner, corner))     # inf for planes
            rho[checked] = np.maximum(rho[checked], self.checker.part_radius())
            box_lo = np.full((len(built.parts), 3), -np.inf)
            box_hi = np.full((len(built.parts), 3), np.inf)
            box_lo[checked], box_hi[checked] = self.checker.part_bounds()
            # part pairs: boxes holding both what the part-part check and the cable check measure
            solid_lo, solid_hi = rigid.lo.copy(), rigid.hi.copy()
            solid_lo[checked] = np.minimum(solid_lo[checked], box_lo[checked])
            solid_hi[checked] = np.maximum(solid_hi[checked], box_hi[checked])
            solids = PartSolids(solid_lo, solid_hi, rigid.axial, rigid.error, rigid.group_index)
            self.advance = Advancement(offsets, config.spacing * radii, rho, config.clearance,
                                       self.stretch, radii, (box_lo, box_hi), solids,
                                       rest_pieces(self._rest, offsets, config.spacing * radii))
            # the active part pairs' own conditions, one a pair, restarted from their measured distances
            # (no group boxes: a pair's own tests are tighter than its bodies', and cost less alone)
            self._pair_gaps_args = (rho, replace(solids, group=None))
            self._moving_pairs = self.part_checker.moving_pairs()
            self._checked_index = np.nonzero(checked)[0]
            self._checker_index = np.cumsum(checked) - 1          # built part -> checker part
        # (centre, checker part) entries of the active pairs (see ACTIVE_HORIZONS)
        # at the last full check: evaluated on their own at every state proven clear
        self._active: tuple[np.ndarray, np.ndarray] = (np.zeros(0, np.int64), np.zeros(0, np.int64))
        self._cable_active = (np.zeros(0, np.int64), np.zeros(0, np.int64))    # (centre, centre)
        # moving part pairs within ACTIVE_HORIZONS of the clearance at the last
        # full check (a table just under a robot base, a hinge pin through its
        # knuckles): left out of the bound, checked on their own at every state
        self._part_active = (np.zeros(0, np.int64), np.zeros(0, np.int64))
        self._names = [c.name for c in built.cables]
        self._offsets = offsets
        self._budget = max(int(PROMOTE_SHARE * offsets[-1]), PROMOTE_MIN)
        self._radii = radii
        # what the attachment windows leave out of the checks, measured on its own
        self.excused = ExcusedLog(self.exclusions, self.checker.parts, self._names, offsets, self._rest, radii,
                                  config.clearance)
        # every pair's closest approach within the reach, clash or not
        self.margin_reach = max(MARGIN_REACH_CLEARANCES * config.clearance,
                                MARGIN_REACH_RADII * float(radii.max()) if len(radii) else 0.0)
        self.margins = MarginLog(self.checker.parts, self._names, offsets, self._rest, radii, self.exclusions,
                                 self.margin_reach, config)
        self.allow = AllowList(AllowRule(r.a, r.b, r.reason) for r in scene.allow)
        self._simulator_pairs = SimulatorPairs(self.exclusions, config.clearance)
        self.validation = Validation(scene.check.clearance, config.method,
                                     hull_parts(built.parts, built.detect),
                                     allow=self.allow)
        self.hull_gaps = HullGaps(built) if detector is not None else None   # cables held on a hull
        self._recheck = Recheck(self.checker.parts, config, self.exclusions, held_element_exclusions(built))
        self._points_error = {c.name: points_error(c.radius, config.spacing) for c in built.cables}
        self._least_hard: dict[tuple, float] = {}       # each pair's least hard value in its run so far
        # how far past the clearance a cable-part pair may read and still be inside it (method points)
        self._near_errors = (np.array([self._points_error[n] for n in self._names], float)
                             if config.method == "points" and not config.face_plane else None)
        self._measures = CableMeasures(offsets)
        self._rest_length = np.array([c.length for c in built.cables], float)
        limit = np.array([np.inf if c.min_bend_radius is None else c.min_bend_radius
                          for c in built.cables], float)
        self._bend_limit = limit
        self._bend_limit_nan = np.where(np.isfinite(limit), limit, np.nan)
        self._has_bend_limit = np.isfinite(limit)
        # states a proven-clear pass takes at most (CHUNK_POINTS): a state's discrete points at rest
        per_state = float(np.sum(self._rest_length / (config.spacing * radii))) + len(radii) if len(radii) else 1.0
        self._chunk = max(1, int(CHUNK_POINTS // max(per_state, 1.0)))

    def run(self, states: Sequence[StepState]) -> list[StepResult]:
        """Check consecutive states (oldest first); one result per state, in order."""
        if not states:
            return []
        pts = np.stack([np.concatenate(s.cables) if s.cables else np.zeros((0, 3)) for s in states])
        poses = np.stack([s.part_poses for s in states])
        lengths, bend, radius_at = self._measures.many(pts, at_points=True)
        strain = lengths / self._rest_length - 1.0
        # a full check's single-cable records: none unless a bend is within
        # the clearance of its limit or a cable is taut
        # (a cable without a limit compares with 0: a straight one's inf - inf is no number)
        single = (((bend - np.where(self._has_bend_limit, self._bend_limit, 0.0) < self.config.clearance)
                   & self._has_bend_limit).any(axis=1)
                  | (taut_margin(lengths, self._rest_length) < 0.0).any(axis=1))
        sampled = self._allowed_samples(states)
        out: list[StepResult] = []
        j = 0
        while j < len(states):
            k = 0
            if self.advance is not None:
                cleared = self.advance.clear_run_local(pts[j:], poses[j:], self._budget)
                k = cleared.states
                centre, built_part = cleared.active.structure
                self._active = (centre, self._checker_index[built_part])   # (centre, checker part)
                self._cable_active = cleared.active.cable
            for lo in range(j, j + k, self._chunk):     # at most CHUNK_POINTS points a pass
                part = slice(lo, min(lo + self._chunk, j + k))
                out += self._proven_clear(states[part], pts[part], poses[part], single[part],
                                          radius_at[part], strain[part], bend[part],
                                          None if sampled is None else sampled[part])
            j += k
            if j < len(states):
                out.append(self._full(states[j], pts[j], poses[j], strain[j], bend[j]))
                j += 1
        if sampled is not None:
            out = self._allowed_sampled(out, sampled)
        out = self._refined(states, pts, poses, out)
        times = np.array([s.t for s in states])
        if self.excused:
            self.excused.add(times, pts, poses[:, self.checked_parts])
        self.margins.add(times, pts, poses[:, self.checked_parts], margin_samples(times, MARGIN_INTERVAL))
        self.lap("check")
        if self.detector is not None:
            return self._validate(states, pts, out)
        return out

    def _allowed_samples(self, states: Sequence[StepState]) -> np.ndarray | None:
        """(S,) bool: the states of a batch at which allowed part-part pairs
        are measured, the first checked in each ALLOWED_INTERVAL of simulated
        time (on one grid over the run, so batches, chunks and full checks
        do not move them); None when the scene allows no pair."""
        if not self.allow:
            return None
        slot = np.floor(np.array([s.t for s in states], float) / ALLOWED_INTERVAL)
        before = np.r_[self._allowed_slot, slot[:-1]]
        self._allowed_slot = float(slot[-1])
        return slot != before                  # NaN before the first state: it is sampled

    def _allowed_part(self, a: str, b: str) -> bool:
        """Parts `a` and `b` are an allowed part-part pair (`[[allow]]`)."""
        hit = self._allowed_memo.get((a, b))
        if hit is None:
            hit = self._allowed_memo[(a, b)] = self.allow.match((PairType.PART_PART, a, b)) is not None
        return hit

    def _allowed_sampled(self, results: list[StepResult], sampled: np.ndarray) -> list[StepResult]:
        """`results` without the allowed part-part pairs' records at the states
        not sampled (ALLOWED_INTERVAL): the same whether a state was checked
        in full or proven clear, so the skip rule changes no answer."""
        out = list(results)
        for i in np.flatnonzero(~sampled).tolist():
            res = out[i]
            drop = [r for r in res.records if r.type == PairType.PART_PART and self._allowed_part(r.a, r.b)]
            if drop:
                gone = {id(r) for r in drop}
                out[i] = replace(res, records=[r for r in res.records if id(r) not in gone])
        return out

    def _refined(self, states: Sequence[StepState], pts: np.ndarray, poses: np.ndarray,
                 results: list[StepResult]) -> list[StepResult]:
        """Method ``points``: its soft cable-part records within the method's
        own error of touching replaced by method ``exact``'s
        (:func:`cablecheck.checker.refine.refined_records`): a hose resting on a link
        reads as touching it, as MuJoCo's contact says, not a fraction of a
        millimetre off; and its near misses, the pairs it reads just past the
        clearance, measured with method ``exact`` too, a record where that
        finds them inside (:func:`cablecheck.checker.refine.near_miss_records`)."""
        if self.config.method != "points":
            return results
        by_state = cables_by_state(self._cable_states(states[0]), pts)   # a cable made where a record asks
        cables = by_state.__getitem__

        placed = poses[:, self.checked_parts]
        records = [r.cable_records for r in results]
        # the hard records deepest by the points so far in their pair's run, the least carried
        # from batch to batch (`deepest_candidates`)
        deepest, self._least_hard = deepest_candidates(
            records, PART_TYPES + (PairType.CABLE_CABLE, PairType.SELF), self._least_hard)
        swaps = refined_records(records, cables, placed, self._recheck, self._points_error, deepest)
        if len(self._names) > 1:          # two hoses pressed together: their soft records measured again too
            for swap, more in zip(swaps, refined_cable_records(records, cables, self.config.clearance, deepest)):
                swap.update(more)
        if "self" in self.built.scene.effects.contact:      # and a cable pressed on its own turns
            for swap, more in zip(swaps, refined_self_records(records, cables, self.config.clearance, deepest)):
                swap.update(more)
        found = near_miss_records([r.near_misses for r in results], cables, placed, self._recheck)
        out = []
        for res, swap, more in zip(results, swaps, found):
            if more:           # the pairs exact found inside the clearance, in the records' order
                cable_ids = {id(r) for r in res.cable_records}
                cable_records = sorted([swap.get(id(r), r) for r in res.cable_records] + more, key=record_order)
                res = replace(res, records=cable_records + [r for r in res.records if id(r) not in cable_ids],
                              cable_records=cable_records)
            elif swap:
                res = replace(res, records=[swap.get(id(r), r) for r in res.records],
                              cable_records=[swap.get(id(r), r) for r in res.cable_records])
            out.append(replace(res, near_misses=()) if res.near_misses else res)
        return out

    def _validate(self, states: Sequence[StepState], pts: np.ndarray,
                  results: list[StepResult]) -> list[StepResult]:
        """`results` with MuJoCo's contacts at every state and their agreement
        with its cable records (complete on a proven-clear step too: every
        other pair is clear); the contacts reduced to pairs for all the
        states at once."""
        # MuJoCo's collision pass on the detection model is validation work, timed as such
        # the body poses the simulation computed at each state, when it kept them
        poses = ((np.stack([s.xpos for s in states]), np.stack([s.xmat for s in states]))
                 if all(s.xpos is not None and s.xmat is not None for s in states) else None)
        raws = self.detector.collide_many([state.qpos for state in states], poses)
        contacts = self.detector.read_many(raws)
        if self.hull_gaps is not None:
            self.hull_gaps.take(np.array([s.t for s in states]), [s.hull for s in states], contacts)
        seen = self._simulator_pairs.many(contacts, self._names, self._radii, pts, self._offsets, self._rest)
        batch: list = []

        def opinions():      # the batch's second opinions, built on the first disagreement
            if not batch:
                batch.append(self._recheck.many_points(self._cable_states(states[0]), pts,
                                                       np.stack([s.part_poses[self.checked_parts] for s in states])))
            return batch[0]

        validated = []
        for i, (state, result, found, pairs) in enumerate(zip(states, results, contacts, seen)):
            if self.focus_names is not None:
                pairs = {k: v for k, v in pairs.items() if k[2] in self.focus_names
                         and k[0] in PART_TYPES}
            agreement = self.validation.compare(state.t, result.cable_records, pairs,
                                                self._second_opinion(opinions, i))
            validated.append(replace(result, contacts=found, agreement=agreement))
        self.lap("validate")
        return validated

    def _proven_clear(self, states: Sequence[StepState], pts: np.ndarray, poses: np.ndarray,
                      single: np.ndarray, radius_at: np.ndarray, strain: np.ndarray,
                      bend: np.ndarray, sampled: np.ndarray | None = None) -> list[StepResult]:
        """States proven clear since the last full check: what a full check
        returns is the single-cable records, the active pairs' records and
        the replayed same-body part records; all but the last for all the
        states at once."""
        n = len(states)
        names = self._names
        records: list[list[Interference]] = [[] for _ in range(n)]
        near: list[list[Interference]] = [[] for _ in range(n)]
        flagged = np.flatnonzero(single)
        if len(flagged):
            found = single_records_many(names, pts[flagged], self._offsets, radius_at[flagged],
                                        self._rest_length, self._bend_limit_nan, self.config.clearance)
            for i, recs in zip(flagged.tolist(), found):
                records[i] = recs
        if len(self._active[0]):
            # the active pairs state by state where their elements come near
            # the part's box, and the points of those elements alone
            checked_poses = poses[:, self.checked_parts]
            si, ci, pi = self.checker.near_entries(pts, checked_poses, self._offsets, self._radii, self._active,
                                                   self._near_errors)
            if len(si):
                keep = around_centres(ci, pts.shape[1], si, len(pts))
                dense = self.checker.densify_many(pts, self._offsets, self._radii, self._rest, keep)
                found = self.checker.structure_many(names, self._radii, dense, checked_poses,
                                                    self.exclusions, (si, ci, pi), self._near_errors)
                if self._near_errors is not None:
                    found, near = found
                records = [a + b for a, b in zip(found, records)]
        if len(self._cable_active[0]):
            # the points of the elements next to the active centres alone
            keep = around_centres(np.concatenate(self._cable_active), pts.shape[1])
            dense = self.checker.densify_many(pts, self._offsets, self._radii, self._rest, keep)
            found = self.checker.cable_pairs_many(names, self._radii, dense, self._cable_active)
            records = [a + b for a, b in zip(found, records)]
        active = self._active_part_records(poses, sampled)
        same = self.part_checker.replay_many(poses) if self.part_checker.has_same_body_records \
            else [[] for _ in range(n)]
        out = []
        for recs, st, bd, found, static, misses in zip(records, strain, bend, active, same, near):
            cable_records = self._focus(recs)
            part_records = static + found
            out.append(StepResult(cable_records + part_records, cable_records, st, bd, False,
                                  near_misses=tuple(self._focus(misses))))
        return out

    def _full(self, state: StepState, pts: np.ndarray, poses: np.ndarray, strain: np.ndarray,
              bend: np.ndarray) -> StepResult:
        cables = self._cable_states(state)
        adv = self.advance
        near = None
        checked = self.checker.check_with_gaps(cables, poses[self.checked_parts], self.exclusions)
        cable_records = checked.records
        # moving part pairs still provably apart: only same-body records and
        # the active pairs, checked on their own
        # moving part pairs still provably apart but the few whose bound
        # failed: same-body records, those pairs and the active pairs, checked
        # on their own (the full part-part check's records, pairs being disjoint)
        failing = adv.part_pairs_failing(poses) if adv is not None and state.step > 0 else None
        if failing is not None:
            fi, fj = failing
            ai, aj = self._part_active
            if len(ai):
                # an active pair whose lower bound is past the clearance has no record (its measure,
                # kept for the split below: `_start_active_gaps`)
                close = self._active_values(poses, ai, aj)[0] <= self.config.clearance
                ai, aj = ai[close], aj[close]
            part_records = self._same_body_records(poses) + self._pair_records(
                poses, np.concatenate([fi, ai]), np.concatenate([fj, aj]), "full")
        else:
            part_records = self.part_checker.check(poses)
        if adv is not None:
            bound = part_pair_bounds(self.rigid, self.rigid.place(poses), *self._moving_pairs)
            # pairs within ACTIVE_HORIZONS of the clearance would stop the
            # skipping at once: left out of the bound, checked on their own
            active = bound - self.config.clearance < ACTIVE_HORIZONS * self.horizon
            mi, mj = self._moving_pairs
            self._part_active = (mi[active], mj[active])
            self._start_active_gaps(poses)
            pairs, bound = (mi[~active], mj[~active]), bound[~active]
            if checked.gaps is not None:
                gaps = checked.gaps.on_parts(self._checked_index, len(self.built.parts))   # built part indices
                parts, cable_pairs = gaps.part_candidates, gaps.cable_candidates
                # the candidates as the points measured them (the gaps count a cable-part
                # candidate from the clearance plus its cable's points' error, a bound the
                # recording's approach lines are not)
                near = (parts if self._near_errors is None else
                        parts._replace(value=parts.value + self._near_errors[parts.cable]), cable_pairs)
                # pairs within ACTIVE_HORIZONS of the clearance (records, and a
                # cable held in a part just inside its attachment window) would
                # stop the skipping at once: evaluated on their own wherever
                # the cable comes near the part (so a contact may slide along)
                close = parts.value < ACTIVE_HORIZONS * self.horizon
                n_k = max(len(self.built.parts), 1)
                key = np.unique(parts.cable[close] * n_k + parts.part[close])
                # self and cable-cable pairs likewise, near their candidates
                ca, cb = cable_pairs.cable_a, cable_pairs.cable_b
                n_c = max(len(self.built.cables), 1)
                close = cable_pairs.value < ACTIVE_HORIZONS * self.horizon
                c_key = np.unique(np.minimum(ca, cb)[close] * n_c + np.maximum(ca, cb)[close])
                left = adv.start(pts, poses, gaps, pairs, bound, (key // n_k, key % n_k),
                                 np.stack([c_key // n_c, c_key % n_c], axis=1))
                centre, built_part = left.structure
                self._active = (centre, self._checker_index[built_part])   # (centre, checker part)
                self._cable_active = left.cable
            else:
                adv.stop()
                adv.start_pairs(poses, pairs, bound)
        cable_records = self._focus(cable_records)
        return StepResult(cable_records + part_records, cable_records, strain, bend, True, near=near,
                          near_misses=tuple(self._focus(checked.near_misses)))

    def _pair_records(self, poses: np.ndarray, i: np.ndarray, j: np.ndarray, slot: str) -> list[Interference]:
        """`PartChecker.check_pairs` of pairs (i, j) at poses (P, 4, 4): the records of the last
        call for the same `slot` where it asked for the same pairs and none of their parts has
        moved since (to the bit: a robot's base on its table, checked at every full check)."""
        used = np.unique(np.concatenate([i, j]))
        last = self._pair_records_memo.get(slot)
        if last is not None and np.array_equal(last[0], i) and np.array_equal(last[1], j) \
                and np.array_equal(last[2], poses[used]):
            return list(last[3])
        records = self.part_checker.check_pairs(poses, i, j)
        self._pair_records_memo[slot] = (np.array(i), np.array(j), poses[used].copy(), list(records))
        return records

    def _start_active_gaps(self, poses: np.ndarray) -> None:
        """Split the active part pairs at poses (P, 4, 4) by their distances
        measured there (`PartChecker.pair_values`, up to the clearance plus a
        horizon): those within the clearance (records; overlapping links) and
        pairs of two primitives are checked at every state where one of their
        parts has moved since (else their records are these, to the bit); the
        rest, pairs with a mesh apart, are bounded from there
        (`_pair_gaps`, one condition a pair)."""
        ai, aj = self._part_active
        poses = np.asarray(poses, float)
        values, axes = self._active_values(poses, ai, aj)
        # two primitives are checked at all the states of a batch in one call, about as cheaply as
        # bounding them: only pairs with a mesh (their triangles) are worth bounding
        kind = self.rigid.convex_kind
        near = (values <= self.config.clearance) | ((kind[ai] >= 0) & (kind[aj] >= 0))
        names = self.rigid.names
        allowed = np.array([bool(self.allow) and self._allowed_part(names[a], names[b])
                            for a, b in zip(ai.tolist(), aj.tolist())], bool).reshape(-1)   # the few active pairs
        self._allowed_near = (ai[near & allowed], aj[near & allowed])
        self._active_near = (ai[near & ~allowed], aj[near & ~allowed])
        # their records where none of their parts has moved since (a robot's base on its table), kept
        # from the last split when the same pairs' parts have not moved since either; the allowed
        # ones' too, for the sampled states where their parts have not moved
        self._near_start = self._records_at(poses, self._active_near, "near")
        self._allowed_start = self._records_at(poses, self._allowed_near, "allowed")
        self._active_apart = (ai[~near], aj[~near])
        self._active_split = True
        self._apart_gaps = [self._pair_gaps(poses, a, b, v, u) for a, b, v, u in
                            zip(ai[~near].tolist(), aj[~near].tolist(), values[~near].tolist(), axes[~near])]

    def _active_values(self, poses: np.ndarray, ai: np.ndarray,
                       aj: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """`PartChecker.pair_values_axes` of the active pairs at poses (P, 4, 4), a pair whose two
        parts have not moved since it was last measured (to the bit) keeping its value and axis."""
        memo = self._value_memo
        values = np.empty(len(ai))
        axes = np.zeros((len(ai), 3))
        fresh = []
        for k, (a, b) in enumerate(zip(ai.tolist(), aj.tolist())):   # the few active pairs
            kept = memo.get((a, b))
            if kept is not None and np.array_equal(kept[0], poses[a]) and np.array_equal(kept[1], poses[b]):
                values[k], axes[k] = kept[2], kept[3]
            else:
                fresh.append(k)
        if fresh:
            fresh = np.array(fresh)
            values[fresh], axes[fresh] = self.part_checker.pair_values_axes(
                poses, ai[fresh], aj[fresh], self.config.clearance + self.horizon, exact_below=self.config.clearance)
            for k in fresh.tolist():
                memo[(int(ai[k]), int(aj[k]))] = (poses[ai[k]].copy(), poses[aj[k]].copy(), float(values[k]),
                                                  axes[k].copy())
        return values, axes

    def _pair_gaps(self, poses: np.ndarray, a: int, b: int, value: float, axis: np.ndarray) -> ApartPair:
        """The part-pair condition of the one pair (a, b), started at poses (P, 4, 4) from its
        distance `value` measured there, and the axis its hulls were found apart along (zero: none)."""
        rho, solids = self._pair_gaps_args
        gaps = PartPairGaps(rho, self.config.clearance, solids)
        gaps.start(poses, (np.array([a]), np.array([b])), np.array([value]))
        return ApartPair(a, b, gaps, np.array(axis, float) if np.any(axis) else None, np.array(poses, float))

    def _apart_clear(self, pair: ApartPair, poses: np.ndarray) -> np.ndarray:
        """(S,) the pair provably outside the clearance at poses (S, P, 4, 4): its part-pair condition
        (`PartPairGaps`: how far one part moved relative to the other), or, where that fails, its
        hulls' separation along the axis found at the start, carried along with either part
        (`PartChecker.hull_separations`: measured at the state itself, no bound on a move), past the
        clearance by a rounding margin."""
        ok = pair.gaps.clear_pairs(poses)[0]
        if pair.axis is not None and not ok.all():
            rows = np.flatnonzero(~ok)
            sep = self.part_checker.hull_separations(poses[rows], pair.a, pair.b, pair.axis, pair.at)
            mu = 1e-9 * (1.0 + float(np.abs(poses[rows][:, [pair.a, pair.b], :3, 3]).max(initial=0.0)))
            ok[rows] = sep > self.config.clearance + mu
        return ok

    def _active_part_records(self, poses: np.ndarray, sampled: np.ndarray | None = None) -> list[list[Interference]]:
        """The active part pairs' records at states (S, P, 4, 4) proven clear
        for everything else: the same as checking them at every state
        (`PartChecker.check_pairs_many`). The pairs within the clearance at
        the last full check are checked at every state. The others: a state
        where none can have come within the clearance since their last
        measured distances, as far as the part-pair condition bounds their
        relative move (`PartPairGaps` started from those distances), has no
        record of theirs; at the first state where one may have, it is checked
        and measured again and its own condition restarts there (at most
        `ACTIVE_RESTARTS` restarts a batch, and none for a pair once within the
        clearance); each pair's states still failing then are checked in one call.
        The allowed pairs within the clearance are checked at the `sampled`
        states alone (ALLOWED_INTERVAL)."""
        n = len(poses)
        out: list[list[Interference]] = [[] for _ in range(n)]
        if not len(self._part_active[0]):
            return out
        if not self._active_split:
            return self.part_checker.check_pairs_many(poses, *self._part_active)
        if len(self._active_near[0]):
            out = self._kept_or_checked(poses, np.arange(n), self._active_near, self._near_start)
        if len(self._allowed_near[0]):
            at = np.flatnonzero(sampled) if sampled is not None else np.arange(n)
            for k, recs in zip(at.tolist(), self._kept_or_checked(poses, at, self._allowed_near,
                                                                  self._allowed_start)):
                out[k] = out[k] + recs
        ai, aj = self._active_apart
        if not len(ai):
            return out
        reach = self.config.clearance + self.horizon
        ok = np.stack([self._apart_clear(g, poses) for g in self._apart_gaps])        # (pairs, states)
        near = np.zeros(len(ai), bool)     # came within the clearance: not restarted again this batch
        for _ in range(ACTIVE_RESTARTS):
            fail = ~ok
            first = np.where(fail.any(axis=1) & ~near, fail.argmax(axis=1), n)
            k = int(np.argmin(first))
            s = int(first[k])
            if s == n:
                break
            pair = (ai[k:k + 1], aj[k:k + 1])
            ok[k, s] = True
            # a lower bound past the clearance: no record there (the convex hulls' where they prove it)
            values, axes = self.part_checker.pair_values_axes(poses[s], *pair, reach,
                                                              exact_below=self.config.clearance)
            if values[0] <= self.config.clearance:
                out[s] = out[s] + self.part_checker.check_pairs(poses[s], *pair)
                near[k] = True
                continue
            self._apart_gaps[k] = self._pair_gaps(poses[s], int(ai[k]), int(aj[k]), float(values[0]), axes[0])
            ok[k, s + 1:] = self._apart_clear(self._apart_gaps[k], poses[s + 1:])
        for k in np.flatnonzero((~ok).any(axis=1)).tolist():     # what is left: in one call a pair
            states = np.flatnonzero(~ok[k])
            for t, recs in zip(states.tolist(), self.part_checker.check_pairs_many(poses[states], ai[k:k + 1],
                                                                                   aj[k:k + 1])):
                out[t] = out[t] + recs
        return out

    def _records_at(self, poses: np.ndarray, pairs: tuple[np.ndarray, np.ndarray], slot: str) -> _PairsAt:
        """Part pairs at poses (P, 4, 4), whose records `_kept_or_checked` keeps where none
        of their parts has moved since: their parts and poses, the records checked when a
        state first asks for them (parts that move at every state, a slider's, never do)."""
        used = np.unique(np.concatenate(pairs))
        return _PairsAt(used, np.array(poses, float), slot)

    def _kept_or_checked(self, poses: np.ndarray, at: np.ndarray, pairs: tuple[np.ndarray, np.ndarray],
                         start: _PairsAt) -> list[list[Interference]]:
        """The records of part pairs at states `at` of poses (S, P, 4, 4): those at `start`
        (`_records_at`) where none of their parts has moved since, to the bit (a robot's
        base on its table), else checked, the moved states in one call."""
        still = (poses[at][:, start.used] == start.poses[start.used][None]).all(axis=(1, 2, 3))
        kept = self._pair_records(start.poses, *pairs, start.slot) if still.any() else []
        out = [list(kept) if k else [] for k in still.tolist()]
        moved = np.flatnonzero(~still)
        if len(moved):
            for k, recs in zip(moved.tolist(), self.part_checker.check_pairs_many(poses[at[moved]], *pairs)):
                out[k] = recs
        return out

    def _same_body_records(self, poses: np.ndarray) -> list[Interference]:
        """The part-part records of a step on which no moving pair can be
        within the clearance: the same-body ones, replayed."""
        return self.part_checker.replay(poses) if self.part_checker.has_same_body_records else []

    def _focus(self, records: list[Interference]) -> list[Interference]:
        """With --only: the records against the assembly's parts alone."""
        if self.focus_names is None:
            return records
        return [r for r in records if r.b in self.focus_names
                and PairType(r.type) in PART_TYPES]

    def _cable_states(self, state: StepState) -> list[CableState]:
        return cable_states(self.built, state.cables)

    def outcome(self, validated: bool) -> ChecksOutcome:
        """The checks' end-of-run record (call after the last batch)."""
        adv = self.advance
        return ChecksOutcome(
            advance=None if adv is None else AdvanceOutcome(self.horizon, self.stretch, adv.full, adv.skipped),
            validation=self.validation.summary() if validated else None,
            part_warnings=tuple(self.rigid.warnings),
            hull_warnings=tuple(self.hull_gaps.warnings()) if self.hull_gaps else (),
            excused=self.excused.worst(), closest=self.margins.closest(),
            margin_reach=self.margin_reach)

    def _second_opinion(self, opinions, i: int):
        """Builds the second opinions on a disagreement at the batch's state i
        (only when the validation asks: most states have none)."""
        return lambda: opinions().at(i)


def margin_samples(times: np.ndarray, interval: float) -> np.ndarray:
    """The states of a batch at ``times`` (S,) whose closest approaches are
    measured: the first in each ``interval`` of simulated time, and the
    batch's first and last (so every stretch between two samples lies in
    one batch)."""
    n = len(times)
    if n == 0:
        return np.zeros(0, np.int64)
    slot = np.floor(np.asarray(times, float) / interval)
    first = np.r_[True, slot[1:] != slot[:-1]]
    first[-1] = True
    return np.flatnonzero(first)


def cable_states(built: Built, points: list[np.ndarray]) -> list[CableState]:
    """The checker's view of the cables at one state (body centres per cable,
    with their material coordinates)."""
    return [CableState(c.name, p, c.radius, c.min_bend_radius, c.length, c.rest_s)
            for c, p in zip(built.cables, points)]


def part_bodies(built: Built) -> np.ndarray:
    """(P,) the body id of each built part."""
    return np.array([int(built.model.geom_bodyid[p.geom_id]) for p in built.parts], np.int64)


def part_pairs_skipped(built: Built) -> np.ndarray:
    """(P, P) bool: part pairs the part-part check leaves out, as MuJoCo does.

    - parts of a child body and of its parent body (other than the world
      body itself) when a joint joins them: arm links overlap at their joints
      by design. As MuJoCo's own filter (Computation, contact selection):
      bodies welded together (no joint between them) count as one, so a
      link's welded companion body (robosuite's Sawyer `right_l1_2` on
      `right_l1`) is its link's child or parent too; unlike MuJoCo's, a
      parent body welded to the world (an arm's fixed base link) is not
      exempt;
    - two geoms of the base mjcf model in the same rigid (weld) group: the
      model author's layout, never colliding in MuJoCo either;
    - pairs the mjcf model itself excludes (`Built.model_skip`: its own
      contact bits, `<contact><exclude>`).
    Scene `[[parts]]` on one body are checked against each other (once, at
    t = 0)."""
    m = built.model
    scene_names = {p.name for p in built.scene.parts}
    body = part_bodies(built)
    weld = m.body_weldid[body]
    parent = m.body_weldid[m.body_parentid[weld]]       # the weld group above each part's weld group
    base = np.array([p.name not in scene_names for p in built.parts], bool)
    child_of = (parent[:, None] == weld[None, :]) & (parent[:, None] != 0) & (weld[:, None] != weld[None, :])
    # and a jointed body's own parent body, though welded to the world (an arm's base link on a
    # fixed base: its first link turns in it by design; MuJoCo exempts the world's weld group)
    raw_parent = m.body_parentid[body]
    jointed = m.body_weldid[body] == body
    child_of |= (raw_parent[:, None] == body[None, :]) & (raw_parent[:, None] != 0) & jointed[:, None]
    skip = child_of | child_of.T
    skip |= (weld[:, None] == weld[None, :]) & base[:, None] & base[None, :]
    if built.model_skip.shape == skip.shape:
        skip |= built.model_skip
    np.fill_diagonal(skip, True)
    return skip


def attachment_exclusions(built: Built, shapes: Sequence[Shape] | None = None,
                          poses: np.ndarray | None = None) -> list[Exclusion]:
    """Windows along each cable's material where touching a part is expected:
    the parts each end and clip is fastened to, and nothing else.

    A window spans `check.attach_zone` cable radii of rest arc length either
    side of the held vertices of one end or clip (a clamp holds two, its
    short edge; a pin one; a free end none), widened to whole elements (so
    that MuJoCo's contacts, one per element, can be filtered by the same
    window), in the cable's material coordinate (:attr:`CableModel.rest_s`:
    a stretched cable keeps the same elements excused). It excuses:

    - the parts the scene names for that end or clip (`part`: names or
      assembly paths), when it names any; else
    - the parts of its holding body, and with `check.attach_links` = N of
      every body within N joints of it (:func:`neighbour_bodies`), that a
      held vertex lies within the cable radius plus the clearance of, at
      t = 0 (the routed state: `shapes` and `poses`, `cablecheck.build.checkview`'s
      part shapes and :func:`~cablecheck.build.checkview.start_part_poses`, computed
      when not given). An end on `world` excuses the fixture it is clamped
      in, never every fixed part nearby.

    Every other part near an end is checked like anywhere else. Each window
    is named ("start", "end", "clip N") so the report can list what it
    excused."""
    zone = built.scene.check.attach_zone
    links = built.scene.check.attach_links
    reach = built.scene.check.clearance
    m = built.model
    names = [p.name for p in built.parts]
    part_body = part_bodies(built)
    table = None
    out = []
    for c in built.cables:
        windows: dict[str, list] = {}
        for att in c.attachments:
            windows.setdefault(att.window, []).append(att)
        for window, held in windows.items():
            s_held = np.array([a.s for a in held])
            lo_s, hi_s = s_held.min() - zone * c.radius, s_held.max() + zone * c.radius
            lo = c.rest_s[np.searchsorted(c.rest_s, lo_s, side="right") - 1] if lo_s > 0 else 0.0
            hi = c.rest_s[min(np.searchsorted(c.rest_s, hi_s), c.count - 1)]
            if held[0].parts:
                fastened = np.flatnonzero([any(covers(n, (p,)) for n in held[0].parts) for p in names])
            else:
                bodies = neighbour_bodies(m, built.body_ids[held[0].body], links)
                near = np.flatnonzero(np.isin(part_body, bodies))
                if table is None and len(near):
                    table = _start_table(built, shapes, poses)
                points = c.routed[[a.vertex for a in held]]
                fastened = near[held_within(table, near, points, c.radius + reach)] if len(near) else near
            to_end = bool(hi >= c.rest_s[c.count - 1])
            out += [Exclusion(c.name, names[k], float(lo), float(hi), window, to_end) for k in fastened.tolist()]
    return sorted(set(out), key=lambda e: (e.cable, e.part, e.s_min, e.window))


def held_element_exclusions(built: Built) -> list[Exclusion]:
    """Windows over each cable's elements with a vertex held by a body (the
    elements either side of an end's or clip's held vertices), against that
    body's parts. MuJoCo collides no flex element with the geoms of a body
    that holds one of its vertices (measured: a sphere 1 mm from the middle
    of a cable's first long element, whose inner end the world holds, on the
    world and on a scene body: no contact; 1 mm from an element wholly free:
    a contact), so its contacts never show those elements near those parts.
    Not excusals: the checker measures those elements as any other;
    validation reads a pair clear without them before it calls a
    checker-only pair unexplained (`cablecheck.checker.validation.Reason.HELD_ELEMENT`)."""
    part_body = part_bodies(built)
    out = []
    for c in built.cables:
        by_body: dict[int, set] = {}
        for a in c.attachments:               # the elements either side of each held vertex
            by_body.setdefault(built.body_ids[a.body], set()).update({a.vertex - 1, a.vertex})
        for body, elems in by_body.items():
            e = np.array(sorted(x for x in elems if 0 <= x < c.count - 1), np.int64)
            if not len(e):
                continue
            cut = np.flatnonzero(np.diff(e) > 1) + 1             # runs of consecutive elements
            for run in np.split(e, cut):
                lo, hi = float(c.rest_s[run[0]]), float(c.rest_s[run[-1] + 1])
                out += [Exclusion(c.name, built.parts[k].name, lo, hi, "held element", bool(run[-1] + 1 == c.count - 1))
                        for k in np.flatnonzero(part_body == body).tolist()]
    return sorted(set(out), key=lambda x: (x.cable, x.part, x.s_min))


def _start_table(built: Built, shapes: Sequence[Shape] | None, poses: np.ndarray | None) -> PartTable:
    """Every built part placed at t = 0, as a checker's part table."""
    shapes = part_shapes(built) if shapes is None else shapes
    poses = start_part_poses(built) if poses is None else poses
    return PartTable([PartState(p.name, sh, pose, p.keepout) for p, sh, pose in zip(built.parts, shapes, poses)])


def held_within(table: PartTable, parts: np.ndarray, points: np.ndarray, reach: float) -> np.ndarray:
    """(len(parts),) bool: some of the world ``points`` (n, 3) lies within
    ``reach`` of part k's surface (or inside it), for each k of ``parts``."""
    k = np.repeat(np.asarray(parts, np.int64), len(points))
    x = np.tile(np.asarray(points, float).reshape(-1, 3), (len(parts), 1))
    loc = table.to_local(k, x)
    inside_box = ((loc >= table.lo[k] - reach) & (loc <= table.hi[k] + reach)).all(axis=1)
    d = np.full(len(k), np.inf)
    d[inside_box] = point_distances(table, k[inside_box], loc[inside_box], False)
    return (d <= reach).reshape(len(parts), len(points)).any(axis=1)


def neighbour_bodies(model, body: int, links: int) -> list[int]:
    """Body ids within `links` joints of `body` in the kinematic tree.

    A step from a body to its parent or a child crosses the child's joints
    (none for a welded body: it moves with its parent, 0 steps). Paths
    never pass through the world body (id 0): everything fixed in the cell
    hangs from it, and a table or fence is no neighbour of a link.
    `links` = 0: the body alone."""
    if links <= 0:
        return [body]
    parent, jnum = model.body_parentid, model.body_jntnum
    children: dict[int, list[int]] = {}
    for b in range(1, model.nbody):
        children.setdefault(int(parent[b]), []).append(b)
    cost = {body: 0}
    todo = [body]
    while todo:       # a tree of a few dozen bodies, searched once per attachment
        b = todo.pop()
        if b == 0:
            continue
        steps = [(int(parent[b]), int(jnum[b]))] + [(k, int(jnum[k])) for k in children.get(b, ())]
        for nb, joints in steps:
            c = cost[b] + joints
            if c <= links and c < cost.get(nb, links + 1):
                cost[nb] = c
                todo.append(nb)
    return sorted(k for k in cost if k != 0 or body == 0)
