"""The cables in the review recording: each one's centreline per frame.

`world/cables/<name>`: the cable's body centres at its true radius, one
strip per run of elements in one state, so only the elements near a
clash's worst place take its state colour (soft, hard); the rest stays the
clear colour. Buffered per frame and sent in one column per cable when the
recording is closed. At a frame recorded only because an event starts or
ends there (not one of the run's regular samples) a cable's shape is kept
only if its state colours change there: the colours change exactly when
the clash does, and a harness of many cables does not store every shape at
every step.

Not here: the clashes themselves (`sim.record.marks`), the wear map
(`sim.record.wearview`).
"""

from __future__ import annotations

import numpy as np
import pyarrow as pa
import rerun as rr

from sim.build import Built
from sim.record.columns import STRIP, Once, column, floats, rgba, strips
from sim.record.columns import times as sim_time
from sim.record.marks import Mark
from sim.record.style import STATE_COLOURS, STATES, escape

_RANK = {s: n for n, s in enumerate(STATES)}


def runs(points: np.ndarray, states: np.ndarray) -> tuple[pa.Array, np.ndarray, np.ndarray]:
    """A cable's frames as line strips, one per run of elements of one state:
    (strips as rerun's `LineStrip3D` arrow array, (R,) state per strip,
    (F,) strips per frame), from `points` (F, N + 1, 3) and `states` (F, N).
    A clear cable is one strip of its body centres; a clash adds two breaks.
    Built in arrow directly: rerun's converter takes strips one at a time."""
    n_f, n = states.shape
    if n == 0 or n_f == 0:
        return pa.array([], type=STRIP), np.zeros(0, np.uint8), np.zeros(n_f, np.int64)
    start = np.ones((n_f, n), bool)
    start[:, 1:] = states[:, 1:] != states[:, :-1]
    frame, first = np.nonzero(start)                        # strips in frame order, then along the cable
    counts = np.bincount(frame, minlength=n_f)
    last = np.empty_like(first)                             # a strip runs to the next one's start (or the end)
    last[:-1] = first[1:]
    same = np.zeros(len(first), bool)
    same[:-1] = frame[1:] == frame[:-1]
    last[~same] = n
    sizes = last - first + 1                                # points: its elements' ends
    offsets = np.zeros(len(sizes) + 1, np.int32)
    np.cumsum(sizes, out=offsets[1:])
    idx = np.repeat(frame * (n + 1) + first - offsets[:-1], sizes) + np.arange(offsets[-1])
    return strips(np.asarray(points, np.float32).reshape(-1, 3)[idx], offsets), states[frame, first], counts


class CableFrames:
    """Every cable's shape and element states, frame by frame.

    Args:
      built: the built scene.
      unit: metres per scene unit.
    """

    def __init__(self, built: Built, unit: float):
        self.built, self.unit = built, unit
        self._index = {c.name: i for i, c in enumerate(built.cables)}
        self._element_s = [0.5 * (c.rest_s[1:] + c.rest_s[:-1]) for c in built.cables]
        self._near = [max(2.0 * c.element_length, 3.0 * c.radius) for c in built.cables]
        self._points: list[list[np.ndarray]] = [[] for _ in built.cables]
        self._states: list[list[np.ndarray]] = [[] for _ in built.cables]
        self._frames: list[list[int]] = [[] for _ in built.cables]

    def add(self, frame: int, cables: list[np.ndarray], marks: list[Mark], sampled: bool = True) -> None:
        """One frame: body centres (metres) and the clashes that colour them.
        A frame that is not `sampled` (recorded only because an event starts
        or ends there) keeps a cable's shape only where its states change."""
        state = [np.zeros(len(c.rest_s) - 1, np.uint8) for c in self.built.cables]
        for m in marks:
            self._state_near(state, m.a, m.s, _RANK[m.state], whole=(m.kind == "taut"))
            if m.s_b is not None and m.b in self._index:
                self._state_near(state, m.b, m.s_b, _RANK[m.state], whole=False)
        u = self.unit
        for i, pts in enumerate(cables):
            if not sampled and self._states[i] and np.array_equal(self._states[i][-1], state[i]):
                continue
            self._frames[i].append(frame)
            self._points[i].append(np.asarray(pts, float) / u)
            self._states[i].append(state[i])

    def _state_near(self, state: list[np.ndarray], cable: str, s: float, rank: int, whole: bool) -> None:
        i = self._index.get(cable)
        if i is None:
            return
        near = np.ones(len(state[i]), bool) if whole else np.abs(self._element_s[i] - s) <= self._near[i]
        state[i][near] = np.maximum(state[i][near], rank)

    def send(self, rec: rr.RecordingStream, times: np.ndarray) -> None:
        """Every cable's frames, one column per cable (`times`: each frame's,
        seconds), its radius in the first row (one chunk per cable)."""
        colours = np.array(rgba([STATE_COLOURS[s] for s in STATES]).to_pylist(), np.uint32)
        for i, cable in enumerate(self.built.cables):
            if not self._points[i]:
                continue
            lines, states, counts = runs(np.stack(self._points[i]), np.stack(self._states[i]))
            rec.send_columns(f"world/cables/{escape(cable.name)}", indexes=[sim_time(times[self._frames[i]])],
                             columns=[column(rr.LineStrips3D.descriptor_strips(), lines, counts),
                                      column(rr.LineStrips3D.descriptor_colors(), pa.array(colours[states]), counts),
                                      Once(rr.LineStrips3D.descriptor_radii(),
                                           floats([cable.radius / self.unit], np.float32), len(counts))])
