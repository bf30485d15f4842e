"""Clamped clips hold the cable's roll: before each simulation step, the
equality on the twist joint of a clip's held edge is given the angle at
which the edge's material frame is the one the clip's body holds.

MuJoCo's rod clamps the frame of a first or last edge whose points are
pinned to a body, not of an edge in the middle: a clip's held edge keeps a
free twist joint (`mujoco/doc/XMLreference.rst`, "Per-edge twist joints"),
so a clip would let the cable turn in it. cablecheck puts a joint equality
on it (`cablecheck.build.mjspec.clip_roll_name`, as stiff as the edges'
equalities), solved with the step like every constraint; setting the joint
between steps instead leaves it free within them, and the rod's moment
turned it back by a third of a quarter turn in each step (measured: the
neighbouring elements settled at 62 degrees of the clip's 90).

The angle is measured from the edge's reference frame in `mjData.plastic`
to the vector the body holds (`ClipRoll.local`, fixed at t = 0 where the
cable starts untwisted), both of the start of the step just taken (MuJoCo's
reference frame is of then, and so is `xmat`): the hold lags the body by
one simulation step of its turn about the cable.

Not here: the clamped ends, which MuJoCo holds itself (`cablecheck.build.untwist`).
"""

from __future__ import annotations

import mujoco
import numpy as np

from cablecheck.build.built import Built
from cablecheck.checker.closest import cross
from cablecheck.checker.twist import wrap


class ClipHold:
    """The clamped clips of a built scene, held together (one pass, no loop over clips)."""

    def __init__(self, built: Built):
        rolls = built.clip_rolls
        self.count = len(rolls)
        self._eq = np.array([r.equality for r in rolls], int)
        self._qpos = np.array([r.qpos_adr for r in rolls], int)
        self._body = np.array([r.body for r in rolls], int)
        frame = np.array([r.frame for r in rolls], int)
        self._t = frame[:, None] + np.arange(3)
        self._u = frame[:, None] + np.arange(3, 6)
        self._local = np.array([r.local for r in rolls], float).reshape(-1, 3)

    def hold(self, m: mujoco.MjModel, d: mujoco.MjData) -> None:
        """Give the clips' equalities their angles for the next step (no-op
        without clips; 0 before any step, the frames all 0 as reset leaves them)."""
        if not self.count:
            return
        t, u = d.plastic[self._t], d.plastic[self._u]
        held = np.einsum("kij,kj->ki", d.xmat[self._body].reshape(-1, 3, 3), self._local)
        # closest.cross: np.cross's bits without its axis handling, a third of this call's cost
        target = np.arctan2(np.einsum("ki,ki->k", cross(t, u), held), np.einsum("ki,ki->k", u, held))
        now = d.qpos[self._qpos]
        m.eq_data[self._eq, 0] = now + wrap(target - now)
