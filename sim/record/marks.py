"""The clashes in the review recording: the spot of each pair and its state lane.

`world/interference/<type>/<a>/<b>`: a wire sphere round the worst place on
cable a, in a colour no cable or part uses; its label (the pair and its
distance) on a point just above the sphere, lifted further where another
spot's label shown at the same time would overlap it (with a leader down
to the sphere), for the deepest dozen spots of a frame (`LABELS_SHOWN`); the segment (the gap) to the closest point on the other
side (`cablecheck.checker.spot`), and a thin line through it that runs on out of the
sphere (so the gap's direction shows outside the marker); all shown from
the frame a clash is seen and emptied at the frame after each run of such
frames. `lanes/<type>/<a>/<b>`:
the pair's state (clear / soft / hard) as state changes, one lane per pair.
Everything is buffered per frame and sent in columns, one chunk per entity,
when the recording is closed; the style (the spot's colour, wire sphere,
labels; the lanes' state colours) is the views' default in the blueprint
(`cablecheck.record.layout`), not data: a harness has thousands of pairs, and a
chunk costs kilobytes.

Not here: which pairs clash (the checker and the event tracker decide).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import rerun as rr

from cablecheck.build.built import Built
from cablecheck.checker import spot
from cablecheck.checker.shapes import Shape
from cablecheck.record.columns import column, floats, strings, strips, times as sim_time, vec3
from cablecheck.record.style import pair_path, pair_text


@dataclass(frozen=True)
class Mark:
    """One clash shown at a frame: the pair and where.

    Attributes:
      kind, a, b: the pair (type value, names).
      distance: signed distance, metres.
      state: "soft" or "hard".
      where: (3,) worst place on cable a, metres.
      s: arc length there on cable a, metres.
      s_b: arc length on cable b (self, cable-cable) or None.
    """

    kind: str
    a: str
    b: str
    distance: float
    state: str
    where: np.ndarray
    s: float
    s_b: float | None


class ClashMarks:
    """Spots and state lanes of the clashes, frame by frame.

    Args:
      built: the built scene.
      unit: metres per scene unit.
      units: the scene's unit name (labels).
      shapes: the checker's shape of every built part (the other side of a
        spot on a part), or None (no segment to parts).
    """

    def __init__(self, built: Built, unit: float, units: str, shapes: list[Shape] | None):
        self.built, self.unit, self.units, self.shapes = built, unit, units, shapes
        self._cable_index = {c.name: i for i, c in enumerate(built.cables)}
        self._part_index = {p.name: k for k, p in enumerate(built.parts)}
        # pair path -> rows (frame, where, other side or None, label, cable a, distance), scene units
        self._rows: dict[str, list[tuple[int, np.ndarray, np.ndarray | None, str, str, float]]] = {}
        # part index -> (rows of a pair, row, where (world, m), part pose), and cable index ->
        # (rows, row, where, s_b, the cable's centres): closest points still to find
        self._part_spots: dict[int, list[tuple]] = {}
        self._cable_spots: dict[int, list[tuple]] = {}
        self._lane: dict[str, str] = {}
        self._lanes: dict[str, tuple[list[int], list[str]]] = {}
        # pair path -> the frames it is shown at (a row at each, or the last row standing)
        self._present: dict[str, list[int]] = {}
        self._between: set[int] = set()         # the frames between the regular samples

    def add(self, frame: int, marks: list[Mark], cables: list[np.ndarray], poses: np.ndarray,
            update: set[tuple[str, str, str]] | None = None) -> tuple[bool, set[tuple[str, str, str]]]:
        """The frame's clashes: whether any is shown, and the pairs (kind, a, b)
        given a row. ``update``: at a frame between the run's regular samples,
        the pairs to give a row (an event's worst or start there); any other
        pair still shown keeps its last row, unless it was not shown at the
        frame before (then it gets one too). None: every pair. ``cables``
        (the frame's body centres) are kept as given, not copied."""
        u = self.unit
        now = set()
        updated: set[tuple[str, str, str]] = set()
        if update is not None:
            self._between.add(frame)
        for m in marks:
            path = pair_path(m.kind, m.a, m.b)
            now.add(path)
            present = self._present.setdefault(path, [])
            key = (m.kind, m.a, m.b)
            if update is not None and key not in update and present and present[-1] == frame - 1:
                present.append(frame)
                if self._lane.get(path) != m.state:
                    self._set_lane(path, frame, m.state)
                continue
            present.append(frame)
            updated.add(key)
            rows = self._rows.setdefault(path, [])
            # the other side's closest point is found with the others of its part or cable at the end
            where = np.asarray(m.where, float)
            if m.kind in ("self", "cable-cable") and m.s_b is not None and m.b in self._cable_index:
                i = self._cable_index[m.b]
                self._cable_spots.setdefault(i, []).append((rows, len(rows), where, m.s_b,
                                                            np.asarray(cables[i], float)))
            elif m.kind in ("cable-structure", "keepout") and self.shapes is not None and m.b in self._part_index:
                k = self._part_index[m.b]
                self._part_spots.setdefault(k, []).append((rows, len(rows), where, np.asarray(poses[k], float)))
            rows.append((frame, where / u, None, f"{pair_text(m.a, m.b)}: {m.distance / u:.3g} {self.units}", m.a,
                         m.distance / u))
            if self._lane.get(path) != m.state:
                self._set_lane(path, frame, m.state)
        for path in [p for p, s in self._lane.items() if p not in now and s != "clear"]:
            self._set_lane(path, frame, "clear")
        return bool(now), updated

    def _set_lane(self, path: str, frame: int, state: str) -> None:
        self._lane[path] = state
        frames, states = self._lanes.setdefault(path, ([], []))
        frames.append(frame)
        states.append(state)

    def _resolve_spots(self) -> None:
        """The other side of every mark on a part or a cable (`cablecheck.checker.spot`):
        one query per part or cable for the whole run. Bend, taut and
        part-part marks have none."""
        u = self.unit
        found = [(spots, spot.on_part_many(self.shapes[k], np.stack([s[3] for s in spots]),
                                           np.stack([s[2] for s in spots])))
                 for k, spots in self._part_spots.items()]
        found += [(spots, spot.on_cable_many(np.stack([s[4] for s in spots]), np.array([s[3] for s in spots]),
                                             np.stack([s[2] for s in spots])))
                  for spots in self._cable_spots.values()]
        for spots, points in found:
            for (rows, i, *_), other in zip(spots, points / u):
                frame, where, _, label, a, d = rows[i]
                rows[i] = (frame, where, other, label, a, d)
        self._part_spots, self._cable_spots = {}, {}

    def send(self, rec: rr.RecordingStream, times: np.ndarray, bounds: tuple[np.ndarray, np.ndarray],
             clearance: float) -> None:
        """Every pair's spot, gap and lane, one column per entity (`times`: each frame's, seconds)."""
        self._resolve_spots()
        n_f = len(times)
        index = lambda frames: [sim_time(times[np.asarray(frames, int)])]
        state = rr.StateChange.descriptor_state()
        for path, (frames, states) in self._lanes.items():
            # the lanes' configuration (state names and colours) is the view's default
            # (`cablecheck.record.layout`): one chunk per lane, not two
            rec.send_columns(f"lanes/{path}", indexes=index(frames), columns=[column(state, strings(states))])
        lo, hi = bounds
        diag = float(np.linalg.norm(hi - lo))
        radii = {path: max(2.5 * self._radius(rows[0][4]) + 0.5 * clearance, 0.01 * diag) / self.unit
                 for path, rows in self._rows.items()}
        lifts = label_lifts(self._rows, radii, LABEL_STEP * diag / self.unit)
        between = np.array(sorted(self._between), np.int64)
        for path, rows in self._rows.items():
            self._send_spot(rec, path, rows, n_f, index, radii[path], lifts[path], self._present[path], between)

    def _radius(self, cable: str) -> float:
        i = self._cable_index.get(cable)
        return 0.0 if i is None else self.built.cables[i].radius

    @staticmethod
    def _send_spot(rec: rr.RecordingStream, path: str, rows: list, n_f: int, index, radius: float,
                   lifts: np.ndarray, present: list[int] | None = None, between: np.ndarray | None = None) -> None:
        """One pair's spot (a wire sphere of `radius`, scene units, standing out of
        the cable; the cable, the gap and the part stay visible inside it), its
        label `lifts` (one per row, scene units; NaN: no label at that frame)
        above its centre, and its gap, emptied at the frame after each run of
        `present` frames (those of the rows where None). Its rows at once, as
        arrays; a row that shows no label, follows none, and moves its sphere
        and its gap's ends no more than :data:`SPOT_STILL` of the sphere's
        radius from the last row kept is left out (the last one stands), unless
        it starts a run or lies between the regular samples (`between`, frame
        numbers: an event's worst instant, start or end, shown as measured there)."""
        frame = np.array([r[0] for r in rows], np.int64)
        on = frame if present is None else np.asarray(present, np.int64)
        where = np.array([r[1] for r in rows], float).reshape(-1, 3)
        other = np.array([np.full(3, np.nan) if r[2] is None else r[2] for r in rows], float).reshape(-1, 3)
        ends = on[np.r_[on[1:] > on[:-1] + 1, True]] + 1
        shown = ~np.isnan(lifts)
        forced = np.isin(frame - 1, on, invert=True)                          # a run's start
        if between is not None:
            forced |= np.isin(frame, between)
        keep = _moving_rows(where, other, shown, forced, SPOT_STILL * radius)
        if not keep.all():
            rows = [r for r, k in zip(rows, keep.tolist()) if k]
            frame, where, other, shown, lifts = frame[keep], where[keep], other[keep], shown[keep], lifts[keep]
        labels = [r[3] for r, k in zip(rows, shown) if k]
        top = where.copy()
        top[:, 2] += np.where(shown, lifts, LABEL_ABOVE * radius)
        # emptied at the frame after each run of frames (an entry with nothing in it)
        ends = ends[ends < n_f]
        frames = np.r_[frame, ends]
        order = np.argsort(frames, kind="stable")
        lengths = np.r_[np.ones(len(frame), np.int32), np.zeros(len(ends), np.int32)][order]
        labelled = np.r_[shown.astype(np.int32), np.zeros(len(ends), np.int32)][order]
        # the sizes go with the centres: an empty row has no sphere at all (a size without
        # a centre would draw one at the origin); the label rides on a point above the
        # sphere (lifted clear of its neighbours' labels, `label_lifts`; none in a row
        # whose label is not shown, a frame of more than `LABELS_SHOWN` spots), the segment to
        # the other side (emptied with the marker) in the same entity, and the style is
        # the views' default (`cablecheck.record.layout`): one chunk per pair, where a style and
        # a gap entity would make four
        e, p = rr.Ellipsoids3D, rr.Points3D
        columns = [column(e.descriptor_centers(), vec3(where), lengths),
                   column(e.descriptor_half_sizes(), vec3(np.full((len(where), 3), radius)), lengths),
                   column(p.descriptor_positions(), vec3(top[shown]), labelled),
                   column(p.descriptor_labels(), strings(labels), labelled)]
        # per row, in this order: the gap (thick); the line through it across the sphere
        # and out of it (thin: the gap's direction stays visible outside the marker); a
        # lifted label's leader
        gap = ~np.isnan(other[:, 0])
        d = other - where
        length = np.sqrt(np.einsum("ij,ij->i", d, d))
        through = gap & (length > 1e-9 * radius)
        d = d / np.where(through, length, 1.0)[:, None]
        reach = THROUGH * radius * np.maximum(1.0, length / radius + 0.3)
        leader = shown & (top[:, 2] - where[:, 2] > 1.01 * radius * LABEL_ABOVE)
        up = where + np.array([0.0, 0.0, radius])
        slots = np.stack([np.stack([where, other], axis=1),
                          np.stack([where - THROUGH * radius * d, where + reach[:, None] * d], axis=1),
                          np.stack([up, top], axis=1)], axis=1)                # (rows, 3, 2, 3)
        width = np.broadcast_to(np.array([GAP_WIDTH, THIN_WIDTH, 0.5 * THIN_WIDTH]) * radius, (len(rows), 3))
        present = np.stack([gap, through, leader], axis=1)
        counts = np.r_[present.sum(axis=1), np.zeros(len(ends), np.int64)][order].astype(np.int32)
        if present.any():
            pairs = slots[present]                                           # (k, 2, 3), row by row
            columns += [column(rr.LineStrips3D.descriptor_strips(),
                               strips(pairs.reshape(-1, 3), np.arange(0, 2 * len(pairs) + 1, 2)), counts),
                        column(rr.LineStrips3D.descriptor_radii(), floats(width[present], np.float32), counts)]
        rec.send_columns(f"world/interference/{path}", indexes=index(frames[order]), columns=columns)


SPOT_STILL = 0.05
"""A spot's row is kept where its sphere or its gap's far end moved more than
this many sphere radii since the last row kept (or where its label shows or
is cleared, a run starts, an event's instant falls): a crossing resting on
another stores its spot once, not at every sample."""


def _moving_rows(where: np.ndarray, other: np.ndarray, labelled: np.ndarray, forced: np.ndarray,
                 still: float) -> np.ndarray:
    """(n,) the spot rows to keep (see `ClashMarks._send_spot`): the first, every
    `forced` or `labelled` one and the one after a labelled one, every one whose
    gap appears or goes, and every one whose centre `where` or gap end `other`
    (n, 3; NaN: no gap) lies more than `still` from the last row kept's."""
    n = len(where)
    gap = ~np.isnan(other[:, 0])
    keep = forced | labelled
    keep[1:] |= labelled[:-1] | (gap[1:] != gap[:-1])
    if n:
        keep[0] = True
    if keep.all():
        return keep
    # compared with the last row kept, not the row before (a slow drift is stored)
    # each row's sphere centre and gap end (a row without a gap: its centre twice), as floats:
    # a loop along the rows, each compared with the last kept (tens of thousands in a harness)
    at = np.concatenate([where, np.where(gap[:, None], other, where)], axis=1).tolist()
    kept = keep.tolist()
    j = 0
    for k in range(1, n):
        if not kept[k] and max(abs(x - y) for x, y in zip(at[k], at[j])) > still:
            kept[k] = True
        if kept[k]:
            j = k
    keep = np.array(kept, bool)
    return keep


LABEL_STEP = 0.03
"""The height of a spot's label in the views, as a fraction of the scene's
extent (a text line in the scene view; more in a clash's closer view):
labels of spots shown at once are stacked at least this far apart."""
LABEL_ABOVE = 1.15
"""A label's lift above its spot's centre, in sphere radii, with no neighbour in the way."""
CHAR_WIDTH = 0.55
"""A label's character width in label heights (the overlap test's width)."""
LABELS_SHOWN = 12
"""Labels shown at one frame at most, those of its deepest spots: a harness's
frame can hold hundreds of clashes, whose labels stacked clear of each other
would rise metres above it (and cost seconds to place); a dozen reads."""
GAP_WIDTH = 0.2
THIN_WIDTH = 0.06
THROUGH = 1.7
"""The gap's line runs on to this many sphere radii from the spot's centre, past the sphere."""


def label_lifts(rows: dict[str, list], radii: dict[str, float], step: float) -> dict[str, np.ndarray]:
    """How far above its spot's centre each spot row's label goes (scene
    units; per pair path, one per row; NaN: no label at that frame): just
    above the sphere, unless another label shown at that frame would then
    overlap it (taken as a box `step` high and :data:`CHAR_WIDTH` x `step`
    per character wide, across in the horizontal plane), then up by steps
    until it does not. At most :data:`LABELS_SHOWN` labels a frame, those of
    its deepest spots (the others keep their spheres and gaps; the clash
    list has every pair). Pairs in path order, so a pair's label keeps its
    place while the others come and go."""
    lifts = {path: np.array([LABEL_ABOVE * radii[path]] * len(r)) for path, r in rows.items()}
    by_frame: dict[int, list[tuple[str, int]]] = {}
    for path in sorted(rows):
        for k, row in enumerate(rows[path]):
            by_frame.setdefault(row[0], []).append((path, k))
    for shown in by_frame.values():
        if len(shown) > LABELS_SHOWN:
            depth = np.array([rows[path][k][5] for path, k in shown], float)
            labelled = np.zeros(len(shown), bool)
            labelled[np.argsort(depth, kind="stable")[:LABELS_SHOWN]] = True      # deepest, then path order
            for (path, k), keep in zip(shown, labelled.tolist()):
                if not keep:
                    lifts[path][k] = np.nan
            shown = [x for x, keep in zip(shown, labelled.tolist()) if keep]
        if len(shown) < 2:
            continue
        placed: list[tuple[float, float, float, float]] = []          # x, y, z, half width
        for path, k in shown:
            where, label = rows[path][k][1], rows[path][k][3]
            half = 0.5 * CHAR_WIDTH * step * len(label)
            z = where[2] + lifts[path][k]
            moved = True
            while moved:
                moved = False
                for x, y, pz, other in placed:
                    # (a label a whole step above another is clear of it: the test leaves
                    # a margin, or rounding in pz + step could keep it "overlapping" forever)
                    if abs(z - pz) < 0.999 * step and np.hypot(where[0] - x, where[1] - y) < half + other:
                        z = pz + step
                        moved = True
            lifts[path][k] = z - where[2]
            placed.append((float(where[0]), float(where[1]), z, half))
    return lifts
