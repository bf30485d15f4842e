"""The cables in the review recording: shaded capsules, each cable in its own colour and named.

`world/cables/<name>`: the cable as a chain of capsules at its true radius,
one per element, from body centre k to k + 1 each recorded frame (rerun's
`Capsules3D`, drawn solid: the viewer shades them, so over and under read
where a cable crosses itself or another; neighbouring capsules share the
sphere round the centre between them, so the chain reads as one round
cable), in the cable's own colour (`cablecheck.record.style.cable_colour`) except
the elements near a clash's worst place, which take its state colour
(soft, hard); and its name as a label on the cable, at a place along it
chosen apart from the other names and from its clashes.

The radius, the fill mode, the label's text and style are given once (the
first row); the colours, one per element, only where the states change;
the capsules' lengths only where one changed by more than :data:`STILL`
radii since they were last given (a cable hardly stretches: a capsule
then ends that little short of or beyond the next centre, inside the next
capsule's end sphere); the capsules' ends and turns (28 bytes an element,
where the tube of 838fb0d took 192 a body centre) and the label's place
at every frame that keeps the cable's shape: where its states change, or
where it moved by more than :data:`STILL` radii since the last shape kept
(a cable lying still is not stored again), at the run's regular samples.
At a frame recorded only because an event starts or ends there (not one
of the run's regular samples) a cable's shape is kept only if its state
colours change there: the colours change exactly when the clash does, and
a harness of many cables does not store every shape at every step. At a
frame between the regular samples (an event's worst instant, start or
end), only that event's cables are given, where their colours change or
they moved more than :data:`LIGHT_STILL` radii; the others' shapes and
colours stand, at most a sample old.
Buffered per frame and sent in one column per cable when the recording is
closed.

Not here: the clashes themselves (`cablecheck.record.marks`), the wear map
(`cablecheck.record.wearview`).
"""

from __future__ import annotations

import numpy as np
import pyarrow as pa
import rerun as rr

from cablecheck.build.built import Built
from cablecheck.checker.arrays import ranges
from cablecheck.record.columns import (
    Once,
    Sometimes,
    column,
    floats,
    quats,
    rgba,
    strings,
    times as sim_time,
    vec3,
)
from cablecheck.record.marks import Mark
from cablecheck.record.style import STATE_COLOURS, STATES, cable_colour, escape

_RANK = {s: n for n, s in enumerate(STATES)}
STILL = 0.05
"""A cable whose centres all moved less than this many radii (in each
coordinate) since its last kept shape is not stored again at a frame: the
viewer shows the kept one, off by a twentieth of the cable's thickness."""
LIGHT_STILL = 0.25
"""At an event's worst instant between the regular samples, its cables'
shapes are kept only where they moved more than this many radii since
their last kept shape: the spot then sits within a quarter of the
cable's thickness of the cable drawn (a harness's events deepen at most
steps: keeping every shape of theirs stored most cables at most steps)."""
LABEL_AT = (0.5, 0.3, 0.7, 0.4, 0.6, 0.2, 0.8)
"""Where along each cable (fraction of its length, in the scene's order of
cables, cycled) its name goes if nothing else is near there."""


def capsules(points: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A cable's elements as capsules in each frame, from its body centres
    `points` (F, P, 3): (F, P - 1, 3) translations (element k's first end,
    centre k), (F, P - 1, 4) unit quaternions (x, y, z, w, as rerun stores
    them) turning +z (a capsule's own axis) onto the element's direction,
    and (F, P - 1) lengths (centre k to centre k + 1). An element of no
    length keeps +z; one pointing down (-z) is turned half round x."""
    points = np.asarray(points, float)
    d = np.diff(points, axis=1)
    length = np.linalg.norm(d, axis=-1)
    u = np.zeros_like(d)
    some = length > 1e-12
    u[some] = d[some] / length[some][:, None]
    u[~some] = (0.0, 0.0, 1.0)
    # the half-way quaternion between +z and u: (z x u, 1 + z . u), normalised
    q = np.stack([-u[..., 1], u[..., 0], np.zeros_like(length), 1.0 + u[..., 2]], axis=-1)
    down = q[..., 3] < 1e-9
    q[down] = (1.0, 0.0, 0.0, 0.0)
    q /= np.linalg.norm(q, axis=-1, keepdims=True)
    return points[:, :-1], q, length


def label_places(firsts: list[np.ndarray], avoid: list[np.ndarray], apart: float) -> list[int]:
    """The body centre of each cable that carries its name: the interior
    centre nearest :data:`LABEL_AT`'s place for it among those at least
    `apart` from the names placed before it and not next to an element in
    `avoid` (a clash's), else the one farthest from them (`firsts`: each
    cable's centres (P, 3) in its first frame)."""
    placed: list[np.ndarray] = []
    chosen = []
    for i, (pts, bad) in enumerate(zip(firsts, avoid)):
        n_p = len(pts)
        cand = np.arange(1, n_p - 1) if n_p > 2 else np.arange(n_p)
        if len(bad) and bad.any():
            near = np.zeros(n_p, bool)
            near[:-1] |= bad
            near[1:] |= bad
            if (~near[cand]).any():
                cand = cand[~near[cand]]
        far = (np.min(np.linalg.norm(pts[cand][:, None] - np.array(placed)[None], axis=-1), axis=1)
               if placed else np.full(len(cand), np.inf))
        seg = np.linalg.norm(np.diff(pts, axis=0), axis=1)
        s = np.concatenate([[0.0], np.cumsum(seg)])
        want = abs(s[cand] / max(s[-1], 1e-300) - LABEL_AT[i % len(LABEL_AT)])
        ok = far >= apart
        k = int(cand[ok][np.argmin(want[ok])] if ok.any() else cand[np.argmax(far)])
        chosen.append(k)
        placed.append(pts[k])
    return chosen


class CableFrames:
    """Every cable's shape and element states, frame by frame.

    Args:
      built: the built scene.
      unit: metres per scene unit.
    """

    def __init__(self, built: Built, unit: float):
        self.built, self.unit = built, unit
        self._index = {c.name: i for i, c in enumerate(built.cables)}
        self._names = [c.name for c in built.cables]
        element_s = [0.5 * (c.rest_s[1:] + c.rest_s[:-1]) for c in built.cables]
        # how far along its cable a mark colours elements, each cable's
        self._near = np.array([max(2.0 * c.element_length, 3.0 * c.radius) for c in built.cables], float)
        # every cable's element places in one array, and laid apart along one axis to search them all at once
        sizes = np.array([len(e) for e in element_s], np.int64)
        self._ends = np.cumsum(sizes)
        self._starts = self._ends - sizes
        self._all_s = np.concatenate(element_s) if element_s else np.zeros(0)
        length = np.array([e[-1] - e[0] if len(e) else 0.0 for e in element_s]) + 4.0 * self._near + 1.0
        first = np.array([e[0] if len(e) else 0.0 for e in element_s])
        self._shift = np.cumsum(length) - length - first
        self._flat_s = self._all_s + np.repeat(self._shift, sizes)
        self._pad = 1e-6 * (1.0 + float(np.abs(self._flat_s).max(initial=0.0)))
        self._still = [STILL * c.radius / unit for c in built.cables]
        self._points: list[list[np.ndarray]] = [[] for _ in built.cables]
        self._states: list[list[np.ndarray]] = [[] for _ in built.cables]
        self._frames: list[list[int]] = [[] for _ in built.cables]

    def add(self, frame: int, cables: list[np.ndarray], marks: list[Mark], sampled: bool = True,
            keep: set[str] | None = None) -> None:
        """One frame: body centres (metres) and the clashes that colour them.
        A cable's shape is kept where its states change, and at a `sampled`
        frame where any centre moved more than :data:`STILL` radii since its
        last kept shape (a frame recorded only because an event starts or
        ends there, not `sampled`, keeps it only where its states change);
        with `keep` (a frame between the regular samples), a cable not named
        there keeps its last shape and colours, and one named there is kept
        where its states change or it moved more than :data:`LIGHT_STILL`
        radii (an event's worst instant, start or end: its own cables)."""
        state = np.split(self._element_states(marks), self._ends[:-1])
        u = self.unit
        for i, (pts, name) in enumerate(zip(cables, self._names)):
            pts = np.asarray(pts, float) / u
            if keep is not None and name not in keep and self._states[i]:
                continue                    # between samples, a cable of no updated pair stands
            taken = sampled and (keep is None or name in keep)
            still = self._still[i] * (1.0 if keep is None else LIGHT_STILL / STILL)
            if self._states[i] and np.array_equal(self._states[i][-1], state[i]) and (
                    not taken or np.abs(pts - self._points[i][-1]).max() <= still):
                continue
            self._frames[i].append(frame)
            self._points[i].append(pts)
            self._states[i].append(state[i])

    def _element_states(self, marks: list[Mark]) -> np.ndarray:
        """Every cable's element states (all cables' elements in one array):
        the highest rank of the marks on each, a mark colouring the elements
        within its cable's reach (`_near`) of its place on cable a (all of a
        taut cable's) and of its place on cable b; all marks at once."""
        out = np.zeros(int(self._ends[-1]), np.uint8)
        places = []                                      # the frame's marks' places: (cable, s, rank, whole)
        for m in marks:
            if m.a in self._index:
                places.append((self._index[m.a], m.s, _RANK[m.state], m.kind == "taut"))
            if m.s_b is not None and m.b in self._index:
                places.append((self._index[m.b], m.s_b, _RANK[m.state], False))
        if not places:
            return out
        cab, s, rank, whole = (np.array(x) for x in zip(*places))
        s, rank = s.astype(float), rank.astype(np.uint8)
        # each mark's elements: a generous range of the cable's (sorted) element places, then the test itself
        first = self._starts[cab]
        count = self._ends[cab] - first
        lo = np.where(whole, first, first + np.maximum(
            np.searchsorted(self._flat_s, s + self._shift[cab] - self._near[cab] - self._pad, "left") - first, 0))
        hi = np.where(whole, first + count, np.minimum(
            np.searchsorted(self._flat_s, s + self._shift[cab] + self._near[cab] + self._pad, "right"),
            first + count))
        n = np.maximum(hi - lo, 0)
        row = np.repeat(np.arange(len(cab)), n)
        el = ranges(lo, n)
        ok = whole[row] | (np.abs(self._all_s[el] - s[row]) <= self._near[cab[row]])
        np.maximum.at(out, el[ok], rank[row[ok]])
        return out

    def send(self, rec: rr.RecordingStream, times: np.ndarray) -> None:
        """Every cable's frames, one column per cable (`times`: each frame's,
        seconds): its capsules, colours and name (see the module docstring)."""
        kept = [i for i in range(len(self.built.cables)) if self._points[i]]
        if not kept:
            return
        firsts = [self._points[i][0] for i in kept]
        every = np.concatenate(firsts)
        apart = 0.08 * float(np.linalg.norm(every.max(axis=0) - every.min(axis=0)))
        places = label_places(firsts, [np.stack(self._states[i]).max(axis=0) > 0 for i in kept], apart)
        state_rgb = np.array([STATE_COLOURS[s] for s in STATES], np.uint32)
        c, p = rr.Capsules3D, rr.Points3D
        solid = rr.components.FillModeBatch(rr.components.FillMode.Solid).as_arrow_array()
        for i, k in zip(kept, places):
            cable = self.built.cables[i]
            r = cable.radius / self.unit
            points = np.stack(self._points[i])                          # (F, P, 3)
            n_f, n_e = points.shape[0], points.shape[1] - 1
            ends, turns, lengths = capsules(points)
            states = np.stack(self._states[i])                          # (F, P - 1): one per element
            changed = np.ones(n_f, bool)
            changed[1:] = (states[1:] != states[:-1]).any(axis=1)
            palette = state_rgb.copy()
            palette[0] = cable_colour(i)
            colours = rgba(palette[states[changed].reshape(-1)])
            stretched = np.zeros(n_f, bool)                             # lengths given again
            stretched[0], given = True, lengths[0]
            for f in range(1, n_f):
                if np.abs(lengths[f] - given).max() > STILL * r:
                    stretched[f], given = True, lengths[f]
            label = points[:, k]                 # the point hides inside the cable; its label shows beside it
            rec.send_columns(f"world/cables/{escape(cable.name)}", indexes=[sim_time(times[self._frames[i]])], columns=[
                column(c.descriptor_translations(), vec3(ends.reshape(-1, 3)), np.full(n_f, n_e)),
                column(c.descriptor_quaternions(), quats(turns.reshape(-1, 4)), np.full(n_f, n_e)),
                Sometimes(c.descriptor_lengths(), floats(lengths[stretched].reshape(-1), np.float32), stretched,
                          np.full(int(stretched.sum()), n_e)),
                Once(c.descriptor_radii(), floats([r], np.float32), n_f),
                Once(c.descriptor_fill_mode(), solid, n_f),
                Sometimes(c.descriptor_colors(), colours, changed, np.full(int(changed.sum()), n_e)),
                column(p.descriptor_positions(), vec3(label)),
                Once(p.descriptor_labels(), strings([cable.name]), n_f),
                Once(p.descriptor_colors(), rgba([cable_colour(i)]), n_f),
                Once(p.descriptor_radii(), floats([0.5 * r], np.float32), n_f),
                Once(p.descriptor_show_labels(), pa.array([True]), n_f)])
