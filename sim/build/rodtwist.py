"""Where a cable's twist lives in MuJoCo's state, and the twist read from it.

MuJoCo 4's rod (`mujoco/doc/XMLreference.rst`, flex elasticity, "Per-edge
twist joints" and "State") gives each edge a material angle, the hinge joint
`<flex>_twist_<e>` (`<flex>_twist` for the last edge), measured from the
edge's time-parallel reference frame; an edge clamped by a body has no joint
(its angle is 0: the body fixes its frame). `mjData.plastic`, from
`flex_plasticadr`, holds the edges' reference frames (six numbers an edge)
and then the reference twist of each interior vertex, unwrapped from step to
step. The rod's twist at interior vertex i, between edges i - 1 and i, is
then the discrete elastic rod's (Bergou et al. 2008)

    m_i = theta_i - theta_(i-1) + reference twist_i,

its torsional moment G J m_i / l_i with l_i half the two edges' rest lengths
(MuJoCo's stiffness `G J / (l0 + l1)` on `m_i^2`), and the cable's twist
end to end the sum of the m_i.

MuJoCo keeps the reference frames and twists of the positions at the start
of the step just taken (its `t_old` are those tangents), while the joints
are at its end: `TwistReader` carries them to the positions the step
ended at as MuJoCo's next step would (`cablecheck.checker.twist.carry_reference`:
time-parallel transport; a clamped edge's frame turns with its body), so the
twist read is the state's own, not a step late (tests/test_rodtwist.py
compares it with MuJoCo's own carried state).

This module reads MuJoCo's arrays; it does not step, and the twist a run
reports over time is gathered in `cablecheck.run.runner`.
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np

from cablecheck.build.built import Built
from cablecheck.checker.twist import carry_reference


@dataclass(frozen=True, eq=False)
class RodTwist:
    """Where one cable's twist is in MuJoCo's state, and its torsional stiffness.

    Attributes:
      joint_qpos: (edges,) qpos address of each edge's twist joint; -1 for
        an edge clamped by a body (no joint, angle 0).
      held_body: (edges,) the body whose turn a clamped edge's frame follows, -1 for the others.
      frames: plastic addresses of the edges' reference frames (tangent, vector: six numbers an edge).
      reference: plastic addresses of the interior vertices' reference twists.
      stiffness: (edges - 1,) G J / l per interior vertex, N m per radian
        (SI whatever the scene's units): its moment is this times its twist.
      length: (edges - 1,) l, the length each interior vertex stands for
        (half its two edges' rest lengths), metres.
      s: (edges - 1,) each interior vertex's arc length along the rest shape, metres.
    """

    joint_qpos: np.ndarray
    held_body: np.ndarray
    frames: slice
    reference: slice
    stiffness: np.ndarray
    length: np.ndarray
    s: np.ndarray

    def twist(self, qpos: np.ndarray, plastic: np.ndarray) -> np.ndarray:
        """(edges - 1,) the twist at each interior vertex, radians, as MuJoCo's
        reference holds it: the state's own right after a step of no length
        (`cablecheck.build.untwist`); a run reads it with `TwistReader`."""
        theta = np.where(self.joint_qpos >= 0, qpos[np.maximum(self.joint_qpos, 0)], 0.0)
        return np.diff(theta) + plastic[self.reference]


@dataclass(frozen=True, eq=False)
class RodRaw:
    """What a state keeps of MuJoCo's rods for `TwistReader.read_many`:
    the reference frames (E, 6) and twists (V,) of all cables' rods as MuJoCo
    holds them (for the start of the step just taken), and the clamping
    bodies' rotations (H, 9) then and now."""

    frames: np.ndarray
    reference: np.ndarray
    rot_before: np.ndarray
    rot: np.ndarray


class TwistReader:
    """Every cable's twist at a batch of states, its reference carried to
    each state's positions, in one pass over all the cables' edges and the
    states stacked (no loop over states, cables or edges): a state keeps
    only `RodRaw` (a few gathers), the carrying runs on the batch.

    Attributes:
      bodies: the bodies whose turn the clamped edges' frames follow, in the
        order `raw` takes their rotations.
    """

    @classmethod
    def of(cls, built: Built) -> TwistReader | None:
        """The reader of a built scene's cables (None for a scene not simulated, `Built.rods` empty)."""
        return cls(list(built.rods), [c.count for c in built.cables]) if built.rods else None

    def __init__(self, rods: list[RodTwist | None], counts: list[int]):
        """`rods` per cable, `counts` its vertices (the order of `read_many`'s points)."""
        self._cables = [i for i, r in enumerate(rods) if r is not None]
        self._count = len(rods)
        self.bodies = np.zeros(0, int)
        live = [rods[i] for i in self._cables]
        if not live:
            return
        edges = [len(r.joint_qpos) for r in live]
        first = np.concatenate([[0], np.cumsum(edges)])[:-1].astype(int)
        offset = np.concatenate([[0], np.cumsum(counts)])[:-1].astype(int)   # each cable's first point
        self._edges = int(sum(edges))
        self._joint = np.concatenate([r.joint_qpos for r in live])
        self._frame = np.concatenate([np.arange(r.frames.start, r.frames.stop) for r in live])
        self._ref = np.concatenate([np.arange(r.reference.start, r.reference.stop) for r in live])
        self._v0 = np.concatenate([offset[i] + np.arange(e) for i, e in zip(self._cables, edges)])
        self._before = np.concatenate([f + np.arange(e - 1) for f, e in zip(first, edges)]).astype(int)
        held = np.concatenate([r.held_body for r in live])
        self._held = np.flatnonzero(held >= 0)
        self.bodies = held[self._held]
        self._split = np.cumsum([e - 1 for e in edges])[:-1]

    def raw(self, plastic: np.ndarray, rot_before: np.ndarray, rot: np.ndarray) -> RodRaw | None:
        """A state's `RodRaw`: `rot_before`, `rot` the rotations of `bodies`
        at the start of the step just taken and now; None without any rod."""
        if not self._cables:
            return None
        return RodRaw(plastic[self._frame].reshape(-1, 6), plastic[self._ref], rot_before, rot)

    def read_many(self, raws: list[RodRaw], points: np.ndarray, qpos: np.ndarray) -> list[np.ndarray | None]:
        """Per cable (None without twist state), its (S, V) twist at each
        interior vertex over S states, radians: `raws` the states' `RodRaw`,
        `points` (S, N, 3) all cables' points in order, `qpos` (S, nq).
        A state before any step (MuJoCo's reference frames all 0, as
        `mj_resetData` leaves them) reads 0: every cable starts untwisted
        (`cablecheck.build.untwist`)."""
        out: list[np.ndarray | None] = [None] * self._count
        if not self._cables or not raws:
            return out
        n, e, held = len(raws), self._edges, self._held
        frames = np.concatenate([r.frames for r in raws])
        ref = np.concatenate([r.reference for r in raws])
        t = (points[:, self._v0 + 1] - points[:, self._v0]).reshape(-1, 3)
        t = t / np.sqrt(np.einsum("ij,ij->i", t, t))[:, None]
        rot = np.stack([r.rot for r in raws]).reshape(-1, 3, 3)
        before = np.stack([r.rot_before for r in raws]).reshape(-1, 3, 3)
        shift = e * np.arange(n)[:, None]
        pairs = ((self._before[None] + shift).ravel(), (self._before[None] + 1 + shift).ravel())
        ref = carry_reference(frames[:, :3], frames[:, 3:], ref, t, (held[None] + shift).ravel(),
                              rot @ np.transpose(before, (0, 2, 1)), pairs)[1]
        theta = np.where(self._joint >= 0, qpos[:, np.maximum(self._joint, 0)], 0.0)
        twist = (theta[:, self._before + 1] - theta[:, self._before]) + ref.reshape(n, -1)
        twist[~np.array([r.frames.any() for r in raws])] = 0.0       # before any step
        for i, part in zip(self._cables, np.split(twist, self._split, axis=1)):
            out[i] = part
        return out


def rod_twist(m: mujoco.MjModel, flex_id: int, rest_s: np.ndarray, shear: float,
              radius: float) -> RodTwist | None:
    """The twist layout of flex `flex_id` (vertices at rest arc lengths
    `rest_s` in metres), with shear modulus `shear` (Pa) and radius (m);
    None where MuJoCo keeps no twist state for it (a rod of one element)."""
    edges = len(rest_s) - 1
    adr = int(m.flex_plasticadr[flex_id])
    if adr < 0 or edges < 2:
        return None
    flex = mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_FLEX, flex_id)
    names = [f"{flex}_twist_{e}" for e in range(edges - 1)] + [f"{flex}_twist"]
    joint_qpos = np.full(edges, -1, int)
    for e, name in enumerate(names):
        j = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, name)
        if j >= 0:
            joint_qpos[e] = int(m.jnt_qposadr[j])
    first = int(m.flex_vertadr[flex_id])
    edge_body = m.flex_vertbodyid[first:first + edges]
    held_body = np.where(joint_qpos < 0, edge_body, -1).astype(int)
    start = adr + 6 * edges
    half = 0.5 * (np.diff(rest_s)[:-1] + np.diff(rest_s)[1:])
    polar = np.pi * radius ** 4 / 2.0
    return RodTwist(joint_qpos, held_body, slice(adr, start),
                    slice(start, start + edges - 1), shear * polar / half, half, np.asarray(rest_s[1:-1], float))
