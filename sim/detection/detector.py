"""The detection model's collision passes at the simulation's states.

Validation compares the checker with MuJoCo's own contacts, from a second
model of the scene (`cablecheck.build.mjspec`, detect): every interaction enabled,
margins from the clearance, the concave meshes' own surfaces
(`cablecheck.detection.mesh`). `Detector` holds that model's data and runs its
collision pass at given generalized positions of the simulation model (the
two share their kinematic tree): one state (`detect_qpos`) or a batch
(`collide_many`, with the surface patches no cable can reach left out,
`cablecheck.detection.surfacereach`), and names the contacts (`cablecheck.detection.contacts`).

It is apart from the stepping (`cablecheck.run.loop.Simulation`) because it needs
nothing of it but positions: a run starts simulating on one thread while
the detection model is still being built on the other (`cablecheck.run.runner`).

This module does not step, compare or decide anything: the checks and the
comparison are `cablecheck.run.stepcheck` and `cablecheck.checker.validation`.
"""

from __future__ import annotations

from collections.abc import Iterable

import mujoco
import numpy as np

from cablecheck.build.built import Built
from cablecheck.detection.contacts import ContactReader, Contacts, RawContacts
from cablecheck.detection.surfacereach import SurfaceReach
from cablecheck.run.ahead import thread_cpu


class Detector:
    """The detection model of `built` (which must have one) and its data.

    `reach`: leave the concave meshes' surfaces no cable can reach out of a
    state's detection pass (`cablecheck.detection.surfacereach`; the same contacts). False
    collides every surface at every state (to compare the two)."""

    def __init__(self, built: Built, reach: bool = True):
        if built.detect is None:
            raise ValueError("the scene was built without a detection model")
        self.built = built
        self.model = built.detect
        self.detect_data = mujoco.MjData(built.detect)
        surfaces = SurfaceReach(built.detect) if reach else None
        self.reach = surfaces if surfaces is not None and len(surfaces) else None
        self.reader = ContactReader(built)
        self._collision = 0.0          # CPU seconds in the detection model's mj_collision

    def detect(self, d: mujoco.MjData) -> Contacts:
        """MuJoCo's contacts for the positions in `d`, from the detection model."""
        return self.detect_qpos(d.qpos)

    def detect_qpos(self, qpos: np.ndarray) -> Contacts:
        """MuJoCo's contacts for the generalized positions `qpos` (of the
        simulation model), from the detection model."""
        return self.read_many([self.collide(qpos)])[0]

    def collide(self, qpos: np.ndarray) -> RawContacts:
        """The detection model's collision pass at `qpos`: its contacts, unnamed."""
        return self.collide_many([qpos])[0]

    def collide_many(self, qposes: list[np.ndarray], poses: tuple[np.ndarray, np.ndarray] | None = None
                     ) -> list[RawContacts]:
        """:meth:`collide` at each of `qposes`. The concave meshes' surface
        patches no cable can reach at a state are left out of its pass
        (`cablecheck.detection.surfacereach`: MuJoCo could find no contact on them), the
        reach of all the states tested at once, from `poses`: (S, nbody, 3)
        xpos and (S, nbody, 9) xmat at those qposes (the simulation's, as
        `StepState` carries them: the two models share their kinematic tree,
        so mj_kinematics gives both the same poses bit for bit); None: the
        detection model's own, computed here.

        The pass is mj_kinematics, mj_flex and mj_collision: the detection
        model's flexes compute no edge Jacobians (`cablecheck.build.mjspec.never_stepped`),
        the one reader of mj_comPos's output there, so it is not run."""
        m2, d2 = self.model, self.detect_data
        reach = self.reach
        each: Iterable[int] = range(len(qposes))
        if reach is not None:
            if poses is None:
                poses = self.detect_poses(qposes)
            each = reach.leave_out_each(reach.reachable(*poses))   # writes only the patches that change
        out = []
        raw = self.reader.raw
        collision = 0.0
        try:
            for i in each:
                d2.qpos[:] = qposes[i]
                mujoco.mj_kinematics(m2, d2)
                mujoco.mj_flex(m2, d2)
                t = thread_cpu()
                mujoco.mj_collision(m2, d2)
                collision += thread_cpu() - t
                out.append(raw(d2))
        finally:
            self._collision += collision
            if reach is not None:
                reach.restore()
        return out

    def detect_poses(self, qposes: list[np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
        """The detection model's body poses at each of `qposes` after
        mj_kinematics: (S, nbody, 3) xpos and (S, nbody, 9) xmat."""
        m2, d2 = self.model, self.detect_data
        xpos = np.empty((len(qposes), m2.nbody, 3))
        xmat = np.empty((len(qposes), m2.nbody, 9))
        for i, qpos in enumerate(qposes):
            d2.qpos[:] = qpos
            mujoco.mj_kinematics(m2, d2)
            xpos[i], xmat[i] = d2.xpos, d2.xmat
        return xpos, xmat

    def collision_seconds(self) -> float:
        """CPU seconds of the detection model's mj_collision so far (the
        calling thread's, as the run's stages are counted: MuJoCo's own
        timer is wall-clock, which on a busy machine counts time the thread
        did not run); what :meth:`collide_many` costs at least."""
        return self._collision

    def read_many(self, raws: list[RawContacts]) -> list[Contacts]:
        """Contacts of :meth:`collide` named, for many steps at once."""
        return self.reader.read_many(raws, self.built.origin)
