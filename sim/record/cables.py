"""The cables in the review recording: shaded tubes, each in its own colour and named.

`world/cables/<name>`: the cable as a tube at its true radius, a mesh swept
along its body centres each recorded frame (a ring of :data:`RING`
vertices round each centre, turned along the cable by parallel transport
so the tube does not twist, the vertex normals pointing outward so the
viewer shades it: over and under read where a cable crosses itself or
another), in the cable's own colour (`sim.record.style.cable_colour`)
except the elements near a clash's worst place, which take its state
colour (soft, hard); and its name as a label on the cable, at a place
along it chosen apart from the other cables' names and from its clashes.

The tube's triangles, the label's text and style are given once (the first
row); the vertex colours only where the states change; the vertices,
normals and the label's place at every frame that keeps the cable's
shape: where its states change, or where it moved by more than
:data:`STILL` radii since the last shape kept (a cable lying still is not
stored again), at the run's regular samples. At a frame recorded only
because an event starts or ends there (not one of the run's regular
samples) a cable's shape is kept only if its state colours change there:
the colours change exactly when the clash does, and a harness of many
cables does not store every shape at every step. Buffered per frame and
sent in one column per cable when the recording is closed.

Not here: the clashes themselves (`sim.record.marks`), the wear map
(`sim.record.wearview`).
"""

from __future__ import annotations

import numpy as np
import pyarrow as pa
import rerun as rr

from sim.build import Built
from sim.record.columns import Once, Sometimes, column, floats, indices3, rgba, strings, vec3
from sim.record.columns import times as sim_time
from sim.record.marks import Mark
from sim.record.style import STATE_COLOURS, STATES, cable_colour, escape

_RANK = {s: n for n, s in enumerate(STATES)}
RING = 8
"""Vertices round each body centre of a cable's tube (an octagon: shaded,
it reads as round; each more costs 24 bytes per body per frame)."""
STILL = 0.05
"""A cable whose centres all moved less than this many radii (in each
coordinate) since its last kept shape is not stored again at a frame: the
viewer shows the kept one, off by less than its octagon's own departure
from a circle (0.08 radii)."""
LABEL_AT = (0.5, 0.3, 0.7, 0.4, 0.6, 0.2, 0.8)
"""Where along each cable (fraction of its length, in the scene's order of
cables, cycled) its name goes if nothing else is near there."""


def _unit(v: np.ndarray, fallback: np.ndarray | None = None) -> np.ndarray:
    n = np.linalg.norm(v, axis=-1, keepdims=True)
    with np.errstate(invalid="ignore", divide="ignore"):
        u = v / n
    bad = ~(n[..., 0] > 1e-12)
    if bad.any():
        u[bad] = np.array([1.0, 0.0, 0.0]) if fallback is None else fallback[bad]
    return u


def _qmul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Quaternion products a b (w, x, y, z last axis), elementwise."""
    aw, ax, ay, az = np.moveaxis(a, -1, 0)
    bw, bx, by, bz = np.moveaxis(b, -1, 0)
    return np.stack([aw * bw - ax * bx - ay * by - az * bz, aw * bx + ax * bw + ay * bz - az * by,
                     aw * by - ax * bz + ay * bw + az * bx, aw * bz + ax * by - ay * bx + az * bw], axis=-1)


def _rotate(q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """v turned by the unit quaternions q, elementwise."""
    w, u = q[..., :1], q[..., 1:]
    c = np.cross(u, v)
    return v + 2.0 * w * c + 2.0 * np.cross(u, c)


def tangents(points: np.ndarray) -> np.ndarray:
    """(F, P, 3) unit tangents at the body centres `points` (F, P, 3): the
    mean direction of the two elements meeting there (an end: its element's)."""
    e = _unit(np.diff(points, axis=1))
    t = np.empty_like(points)
    t[:, 0], t[:, -1] = e[:, 0], e[:, -1]
    if points.shape[1] > 2:
        t[:, 1:-1] = _unit(e[:, :-1] + e[:, 1:], e[:, 1:])
    return t


def transported_normals(t: np.ndarray) -> np.ndarray:
    """(F, P, 3) unit normals to the tangents `t` (F, P, 3), carried along
    each cable by parallel transport (each turned by the least rotation
    that takes one tangent to the next, so the tube's rings do not twist
    about the cable): the rotations' running products by doubling, in
    log2(P) vectorised passes (no loop over the points)."""
    n_f, n_p, _ = t.shape
    a, b = t[:, :-1], t[:, 1:]
    q = np.concatenate([1.0 + np.sum(a * b, axis=-1, keepdims=True), np.cross(a, b)], axis=-1)
    flip = q[..., 0] < 1e-9                                  # a half turn: about any normal to a
    if flip.any():
        side = np.where(np.abs(a[flip][:, :1]) < 0.9, np.array([1.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.0]))
        q[flip] = np.concatenate([np.zeros((flip.sum(), 1)), _unit(np.cross(a[flip], side))], axis=-1)
    q = _unit(q)
    run = np.concatenate([np.tile([1.0, 0.0, 0.0, 0.0], (n_f, 1, 1)), q], axis=1)   # (F, P, 4): Q_k = q_k ... q_1
    step = 1
    while step < n_p:
        run[:, step:] = _qmul(run[:, step:], run[:, :-step].copy())
        step *= 2
    run = _unit(run)
    t0 = t[:, 0]
    up = np.where(np.abs(t0[:, 2:]) < 0.9, np.array([0.0, 0.0, 1.0]), np.array([1.0, 0.0, 0.0]))
    n0 = _unit(np.cross(np.cross(t0, up), t0))               # the first ring's, toward up
    n = _rotate(run, np.broadcast_to(n0[:, None], t.shape))
    return _unit(n - np.sum(n * t, axis=-1, keepdims=True) * t)


def tube(points: np.ndarray, radius: float, ring: int = RING) -> tuple[np.ndarray, np.ndarray]:
    """A cable's tube in each frame: (F, V, 3) vertices and (F, V, 3) unit
    outward normals, V = P x `ring` + 2, from its body centres `points`
    (F, P, 3). Vertex k x ring + j lies on the circle of `radius` round
    centre k, square to the tangent there, at angle 2 pi j / ring from the
    transported normal; the last two close the ends, `radius` beyond the
    first and the last centre along the cable (their normals along it)."""
    points = np.asarray(points, float)
    n_f, n_p, _ = points.shape
    t = tangents(points)
    n = transported_normals(t)
    b = np.cross(t, n)
    angle = 2.0 * np.pi * np.arange(ring) / ring
    out = np.cos(angle)[None, None, :, None] * n[:, :, None] + np.sin(angle)[None, None, :, None] * b[:, :, None]
    normals = np.empty((n_f, n_p * ring + 2, 3))
    normals[:, :-2] = out.reshape(n_f, -1, 3)
    normals[:, -2], normals[:, -1] = -t[:, 0], t[:, -1]
    vertices = np.empty_like(normals)
    vertices[:, :-2] = np.repeat(points, ring, axis=1)
    vertices[:, -2], vertices[:, -1] = points[:, 0], points[:, -1]
    vertices += radius * normals
    return vertices, normals


def tube_triangles(n_points: int, ring: int = RING) -> np.ndarray:
    """(T, 3) vertex indices of :func:`tube`'s triangles, wound so that
    their normals point outward: two per quad between neighbouring rings,
    a fan to each end's closing vertex."""
    k, j = np.meshgrid(np.arange(n_points - 1), np.arange(ring), indexing="ij")
    a = k * ring + j
    b = k * ring + (j + 1) % ring
    c, d = a + ring, b + ring
    sides = np.stack([np.stack([a, b, c], -1), np.stack([b, d, c], -1)], axis=2).reshape(-1, 3)
    j = np.arange(ring)
    first, last = n_points * ring, n_points * ring + 1
    start = np.stack([np.full(ring, first), (j + 1) % ring, j], axis=-1)
    end = np.stack([np.full(ring, last), (n_points - 1) * ring + j, (n_points - 1) * ring + (j + 1) % ring], axis=-1)
    return np.concatenate([sides, start, end]).astype(np.uint32)


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
        self._element_s = [0.5 * (c.rest_s[1:] + c.rest_s[:-1]) for c in built.cables]
        self._near = [max(2.0 * c.element_length, 3.0 * c.radius) for c in built.cables]
        self._still = [STILL * c.radius / unit for c in built.cables]
        self._points: list[list[np.ndarray]] = [[] for _ in built.cables]
        self._states: list[list[np.ndarray]] = [[] for _ in built.cables]
        self._frames: list[list[int]] = [[] for _ in built.cables]

    def add(self, frame: int, cables: list[np.ndarray], marks: list[Mark], sampled: bool = True) -> None:
        """One frame: body centres (metres) and the clashes that colour them.
        A cable's shape is kept where its states change, and at a `sampled`
        frame where any centre moved more than :data:`STILL` radii since its
        last kept shape (a frame recorded only because an event starts or
        ends there, not `sampled`, keeps it only where its states change)."""
        state = [np.zeros(len(c.rest_s) - 1, np.uint8) for c in self.built.cables]
        for m in marks:
            self._state_near(state, m.a, m.s, _RANK[m.state], whole=(m.kind == "taut"))
            if m.s_b is not None and m.b in self._index:
                self._state_near(state, m.b, m.s_b, _RANK[m.state], whole=False)
        u = self.unit
        for i, pts in enumerate(cables):
            pts = np.asarray(pts, float) / u
            if self._states[i] and np.array_equal(self._states[i][-1], state[i]) and (
                    not sampled or np.abs(pts - self._points[i][-1]).max() <= self._still[i]):
                continue
            self._frames[i].append(frame)
            self._points[i].append(pts)
            self._states[i].append(state[i])

    def _state_near(self, state: list[np.ndarray], cable: str, s: float, rank: int, whole: bool) -> None:
        i = self._index.get(cable)
        if i is None:
            return
        near = np.ones(len(state[i]), bool) if whole else np.abs(self._element_s[i] - s) <= self._near[i]
        state[i][near] = np.maximum(state[i][near], rank)

    def send(self, rec: rr.RecordingStream, times: np.ndarray) -> None:
        """Every cable's frames, one column per cable (`times`: each frame's,
        seconds): its tube, colours and name (see the module docstring)."""
        kept = [i for i in range(len(self.built.cables)) if self._points[i]]
        if not kept:
            return
        firsts = [self._points[i][0] for i in kept]
        every = np.concatenate(firsts)
        apart = 0.08 * float(np.linalg.norm(every.max(axis=0) - every.min(axis=0)))
        places = label_places(firsts, [np.stack(self._states[i]).max(axis=0) > 0 for i in kept], apart)
        state_rgb = np.array([STATE_COLOURS[s] for s in STATES], np.uint32)
        m, p = rr.Mesh3D, rr.Points3D
        for i, k in zip(kept, places):
            cable = self.built.cables[i]
            r = cable.radius / self.unit
            points = np.stack(self._points[i])                          # (F, P, 3)
            n_f, n_p, _ = points.shape
            vertices, normals = tube(points, r)
            # a ring's state: the worse of its two elements'; the ends' closing vertices their ring's
            states = np.stack(self._states[i])
            ring = np.zeros((n_f, n_p), np.uint8)
            ring[:, :-1] = states
            ring[:, 1:] = np.maximum(ring[:, 1:], states)
            changed = np.ones(n_f, bool)
            changed[1:] = (ring[1:] != ring[:-1]).any(axis=1)
            palette = state_rgb.copy()
            palette[0] = cable_colour(i)
            rows = ring[changed]
            per_vertex = np.concatenate([np.repeat(rows, RING, axis=1), rows[:, :1], rows[:, -1:]], axis=1)
            colours = rgba(palette[per_vertex.reshape(-1)])
            label = points[:, k]                 # the point hides inside the tube; its label shows beside it
            v = vertices.shape[1]
            rec.send_columns(f"world/cables/{escape(cable.name)}", indexes=[sim_time(times[self._frames[i]])], columns=[
                column(m.descriptor_vertex_positions(), vec3(vertices.reshape(-1, 3)), np.full(n_f, v)),
                column(m.descriptor_vertex_normals(), vec3(normals.reshape(-1, 3)), np.full(n_f, v)),
                Once(m.descriptor_triangle_indices(), indices3(tube_triangles(n_p)), n_f),
                Sometimes(m.descriptor_vertex_colors(), colours, changed, np.full(int(changed.sum()), v)),
                column(p.descriptor_positions(), vec3(label)),
                Once(p.descriptor_labels(), strings([cable.name]), n_f),
                Once(p.descriptor_colors(), rgba([cable_colour(i)]), n_f),
                Once(p.descriptor_radii(), floats([0.5 * r], np.float32), n_f),
                Once(p.descriptor_show_labels(), pa.array([True]), n_f)])
