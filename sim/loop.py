"""The step loop: settle, then follow the script, yielding each step's state.

`Simulation.steps()` yields a `StepState` for t = 0 (the settled rest state)
and then for every step up to the scene's duration: the time, every cable's
body centres in order from start to end, the world pose of every part, and,
when asked for, MuJoCo's contacts from the detection model (every
interaction enabled, margins from the clearance) fed the simulated positions.

Simulate only what the scene calls for: with `effects.dynamics = false`
nothing is stepped; the cables stay exactly as routed while scripted bodies
move (forward kinematics only), so rigid parts can still be checked.

This module does not check interference, log or report: it is the interface
the checker and the recorder read from.
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator
from dataclasses import dataclass

import mujoco
import numpy as np

from sim.build import Built
from sim.ahead import thread_cpu
from sim.contacts import ContactReader, Contacts, RawContacts
from sim.hullgap import HullReader, HullRows
from sim.motion import Motion
from sim.surfacereach import SurfaceReach


@dataclass(frozen=True, eq=False)
class StepState:
    """One step of the run.

    Attributes:
      step: index of the step after t = 0 (0 is the rest state).
      t: time, seconds (0 at the end of settling).
      cables: per cable, (n, 3) body centres from start to end, scene world, metres.
      part_poses: (P, 4, 4) scene-world pose of every part (geom frame), metres.
      contacts: MuJoCo's contacts from the detection model, or None.
      energy: (2,) potential and kinetic energy of the simulation, J.
      qpos: the simulation's generalized positions (for detecting later).
      end_rot: (C, 2, 3, 3) world rotation of the bodies each cable's start
        and end ride on (the frames clamped ends hold; `checker.twist`).
      hull: the simulation's contacts of cables with concave parts' hulls
        (`sim.hullgap`), or None when no part is watched.
      xpos, xmat: (nbody, 3) and (nbody, 9) the simulation's body poses at
        `qpos` (model coordinates) for the detection model's reach test
        (`Simulation.collide_many`), or None when it has none.
    """

    step: int
    t: float
    cables: list[np.ndarray]
    part_poses: np.ndarray
    contacts: Contacts | None
    energy: np.ndarray
    qpos: np.ndarray
    end_rot: np.ndarray | None = None
    hull: HullRows | None = None
    xpos: np.ndarray | None = None
    xmat: np.ndarray | None = None


class Simulation:
    """A built scene with its data, stepped by `steps()`.

    `reach`: leave the concave meshes' surfaces no cable can reach out of a
    state's detection pass (`sim.surfacereach`; the same contacts). False
    collides every surface at every state (to compare the two)."""

    def __init__(self, built: Built, reach: bool = True):
        self.built = built
        self.model = built.model
        self.data = mujoco.MjData(self.model)
        self.model.opt.enableflags |= int(mujoco.mjtEnableBit.mjENBL_ENERGY)
        self.motion = Motion(built)
        self.detect_data = mujoco.MjData(built.detect) if built.detect is not None else None
        surfaces = SurfaceReach(built.detect) if (reach and built.detect is not None) else None
        self.reach = surfaces if surfaces is not None and len(surfaces) else None
        self.reader = ContactReader(built)
        self._collision = 0.0          # CPU seconds in the detection model's mj_collision
        self.hull = HullReader.of(built)
        self._part_geoms = np.array([p.geom_id for p in built.parts], int)
        self._verts = [np.arange(c.vert_adr, c.vert_adr + c.count) for c in built.cables]
        self._end_bodies = np.array([[built.body_ids[c.start.body], built.body_ids[c.end.body]]
                                     for c in built.scene.cables], int).reshape(-1, 2)
        scene = built.scene
        self.timestep = scene.timestep
        self.substeps = built.substeps.count if built.substeps is not None else 1
        self.step_size = scene.timestep / self.substeps  # the simulation model's timestep
        self.settle_steps = int(round(scene.settle / self.step_size)) if scene.effects.dynamics else 0
        self.total_steps = int(round(scene.duration / scene.timestep))

    def reset(self) -> None:
        """Routed shape, scripted targets at t = 0, no velocity."""
        d = self.data
        mujoco.mj_resetData(self.model, d)
        d.qpos[:] = self.built.qpos0
        self.motion.apply(d, 0.0, frozen=True)
        mujoco.mj_forward(self.model, d)

    def settle(self, progress=None, stop=None) -> None:
        """Simulate `settle` seconds with the script frozen at t = 0, by
        dynamic relaxation with kinetic damping; `stop()` returning True
        ends settling early.

        Settling looks for the static rest state, not for a motion, and the
        cables carry only their material damping (see
        `sim.build.rayleigh_damping`): a hanging cable would swing for many
        seconds. So every time the kinetic energy passes a peak all
        velocities are set to zero (kinetic damping, the dynamic relaxation
        method of Cundall and of Barnes for form finding): the state then
        descends towards the nearest equilibrium, which is where damped
        motion would come to rest, without any force being added."""
        d = self.data
        previous = 0.0
        for k in range(self.settle_steps):
            if stop is not None and stop():
                return
            mujoco.mj_step(self.model, d)
            self.motion.apply(d, 0.0, frozen=True)  # exactly where the script holds them
            kinetic = float(d.energy[1])  # at the start of the step just taken
            if kinetic < previous:  # past a peak
                d.qvel[:] = 0.0
                kinetic = 0.0
            previous = kinetic
            if progress is not None:
                progress(k + 1)

    def steps(self, contacts: bool = True, every: int = 1) -> Iterator[StepState]:
        """Yield the rest state, then every `every`-th step until the duration.

        `reset` and `settle` must have run. Steps that are not yielded are
        still simulated. Each scene step is `substeps` simulation steps
        (`sim.build.choose_substeps`)."""
        yield self.state(0, contacts)
        dynamics = self.built.scene.effects.dynamics
        if dynamics:
            self.motion.apply(self.data, 0.0)  # settling froze the targets' velocity
        for k in range(1, self.total_steps + 1):
            if dynamics:
                # The step carries the targets (at their pose and velocity at
                # its start) and the cable to time k * dt. The cable's reaction
                # moves a target's free joint a little within the step despite
                # its armature (a panel flush on a floor read 1e-6 m inside it);
                # the script's pose at k * dt then replaces what the step made
                # of it, so targets follow their script exactly, and its
                # velocity there carries the next step.
                for j in range(1, self.substeps):
                    mujoco.mj_step(self.model, self.data)
                    self.motion.apply(self.data, ((k - 1) * self.substeps + j) * self.step_size)
                mujoco.mj_step(self.model, self.data)
            self.motion.apply(self.data, k * self.timestep)
            if k % every == 0 or k == self.total_steps:
                yield self.state(k, contacts)

    def state(self, step: int, contacts: bool) -> StepState:
        """The current state as a StepState (no stepping)."""
        d = self.data
        # mj_step leaves positions (xpos, flexvert_xpos) from the start of the
        # step and qpos at its end: recompute them from qpos so the checker,
        # the detection model and the recording all see the same instant.
        mujoco.mj_kinematics(self.model, d)
        mujoco.mj_flex(self.model, d)
        origin = self.built.origin  # model coordinates + origin = scene world
        xpos = d.flexvert_xpos
        if self.built.scene.effects.dynamics:
            cables = [xpos[idx] + origin for idx in self._verts]
        else:  # exactly as routed, held ends included (they ride bodies that may move)
            cables = [c.routed.copy() for c in self.built.cables]
        poses = np.zeros((len(self._part_geoms), 4, 4))
        poses[:, :3, :3] = d.geom_xmat[self._part_geoms].reshape(-1, 3, 3)
        poses[:, :3, 3] = d.geom_xpos[self._part_geoms] + origin
        poses[:, 3, 3] = 1.0
        found = self.detect(d) if (contacts and self.detect_data is not None) else None
        end_rot = d.xmat[self._end_bodies].reshape(-1, 2, 3, 3)
        hull = self.hull.rows(d) if self.hull is not None else None   # the last step's contacts
        bodies = (d.xpos.copy(), d.xmat.copy()) if self.reach is not None else (None, None)
        return StepState(step, step * self.timestep, cables, poses, found, d.energy.copy(), d.qpos.copy(),
                         end_rot, hull, *bodies)

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
        (`sim.surfacereach`: MuJoCo could find no contact on them), the
        reach of all the states tested at once, from `poses`: (S, nbody, 3)
        xpos and (S, nbody, 9) xmat at those qposes (the simulation's, as
        `StepState` carries them: the two models share their kinematic tree,
        so mj_kinematics gives both the same poses bit for bit); None: the
        detection model's own, computed here.

        The pass is mj_kinematics, mj_flex and mj_collision: the detection
        model's flexes compute no edge Jacobians (`sim.mjspec.never_stepped`),
        the one reader of mj_comPos's output there, so it is not run."""
        m2, d2 = self.built.detect, self.detect_data
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
        m2, d2 = self.built.detect, self.detect_data
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
        did not run); what :meth:`collide_many` costs at least; 0 without a
        detection model."""
        return self._collision

    def read_many(self, raws: list[RawContacts]) -> list[Contacts]:
        """Contacts of :meth:`collide` named, for many steps at once."""
        return self.reader.read_many(raws, self.built.origin)

    def warnings(self) -> dict[str, int]:
        """MuJoCo warnings raised so far, by name, nonzero only."""
        out = {}
        for i, w in enumerate(self.data.warning):
            if w.number:
                out[mujoco.mjtWarning(i).name] = int(w.number)
        return out
