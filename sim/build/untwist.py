"""Every cable starts untwisted as routed: the end roll that takes out the
twist the straight compile would leave between a cable's clamped ends.

MuJoCo fixes a clamped end edge's material frame to the body holding it,
turning it as the body turns from its pose at qpos0, from the frame it has
as the model is compiled; cablecheck compiles each cable straight (its rest
shape, `cablecheck.build.mjspec.compile_model`). Put into its routed shape,
a cable's frame carried along the route from its start then meets the end's
frame at an angle that depends on the route alone (a cable bent out of one
plane: 41 degrees on a 1 m cable routed through one corner, 156 and 84
degrees on robot_cell's two), which MuJoCo would read as twist held between
the clamps. A cable routed in CAD carries none, so each clamped end rides
its end roll body (`cablecheck.build.built.end_roll_body`) on a hinge about
the end's held edge, and `untwist_ends` finds the hinge angle that takes
that twist out, measured on the compiled model at t = 0; the run holds it
there (`Built.end_rolls`, `cablecheck.run.motion`). MuJoCo restarts the
reference frames from the first edge at `mj_resetData`, so the state a run
starts from is the one measured here.

A clamped clip holds the roll of its short held edge, in the middle of the
cable, where MuJoCo's rod has a free twist joint: `clip_rolls` fixes in the
holding body the edge's material vector at t = 0, which the run then keeps
the edge's frame on (`cablecheck.run.cliphold`). `untwisted` does both.

This module does not read twist during a run (see `cablecheck.build.rodtwist`
and `cablecheck.run.runner`).
"""

from __future__ import annotations

from dataclasses import replace

import mujoco
import numpy as np

from cablecheck.build.built import Built, ClipRoll, EndRoll
from cablecheck.build.cableplan import clamped_clips
from cablecheck.build.mjspec import clip_roll_name
from cablecheck.build.rodtwist import RodTwist

PROBE_STEP = 1e-12
"""Seconds: the step `start_state` takes to have MuJoCo set the rods' frames."""

UNTWISTED = 1e-9
"""Radians: the twist a cable may carry at t = 0 after its end roll is set,
summed over its vertices (the measure is exact up to rounding)."""


def start_state(built: Built) -> mujoco.MjData:
    """The simulation's data at t = 0 as a run starts it: reset, the routed
    shape, the script at t = 0, with the rods' reference frames set.

    MuJoCo sets those (`mjData.plastic`) in a step, not in `mj_forward`,
    which leaves them as reset: one step of `PROBE_STEP` seconds sets them
    and moves nothing that can be measured."""
    from cablecheck.run.motion import (
        Motion,  # motion imports cablecheck.build.stages, which imports this module
    )

    m = built.model
    d = mujoco.MjData(m)
    d.qpos[:] = built.qpos0
    Motion(built).apply(d, 0.0, frozen=True)
    step = m.opt.timestep
    m.opt.timestep = PROBE_STEP
    try:
        mujoco.mj_step(m, d)
    finally:
        m.opt.timestep = step
    return d


def untwisted(built: Built) -> tuple[Built, list[str]]:
    """`built` with its end rolls' angles (`untwist_ends`) and its clips' holds
    (`clip_rolls`), and the cables MuJoCo keeps no twist state for
    (`without_twist_state`), from one or two `start_state`s: the one the
    end rolls are measured on, and, where they turn, the one they start."""
    rods = list(built.rods)
    d = start_state(built)
    if built.end_rolls:
        built = replace(built, end_rolls=untwist_ends(built, rods, d))
        d = start_state(built)
        check_untwisted(built, rods, d)
    return replace(built, clip_rolls=clip_rolls(built, rods, d)), without_twist_state(built, rods, d)


def untwist_ends(built: Built, rods: list[RodTwist | None], d: mujoco.MjData) -> tuple[EndRoll, ...]:
    """`built.end_rolls` with the angles that start each cable untwisted
    (`rods` per cable of `built`; `d` its `start_state` with the rolls as they are)."""
    rod_of = {c.name: rod for c, rod in zip(built.cables, rods)}
    return tuple(replace(r, angle=r.angle - float(rod_of[r.cable].twist(d.qpos, d.plastic).sum()))
                 if rod_of[r.cable] is not None else r for r in built.end_rolls)


def check_untwisted(built: Built, rods: list[RodTwist | None], d: mujoco.MjData) -> None:
    """Raise RuntimeError where a cable of `built` still carries twist at t = 0
    (`d` its `start_state`): MuJoCo's clamped frame not following the body
    as documented."""
    rod_of = {c.name: rod for c, rod in zip(built.cables, rods)}
    for r in built.end_rolls:
        rod = rod_of[r.cable]
        left = 0.0 if rod is None else float(rod.twist(d.qpos, d.plastic).sum())
        if abs(left) > UNTWISTED * max(1.0, abs(r.angle)):
            raise RuntimeError(f"cable {r.cable!r}: turning its clamped end by {r.angle:.6g} rad left "
                               f"{left:.3g} rad of twist at t = 0")


def clip_rolls(built: Built, rods: list[RodTwist | None], d: mujoco.MjData) -> tuple[ClipRoll, ...]:
    """Each clamped clip's hold on its cable's roll: the twist joint of its
    held edge and the edge's material vector at t = 0 (`d`, the
    `start_state`: the cable untwisted) in the frame of the body holding it."""
    out = []
    for c, rod in zip(built.cables, rods):
        if rod is None:
            continue
        for window, vertices in clamped_clips(c.attachments).items():
            edge = min(vertices)
            if rod.joint_qpos[edge] < 0:
                continue
            body = built.body_ids[next(a.body for a in c.attachments if a.window == window)]
            frame = rod.frames.start + 6 * edge
            t, u = d.plastic[frame:frame + 3], d.plastic[frame + 3:frame + 6]
            theta = float(d.qpos[rod.joint_qpos[edge]])
            material = np.cos(theta) * u + np.sin(theta) * np.cross(t, u)
            local = d.xmat[body].reshape(3, 3).T @ material
            eq = mujoco.mj_name2id(built.model, mujoco.mjtObj.mjOBJ_EQUALITY, clip_roll_name(c.name, window))
            out.append(ClipRoll(c.name, window, eq, int(rod.joint_qpos[edge]), body, frame, local))
    return tuple(out)


def without_twist_state(built: Built, rods: list[RodTwist | None], d: mujoco.MjData) -> list[str]:
    """The cables whose rod MuJoCo keeps no twist state for at t = 0 (its
    reference frames all 0 after a step, `d` the `start_state`): a turned end
    or clip winds nothing in them and their twist reads 0. None is expected:
    the causes found (docs/twist.md) are built around; this says so if one is not."""
    return [c.name for c, rod in zip(built.cables, rods) if rod is not None and not d.plastic[rod.frames].any()]
