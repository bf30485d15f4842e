"""Joint space of a run: the moving joints' values and what each event owes to them.

Where the scene moves joints of its mjcf model, `JointLog` gives each event:

- `joints`: every moving joint's value at the event's `t_worst`;
- `link`: the mjcf body that a part of the pair rides on (the link rubbed),
  or None when neither side rides a moving link (a cable against the table);
- `joint_ranges`: [lowest, highest] over the event's interval of the joints
  that move that link (the moving joints between it and the world, nearest
  first), or of every moving joint when there is no link.

Values are the script's (`cablecheck.run.motion`: the joints are driven kinematically,
so the simulation follows them to within its step's integration), degrees
for hinges and scene units for slides. A range is exact: both
interpolations are monotone between samples, so the extremes over an
interval lie at its ends or at samples inside it. This module does not
check interference or know how events are found.
"""

from __future__ import annotations

import mujoco
import numpy as np

from cablecheck.build.built import Built
from cablecheck.run.motion import Motion

_HINGE = int(mujoco.mjtJoint.mjJNT_HINGE)


class JointLog:
    """The moving joints of one run and their values over time.

    Attributes:
      names: the moving joints, in model order.
      units: per joint, "deg" (hinge) or the scene's units (slide).
    """

    def __init__(self, built: Built, motion: Motion):
        model = built.model
        drives = sorted((built.joints[n] for n in motion.moving), key=lambda d: d.qpos_adr)
        self.names: list[str] = [d.name for d in drives]
        self.units: list[str] = ["deg" if d.type == _HINGE else built.scene.units for d in drives]
        self._per = np.array([d.scale for d in drives], float)   # MuJoCo units per written unit
        self._motion = motion
        self._knots = motion.curve.value.x
        self._body_of = {p.name: p.body for p in built.parts}
        index = {n: k for k, n in enumerate(self.names)}
        self._chain: dict[str, list[int]] = {}
        for body, b in built.body_ids.items():
            chain = []
            while b > 0:
                chain += [index[model.joint(j).name] for j in range(model.njnt)
                          if int(model.jnt_bodyid[j]) == b and model.joint(j).name in index]
                b = int(model.body_parentid[b])
            self._chain[body] = chain

    def __bool__(self) -> bool:
        return bool(self.names)

    def values(self, times) -> np.ndarray:
        """(m, J) joint values (degrees / scene units) at `times` (m,)."""
        times = np.atleast_1d(np.asarray(times, float))
        return self._motion.joint_values(times, self.names) / self._per

    def event_fields(self, t_start: float, t_end: float, t_worst: float,
                     a: str, b: str) -> dict:
        """`joints`, `link` and `joint_ranges` of an event (see the module docstring)."""
        worst = self.values(t_worst)[0]
        knots = self._knots[(self._knots > t_start) & (self._knots < t_end)]
        inside = self.values(np.concatenate([[t_start, t_end], knots]))
        links = [self._body_of[n] for n in (b, a) if n in self._body_of]
        links = [body for body in links if self._chain.get(body)]
        chain = list(dict.fromkeys(k for body in links for k in self._chain[body]))
        chain = chain or list(range(len(self.names)))
        lo, hi = inside.min(axis=0), inside.max(axis=0)
        return {
            "joints": {n: float(v) + 0.0 for n, v in zip(self.names, worst)},
            "link": links[0] if links else None,
            "joint_ranges": {self.names[k]: [float(lo[k]) + 0.0, float(hi[k]) + 0.0] for k in chain},
        }
