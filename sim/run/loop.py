"""The step loop: settle, then follow the script, yielding each step's state.

`Simulation.steps()` yields a `StepState` for t = 0 (the settled rest state)
and then for every step up to the scene's duration: the time, every cable's
body centres in order from start to end, the world pose of every part, and,
when asked for, MuJoCo's contacts from the detection model (every
interaction enabled, margins from the clearance) fed the simulated positions
(`cablecheck.detection.detector`, which also runs on its own for a run's batches).

Simulate only what the scene calls for: with `effects.dynamics = false`
nothing is stepped; the cables stay exactly as routed while scripted bodies
move (forward kinematics only), so rigid parts can still be checked.

MuJoCo's automatic reset is off: a simulation that goes unstable (NaN,
infinite or huge values, `cablecheck.run.divergence.BAD_WARNINGS`) keeps its bad
values instead of jumping back to its initial state unremarked; settling
stops at once and `steps()` yields that state, carrying the warning
(`StepState.unstable`), as its last.

This module does not check interference, log, report or hold the detection
model's passes (`cablecheck.detection.detector`), nor judge a divergence (`cablecheck.run.divergence`):
it is the interface the checker and the recorder read from.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass

import mujoco
import numpy as np

from cablecheck.build.built import Built, mesh_parts
from cablecheck.build.rodtwist import RodRaw, TwistReader
from cablecheck.detection.contacts import Contacts
from cablecheck.detection.detector import Detector
from cablecheck.detection.hullgap import HullRaw, HullReader
from cablecheck.run.cliphold import ClipHold
from cablecheck.run.divergence import BAD_WARNINGS, Instability
from cablecheck.run.motion import Motion

SCRIPT_BLOCK = 256
"""Scene steps whose script times are evaluated at once (`script_times`)."""


def script_times(ks: np.ndarray, substeps: int, step_size: float, timestep: float) -> np.ndarray:
    """The times the loop sets the script at for scene steps `ks`, in order:
    after each substep j < substeps of step k, ((k - 1) substeps + j)
    step_size, then k timestep (the same floating-point products as
    computing each one on its own)."""
    j = np.arange(1, substeps)
    inner = ((ks[:, None] - 1) * substeps + j[None, :]) * step_size
    return np.concatenate([inner, (ks * timestep)[:, None]], axis=1).ravel()


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
        and end ride on (the frames clamped ends hold; `cablecheck.checker.twist`).
      hull: the simulation's contacts as MuJoCo lists them, copied (`cablecheck.detection.hullgap`
        reads those of cables with mesh parts' hulls from them), or None when
        not validated or no hull can hold a cable.
      xpos, xmat: (nbody, 3) and (nbody, 9) the simulation's body poses at
        `qpos` (model coordinates) for the detection model's reach test
        (`cablecheck.detection.detector.Detector.collide_many`), or None when not validated.
      unstable: MuJoCo's first instability warning, when the simulation
        went unstable up to this state (it is then the last state), else None.
      rod: what the state keeps of the simulated rods' twist
        (`cablecheck.build.rodtwist.RodRaw`, read by `TwistReader.read_many`),
        or None when nothing is simulated.
    """

    step: int
    t: float
    cables: list[np.ndarray]
    part_poses: np.ndarray
    contacts: Contacts | None
    energy: np.ndarray
    qpos: np.ndarray
    end_rot: np.ndarray | None = None
    hull: HullRaw | None = None
    xpos: np.ndarray | None = None
    xmat: np.ndarray | None = None
    unstable: Instability | None = None
    rod: RodRaw | None = None


class Simulation:
    """A built scene with its data, stepped by `steps()`.

    `validate`: the states are to be compared with the detection model's
    contacts, so each keeps what that comparison reads besides the cables:
    with mesh parts, the simulation's body poses (`StepState.xpos`, `xmat`,
    for the reach test) and its contacts of cables with those parts' hulls
    (`StepState.hull`). None: when `built` has a detection model. A run
    builds the detection model while the simulation already settles
    (`cablecheck.run.runner`), so it says so itself.

    `detector`: the detection model's passes (`cablecheck.detection.detector.Detector`), when
    `built` has one; `reach` is handed to it."""

    def __init__(self, built: Built, reach: bool = True, validate: bool | None = None):
        self.built = built
        self.model = built.model
        self.data = mujoco.MjData(self.model)
        self.model.opt.enableflags |= int(mujoco.mjtEnableBit.mjENBL_ENERGY)
        # bad values stay bad (no silent reset to the initial state): cablecheck.run.divergence names them
        self.model.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_AUTORESET)
        self.motion = Motion(built)
        self.detector = Detector(built, reach) if built.detect is not None else None
        validate = (built.detect is not None) if validate is None else validate
        self.hull = HullReader.of(built) if validate else None
        self._part_geoms = np.array([p.geom_id for p in built.parts], int)
        # the reach test reads the body poses; it has something to leave out only with meshes
        self._poses = validate and bool(len(mesh_parts(built)))
        self._verts = [slice(c.vert_adr, c.vert_adr + c.count) for c in built.cables]   # each cable's, in order
        self.clips = ClipHold(built)       # clamped clips hold the rod's roll
        self._twist = TwistReader.of(built)
        self._end_bodies = np.array([[built.body_ids[c.start.body], built.body_ids[c.end.body]]
                                     for c in built.scene.cables], int).reshape(-1, 2)
        scene = built.scene
        self.timestep = scene.timestep
        self.substeps = built.substeps.count if built.substeps is not None else 1
        self.step_size = scene.timestep / self.substeps  # the simulation model's timestep
        self.settle_steps = int(round(scene.settle / self.step_size)) if scene.effects.dynamics else 0
        self.total_steps = int(round(scene.duration / scene.timestep))
        self.instability: Instability | None = None
        self._t0 = self.settle_steps * self.step_size   # simulation time of scene time 0
        self._warning = self.data.warning               # MuJoCo's counters, read after every step

    def unstable(self) -> Instability | None:
        """MuJoCo's first instability warning so far (`cablecheck.run.divergence.BAD_WARNINGS`), or None."""
        if self.instability is None:
            warning = self._warning
            for k in BAD_WARNINGS:
                if warning[k].number:
                    self.instability = Instability(mujoco.mjtWarning(k).name, int(warning[k].lastinfo),
                                                   float(self.data.time - self._t0))
                    break
        return self.instability

    def state_bytes(self) -> int:
        """About how many bytes one `StepState` of this simulation holds
        (its arrays; how deep a queue of them may be, `cablecheck.run.ahead`)."""
        m = self.model
        floats = (m.nq + 2 + 16 * len(self._part_geoms) + 3 * int(sum(c.count for c in self.built.cables))
                  + 18 * len(self._end_bodies) + (12 * m.nbody if self._poses else 0))
        return 8 * floats

    def reset(self) -> None:
        """Routed shape, scripted targets at t = 0, no velocity."""
        d = self.data
        mujoco.mj_resetData(self.model, d)
        self.instability = None
        self._t0 = self.settle_steps * self.step_size
        d.qpos[:] = self.built.qpos0
        self.motion.apply(d, 0.0, frozen=True)
        mujoco.mj_forward(self.model, d)

    def settle(self, progress=None, stop=None) -> None:
        """Simulate `settle` seconds with the script frozen at t = 0, by
        dynamic relaxation with kinetic damping; `stop()` returning True
        ends settling early.

        Settling looks for the static rest state, not for a motion, and the
        cables carry only their material damping (see
        `cablecheck.build.stages.rayleigh_damping`): a hanging cable would swing for many
        seconds. So every time the kinetic energy passes a peak all
        velocities are set to zero (kinetic damping, the dynamic relaxation
        method of Cundall and of Barnes for form finding): the state then
        descends towards the nearest equilibrium, which is where damped
        motion would come to rest, without any force being added.

        A simulation that goes unstable stops settling at once (`unstable`)."""
        d = self.data
        previous = 0.0
        for k in range(self.settle_steps):
            if stop is not None and stop():
                return
            mujoco.mj_step(self.model, d)
            if self.unstable() is not None:
                return
            self.motion.apply(d, 0.0, frozen=True)  # exactly where the script holds them
            self.clips.hold(self.model, d)
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
        (`cablecheck.build.stages.choose_substeps`). A simulation that goes unstable
        (`unstable`) yields the step it was found at and ends there."""
        self._t0 = float(self.data.time)      # settling may have ended early
        yield self.state(0, contacts)
        if self.instability is not None:      # while settling
            return
        dynamics = self.built.scene.effects.dynamics
        if dynamics:
            self.motion.apply(self.data, 0.0)  # settling froze the targets' velocity
        apply, sub, hold = self.motion.apply_values, self.substeps, self.clips.hold
        for first in range(1, self.total_steps + 1, SCRIPT_BLOCK):
            # the script at every time the block's steps set it, in one evaluation
            ks = np.arange(first, min(first + SCRIPT_BLOCK, self.total_steps + 1))
            value, rate = self.motion.curve.at_many(script_times(ks, sub, self.step_size, self.timestep))
            row = 0
            for k in ks.tolist():
                if dynamics:
                    # The step carries the targets (at their pose and velocity at
                    # its start) and the cable to time k * dt. The cable's reaction
                    # moves a target's free joint a little within the step despite
                    # its armature (a panel flush on a floor read 1e-6 m inside it);
                    # the script's pose at k * dt then replaces what the step made
                    # of it, so targets follow their script exactly, and its
                    # velocity there carries the next step.
                    for _ in range(1, sub):
                        mujoco.mj_step(self.model, self.data)
                        apply(self.data, value[row], rate[row])
                        hold(self.model, self.data)
                        row += 1
                    mujoco.mj_step(self.model, self.data)
                else:
                    row += sub - 1
                apply(self.data, value[row], rate[row])
                if dynamics:
                    hold(self.model, self.data)
                row += 1
                if dynamics and self.unstable() is not None:
                    yield self.state(k, contacts)
                    return
                if k % every == 0 or k == self.total_steps:
                    yield self.state(k, contacts)

    def state(self, step: int, contacts: bool) -> StepState:
        """The current state as a StepState (no stepping)."""
        d = self.data
        # the clamping bodies' rotations at the start of the step just taken (the rods' reference is of then)
        before = d.xmat[self._twist.bodies] if self._twist is not None else None
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
        found = self.detector.detect_qpos(d.qpos) if (contacts and self.detector is not None) else None
        end_rot = d.xmat[self._end_bodies].reshape(-1, 2, 3, 3)
        hull = self.hull.raw(d) if self.hull is not None else None   # the last step's contacts, as they are
        bodies = (d.xpos.copy(), d.xmat.copy()) if self._poses else (None, None)
        rod = self._twist.raw(d.plastic, before, d.xmat[self._twist.bodies]) if self._twist is not None else None
        return StepState(step, step * self.timestep, cables, poses, found, d.energy.copy(), d.qpos.copy(),
                         end_rot, hull, *bodies, unstable=self.instability, rod=rod)

    def warnings(self) -> dict[str, int]:
        """MuJoCo warnings raised so far, by name, nonzero only."""
        out = {}
        for i, w in enumerate(self.data.warning):
            if w.number:
                out[mujoco.mjtWarning(i).name] = int(w.number)
        return out
