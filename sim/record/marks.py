"""The clashes in the review recording: the spot of each pair and its state lane.

`world/interference/<type>/<a>/<b>`: a wire sphere round the worst place on
cable a, in a colour no cable or part uses; its label (the pair and its
distance) on a point just above the sphere, lifted further where another
spot's label shown at the same time would overlap it (with a leader down
to the sphere); the segment (the gap) to the closest point on the other
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
        # pair path -> rows (frame, where, other side or None, label, cable a), scene units
        self._rows: dict[str, list[tuple[int, np.ndarray, np.ndarray | None, str, str]]] = {}
        # part index -> (rows of a pair, row, where (world, m), part pose), and cable index ->
        # (rows, row, where, s_b, the cable's centres): closest points still to find
        self._part_spots: dict[int, list[tuple]] = {}
        self._cable_spots: dict[int, list[tuple]] = {}
        self._lane: dict[str, str] = {}
        self._lanes: dict[str, tuple[list[int], list[str]]] = {}

    def add(self, frame: int, marks: list[Mark], cables: list[np.ndarray], poses: np.ndarray) -> bool:
        """The frame's clashes; True if any is shown."""
        u = self.unit
        now = set()
        for m in marks:
            path = pair_path(m.kind, m.a, m.b)
            now.add(path)
            rows = self._rows.setdefault(path, [])
            # the other side's closest point is found with the others of its part or cable at the end
            where = np.asarray(m.where, float)
            if m.kind in ("self", "cable-cable") and m.s_b is not None and m.b in self._cable_index:
                i = self._cable_index[m.b]
                self._cable_spots.setdefault(i, []).append((rows, len(rows), where, m.s_b,
                                                            np.array(cables[i], float)))
            elif m.kind in ("cable-structure", "keepout") and self.shapes is not None and m.b in self._part_index:
                k = self._part_index[m.b]
                self._part_spots.setdefault(k, []).append((rows, len(rows), where, np.asarray(poses[k], float)))
            rows.append((frame, where / u, None, f"{pair_text(m.a, m.b)}: {m.distance / u:.3g} {self.units}", m.a))
            if self._lane.get(path) != m.state:
                self._set_lane(path, frame, m.state)
        for path in [p for p, s in self._lane.items() if p not in now and s != "clear"]:
            self._set_lane(path, frame, "clear")
        return bool(now)

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
                frame, where, _, label, a = rows[i]
                rows[i] = (frame, where, other, label, a)
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
        for path, rows in self._rows.items():
            self._send_spot(rec, path, rows, n_f, index, radii[path], lifts[path])

    def _radius(self, cable: str) -> float:
        i = self._cable_index.get(cable)
        return 0.0 if i is None else self.built.cables[i].radius

    @staticmethod
    def _send_spot(rec: rr.RecordingStream, path: str, rows: list, n_f: int, index, radius: float,
                   lifts: np.ndarray) -> None:
        """One pair's spot (a wire sphere of `radius`, scene units, standing out of
        the cable; the cable, the gap and the part stay visible inside it), its
        label `lifts` (one per row, scene units) above its centre, and its gap."""
        frames, centres, labels, segs, anchors = [], [], [], [], []
        last = -2

        def empty(frame):
            frames.append(frame)
            centres.append(None)
            labels.append(None)
            segs.append(None)
            anchors.append(None)

        for (frame, where, other, label, _), lift in zip(rows, lifts):
            if frame > last + 1 and last >= 0 and last + 1 < n_f:
                empty(last + 1)
            frames.append(frame)
            centres.append(where)
            labels.append(label)
            segs.append(None if other is None else np.stack([where, other]))
            anchors.append(where + np.array([0.0, 0.0, lift]))
            last = frame
        if last + 1 < n_f:
            empty(last + 1)
        lengths = np.array([0 if c is None else 1 for c in centres], np.int32)
        pts = np.array([c for c in centres if c is not None]).reshape(-1, 3)
        tops = np.array([a for a in anchors if a is not None]).reshape(-1, 3)
        # the sizes go with the centres: an empty row has no sphere at all (a size without
        # a centre would draw one at the origin); the label rides on a point above the
        # sphere (lifted clear of its neighbours' labels, `label_lifts`), the segment to
        # the other side (emptied with the marker) in the same entity, and the style is
        # the views' default (`cablecheck.record.layout`): one chunk per pair, where a style and
        # a gap entity would make four
        e, p = rr.Ellipsoids3D, rr.Points3D
        columns = [column(e.descriptor_centers(), vec3(pts), lengths),
                   column(e.descriptor_half_sizes(), vec3(np.full((len(pts), 3), radius)), lengths),
                   column(p.descriptor_positions(), vec3(tops), lengths),
                   column(p.descriptor_labels(), strings([x for x in labels if x is not None]), lengths)]
        # per row: the gap (thick), and the line through it across the sphere and out of it
        # (thin: the gap's direction stays visible outside the marker); a lifted label's leader
        lines, widths, counts = [], [], []
        for seg, centre, top in zip(segs, centres, anchors):
            n = 0
            if seg is not None:
                lines.append(seg)
                widths.append(GAP_WIDTH * radius)
                n += 1
                d = seg[1] - seg[0]
                length = float(np.linalg.norm(d))
                if length > 1e-9 * radius:
                    d /= length
                    lines.append(np.stack([seg[0] - THROUGH * radius * d, seg[0] + THROUGH * radius * max(
                        1.0, length / radius + 0.3) * d]))
                    widths.append(THIN_WIDTH * radius)
                    n += 1
            if top is not None and top[2] - centre[2] > 1.01 * radius * LABEL_ABOVE:
                lines.append(np.stack([centre + np.array([0.0, 0.0, radius]), top]))
                widths.append(0.5 * THIN_WIDTH * radius)
                n += 1
            counts.append(n)
        if lines:
            pairs = np.stack(lines)                                      # (k, 2, 3)
            columns += [column(rr.LineStrips3D.descriptor_strips(),
                               strips(pairs.reshape(-1, 3), np.arange(0, 2 * len(pairs) + 1, 2)), counts),
                        column(rr.LineStrips3D.descriptor_radii(), floats(widths, np.float32), counts)]
        rec.send_columns(f"world/interference/{path}", indexes=index(frames), columns=columns)


LABEL_STEP = 0.03
"""The height of a spot's label in the views, as a fraction of the scene's
extent (a text line in the scene view; more in a clash's closer view):
labels of spots shown at once are stacked at least this far apart."""
LABEL_ABOVE = 1.15
"""A label's lift above its spot's centre, in sphere radii, with no neighbour in the way."""
CHAR_WIDTH = 0.55
"""A label's character width in label heights (the overlap test's width)."""
GAP_WIDTH = 0.2
THIN_WIDTH = 0.06
THROUGH = 1.7
"""The gap's line runs on to this many sphere radii from the spot's centre, past the sphere."""


def label_lifts(rows: dict[str, list], radii: dict[str, float], step: float) -> dict[str, np.ndarray]:
    """How far above its spot's centre each spot row's label goes (scene
    units; per pair path, one per row): just above the sphere, unless
    another label shown at that frame would then overlap it (taken as a box
    `step` high and :data:`CHAR_WIDTH` x `step` per character wide, across
    in the horizontal plane), then up by steps until it does not. Pairs in
    path order, so a pair's label keeps its place while the others come and
    go. Whether two labels overlap across is found for a frame's labels at
    once; a label then rises past those alone, in their order (a harness's
    frame shows hundreds of labels, each overlapping a few)."""
    lifts = {path: np.array([LABEL_ABOVE * radii[path]] * len(r)) for path, r in rows.items()}
    by_frame: dict[int, list[tuple[str, int]]] = {}
    for path in sorted(rows):
        for k, row in enumerate(rows[path]):
            by_frame.setdefault(row[0], []).append((path, k))
    for shown in by_frame.values():
        if len(shown) < 2:
            continue
        where = np.array([rows[path][k][1] for path, k in shown], float).reshape(-1, 3)
        half = np.array([0.5 * CHAR_WIDTH * step * len(rows[path][k][3]) for path, k in shown])
        # across[i, j]: labels i and j overlap in the horizontal plane, whatever their heights
        across = np.hypot(where[:, None, 0] - where[None, :, 0], where[:, None, 1] - where[None, :, 1]) \
            < half[:, None] + half[None, :]
        placed = np.empty(len(shown))                         # each label's height, once placed
        for i, (path, k) in enumerate(shown):
            z = where[i, 2] + lifts[path][k]
            under = placed[np.flatnonzero(across[i, :i])].tolist()
            moved = True
            while moved:
                moved = False
                for pz in under:
                    # (a label a whole step above another is clear of it: the test leaves
                    # a margin, or rounding in pz + step could keep it "overlapping" forever)
                    if abs(z - pz) < 0.999 * step:
                        z = pz + step
                        moved = True
            lifts[path][k] = z - where[i, 2]
            placed[i] = z
    return lifts
