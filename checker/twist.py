"""Twist of a cable: read from the frames of its held ends by parallel
transport, or gathered from the simulated rod's twist along it.

A cable clamped at both ends (its end tangents and the roll about them held
by the bodies it rides on) is twisted by the rotation of one end's frame
about the cable relative to the other's. The start end's frame is carried
along the centreline by parallel transport (the rotation-minimising,
twist-free frame: Bishop 1975; Bergou et al. 2008, "Discrete elastic rods")
and compared with the end's frame at the end tangent; the signed angle
between them about the end tangent is the twist the ends wind in, whatever
the centreline's bends (a bent but untwisted cable reads 0).

- :func:`transport` carries vectors along polylines, vectorised over states
  and edges: each edge gets a frame vector of its own (perpendicular to its
  tangent) and the angle between consecutive frames after the minimal
  rotation taking one tangent to the next; the transported vector's angle
  is their sum, so no loop runs along the cable.
- :func:`twist_angle` is that comparison for many states, in (-pi, pi].
- :class:`TwistMeter` accumulates one cable's angle step to step (each
  change wrapped to (-pi, pi]), so winding past half a turn is counted, and
  keeps its largest absolute twist; :func:`update_many` updates several
  cables' meters with one :func:`twist_angle` call per point count.

Zero-length edges take the tangent of the edge before them (or after, at the
start). A cusp (an edge folded back onto the one before) has no minimal
rotation; it is treated as a half turn about an arbitrary axis.

- :func:`carry_reference` carries a discrete elastic rod's reference
  frames and reference twists (MuJoCo's `mjData.plastic`, which holds them
  for the positions at the start of the step just taken) to the positions
  the step ended at, so the rod's twist can be read at the state checked.
- :class:`RodTwistMeter` keeps what a run reports of the twist a simulated
  rod carries (its twist at each interior vertex, step by step): the
  largest absolute twist end to end, and per vertex the largest moment and
  twist per length. A run with dynamics reads twist this way; the frames
  of the held ends are what a run without dynamics has.

This module does not know which ends are clamped, bodies or MuJoCo: it takes
the end frames it is given as reference vectors in world coordinates, and
the rod's twists as arrays.
"""

from __future__ import annotations

import numpy as np

from cablecheck.checker.closest import cross

_TINY = 1e-300


def _dot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.einsum("...i,...i->...", a, b)


def _norm(x: np.ndarray, keepdims: bool = False) -> np.ndarray:
    """``np.linalg.norm(x, axis=-1)`` for real arrays: its formula and bits."""
    return np.sqrt(np.add.reduce(x * x, axis=-1, keepdims=keepdims))


def wrap(angle: np.ndarray) -> np.ndarray:
    """Angles wrapped to (-pi, pi]."""
    return np.pi - np.mod(np.pi - angle, 2.0 * np.pi)


def _tangents(points: np.ndarray) -> np.ndarray:
    """(S, m, 3) unit edge tangents; zero-length edges take a neighbour's."""
    e = np.diff(points, axis=1)
    length = _norm(e)
    scale = np.abs(points).max(axis=(1, 2), keepdims=True)[:, :, 0] + _TINY
    ok = length > 1e-12 * scale
    if ok.all():                                                    # no edge to fill (the usual case)
        return e / length[:, :, None]
    idx = np.where(ok, np.arange(e.shape[1])[None, :], 0)
    idx = np.maximum.accumulate(idx, axis=1)                        # forward fill
    first = np.argmax(ok, axis=1)                                   # leading zero edges: the first good one
    idx = np.where(np.arange(e.shape[1])[None, :] < first[:, None], first[:, None], idx)
    t = e / np.where(ok, length, 1.0)[:, :, None]
    t = np.take_along_axis(t, idx[:, :, None], axis=1)
    bad = ~ok.any(axis=1)                                           # a cable of no length: any axis
    t[bad] = [1.0, 0.0, 0.0]
    return t


def _normal_to(t: np.ndarray) -> np.ndarray:
    """(..., 3) unit vectors perpendicular to unit `t`, from the axis least aligned with it."""
    axis = np.eye(3)[np.argmin(np.abs(t), axis=-1)]
    n = cross(t, axis)
    return n / _norm(n, keepdims=True)


def _signed_angle(a: np.ndarray, b: np.ndarray, axis: np.ndarray) -> np.ndarray:
    """Angle from `a` to `b` about unit `axis` (both taken perpendicular to it)."""
    return np.arctan2(_dot(cross(a, b), axis), _dot(a, b) - _dot(a, axis) * _dot(b, axis))


def _rotate_min(v: np.ndarray, t0: np.ndarray, t1: np.ndarray) -> np.ndarray:
    """`v` rotated by the least rotation taking unit `t0` to unit `t1`
    (Rodrigues' formula with c = t0 x t1, d = t0 . t1); a cusp (t1 = -t0)
    turns half a turn about a normal of t0."""
    c = cross(t0, t1)
    d = _dot(t0, t1)
    folded = d < -1.0 + 1e-12
    out = v * d[..., None] + cross(c, v) + c * (_dot(c, v) / np.where(folded, 1.0, 1.0 + d))[..., None]
    if folded.any():
        a = _normal_to(t0)
        out = np.where(folded[..., None], 2.0 * a * _dot(a, v)[..., None] - v, out)
    return out


def transport(points: np.ndarray, vectors: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Parallel transport of vectors from the first edge of polylines to the last.

    Args:
      points: (S, n, 3) polylines (n >= 2).
      vectors: (S, 3) vectors at the first edge (their part along its
        tangent is dropped; they need not be unit).

    Returns:
      t_end: (S, 3) unit tangent of the last edge.
      moved: (S, 3) the unit vectors transported to it (perpendicular to it).

    Method: with f_k a unit normal of edge k of its own (`_normal_to`) and
    P_k the least rotation from tangent k to tangent k + 1, the angle of the
    transported vector from f_k grows by beta_k, the angle from f_{k+1} to
    P_k f_k; so at the last edge it is the start's angle plus sum(beta_k).
    """
    points = np.asarray(points, float)
    t = _tangents(points)
    f = _normal_to(t)
    beta = _signed_angle(f[:, 1:], _rotate_min(f[:, :-1], t[:, :-1], t[:, 1:]), t[:, 1:])
    alpha = _signed_angle(f[:, 0], np.asarray(vectors, float), t[:, 0])
    phi = alpha + beta.sum(axis=1)
    t_end, f_end = t[:, -1], f[:, -1]
    moved = np.cos(phi)[:, None] * f_end + np.sin(phi)[:, None] * cross(t_end, f_end)
    return t_end, moved


def twist_angle(points: np.ndarray, start_ref: np.ndarray, end_ref: np.ndarray) -> np.ndarray:
    """(S,) twist in (-pi, pi]: the angle about the last edge's tangent from the
    start end's reference vector, parallel transported along the polyline, to
    the end's reference vector.

    Args:
      points: (S, n, 3) cable centrelines from start to end.
      start_ref, end_ref: (S, 3) vectors fixed in the start and end frames
        (roughly perpendicular to the cable there), in world coordinates.
    """
    t_end, moved = transport(points, start_ref)
    return _signed_angle(moved, np.asarray(end_ref, float), t_end)


def reference_vectors(points: np.ndarray, start_rot: np.ndarray, end_rot: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Reference vectors fixed in the end frames that read no twist in this state.

    Args:
      points: (n, 3) centreline in the reference state (e.g. t = 0).
      start_rot, end_rot: (3, 3) end frames' rotations (frame to world).

    Returns (3,) each, in the frames' own coordinates: a normal of the first
    edge, and that normal transported to the last edge.
    """
    points = np.asarray(points, float)[None]
    u = _normal_to(_tangents(points)[:, 0])
    _, v = transport(points, u)
    return np.asarray(start_rot, float).T @ u[0], np.asarray(end_rot, float).T @ v[0]


class TwistMeter:
    """One cable's twist accumulated over time and its largest absolute value.

    Built from the first state (which reads 0: reference vectors fixed in
    the end frames by `reference_vectors`); `update` takes later states in
    order. A change between consecutive states is wrapped to (-pi, pi], so
    the ends may wind any number of turns as long as no two consecutive
    states differ by half a turn.

    Attributes:
      twist: current twist, radians.
      max_abs: largest absolute twist so far, radians.
    """

    def __init__(self, points: np.ndarray, start_rot: np.ndarray, end_rot: np.ndarray):
        self._u, self._v = reference_vectors(points, start_rot, end_rot)
        self._last = 0.0
        self.twist = 0.0
        self.max_abs = 0.0

    def update(self, points: np.ndarray, start_rot: np.ndarray, end_rot: np.ndarray) -> np.ndarray:
        """Take S consecutive states: centrelines (S, n, 3) and end frames'
        rotations (S, 3, 3) each; return their (S,) twists, radians."""
        return self.take(twist_angle(points, *self.references(start_rot, end_rot)))

    def references(self, start_rot: np.ndarray, end_rot: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(S, 3) each: the reference vectors in world coordinates for the
        end frames' rotations (S, 3, 3) (what :func:`twist_angle` compares)."""
        return np.asarray(start_rot, float) @ self._u, np.asarray(end_rot, float) @ self._v

    def take(self, angles: np.ndarray) -> np.ndarray:
        """Take the (S,) angles of S consecutive states from :func:`twist_angle`
        (in (-pi, pi]); return their (S,) accumulated twists, radians."""
        twist = self.twist + np.cumsum(wrap(np.diff(np.concatenate([[self._last], angles]))))
        self._last = float(angles[-1])
        self.twist = float(twist[-1])
        self.max_abs = max(self.max_abs, float(np.abs(twist).max()))
        return twist


def update_many(meters: list[TwistMeter], points: list[np.ndarray], start_rot: list[np.ndarray],
                end_rot: list[np.ndarray]) -> list[np.ndarray]:
    """:meth:`TwistMeter.update` for several cables over the same S states,
    to the bit: the cables with the same number of points are stacked into
    one :func:`twist_angle` call (its arithmetic is row by row), so a batch
    costs about one call's numpy overhead per point count, not per cable.

    Args:
      meters: one meter per cable.
      points: per cable, (S, n_c, 3) centrelines.
      start_rot, end_rot: per cable, (S, 3, 3) end frames' rotations.

    Returns per cable its (S,) twists, radians.
    """
    out: list[np.ndarray | None] = [None] * len(meters)
    groups: dict[int, list[int]] = {}
    for c, p in enumerate(points):
        groups.setdefault(p.shape[1], []).append(c)
    for cables in groups.values():
        refs = [meters[c].references(start_rot[c], end_rot[c]) for c in cables]
        angles = twist_angle(np.concatenate([points[c] for c in cables]),
                             np.concatenate([r[0] for r in refs]), np.concatenate([r[1] for r in refs]))
        for c, a in zip(cables, np.split(angles, len(cables))):
            out[c] = meters[c].take(a)
    return out


def carry_reference(t_old: np.ndarray, u_old: np.ndarray, ref_old: np.ndarray, t_new: np.ndarray,
                    held: np.ndarray | None = None, turn: np.ndarray | None = None,
                    pairs: tuple[np.ndarray, np.ndarray] | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Rods' reference frames and reference twists carried to new tangents,
    as the discrete elastic rod does in time (Bergou et al. 2010, "Discrete
    viscous threads": time-parallel transport).

    Args:
      t_old, u_old: (E, 3) each edge's unit tangent and reference vector (square to it).
      ref_old: (V,) reference twist at each interior vertex, radians, unwrapped.
      t_new: (E, 3) the edges' unit tangents now.
      held: indices of the edges whose frame a body holds (a clamped end),
        with `turn` (len(held), 3, 3) each body's turn since `t_old`: their
        vectors turn with it.
      pairs: (V,) each, the edges before and after each interior vertex;
        default one rod, edge i - 1 and i (several rods' edges may be
        stacked, their vertices paired within each).

    Returns (u_new (E, 3), ref_new (V,)): each edge's vector carried by the
    least rotation from its old tangent to its new one (or turned with its
    body), and at each interior vertex the angle, about the next edge's
    tangent, from the previous edge's vector carried along the rod (least
    rotation between the two tangents) to the next edge's, unwrapped to
    within half a turn of `ref_old`."""
    u_new = _rotate_min(u_old, t_old, t_new)
    if held is not None and len(held):
        u_new[held] = np.einsum("eij,ej->ei", turn, u_old[held])
    before, after = pairs if pairs is not None else (np.arange(len(t_new) - 1), np.arange(1, len(t_new)))
    carried = _rotate_min(u_new[before], t_new[before], t_new[after])
    raw = _signed_angle(carried, u_new[after], t_new[after])
    return u_new, ref_old + wrap(raw - ref_old)


class RodTwistMeter:
    """What a run keeps of one simulated rod's twist.

    Args:
      stiffness: (V,) per interior vertex, its moment per radian of twist,
        N m / rad (G J over the length it stands for).
      length: (V,) the length each interior vertex stands for, metres.

    Attributes:
      max_abs: largest absolute twist end to end (the sum over the
        vertices) so far, radians.
      max_moment: (V,) each vertex's largest absolute moment so far, N m.
      max_rate: (V,) each vertex's largest absolute twist per length so far,
        radians per metre.
    """

    def __init__(self, stiffness: np.ndarray, length: np.ndarray):
        self._stiffness = np.asarray(stiffness, float)
        self._length = np.asarray(length, float)
        self.max_abs = 0.0
        self.max_moment = np.zeros(len(self._stiffness))
        self.max_rate = np.zeros(len(self._stiffness))

    def take(self, twist: np.ndarray) -> np.ndarray:
        """Take S states' (S, V) twists at the interior vertices, radians;
        return their (S,) twists end to end."""
        twist = np.asarray(twist, float).reshape(-1, len(self._stiffness))
        total = twist.sum(axis=1)
        if len(total):
            self.max_abs = max(self.max_abs, float(np.abs(total).max()))
            most = np.abs(twist).max(axis=0)
            self.max_moment = np.maximum(self.max_moment, self._stiffness * most)
            self.max_rate = np.maximum(self.max_rate, most / self._length)
        return total
