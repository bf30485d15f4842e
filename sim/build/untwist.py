"""Every cable starts untwisted as routed: the end roll that takes out the
twist the straight compile would leave between a cable's clamped ends.

MuJoCo fixes a clamped end edge's material frame in the body holding it as
the model is compiled, and cablecheck compiles each cable straight (its rest
shape, `cablecheck.build.mjspec.compile_model`). Put into its routed shape,
a cable's frame carried along the route from its start then meets the end's
frame at an angle that depends on the route alone (a cable bent out of one
plane: 41 degrees on a 1 m cable routed through one corner, 156 and 84
degrees on robot_cell's two), which MuJoCo would read as twist held between
the clamps. A cable routed in CAD carries none, so the body holding the
clamped end (`cablecheck.build.mjspec.end_roll_body`) is turned about the
end's held edge by that angle, measured on the compiled model at t = 0.
MuJoCo restarts the reference frames from the first edge at
`mj_resetData`, so the state a run starts from is the one measured here.

This module does not read twist during a run (see `cablecheck.build.rodtwist`
and `cablecheck.run.runner`).
"""

from __future__ import annotations

from dataclasses import replace

import mujoco
from cablecheck.build.built import Built, EndRoll
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


def untwist_ends(built: Built, rods: list[RodTwist | None]) -> tuple[EndRoll, ...]:
    """`built.end_rolls` with the angles that start each cable untwisted
    (`rods` per cable of `built`). Raises RuntimeError where the angle does
    not take the twist out (MuJoCo's clamped frame not following the body
    as documented)."""
    if not built.end_rolls:
        return ()
    rod_of = {c.name: rod for c, rod in zip(built.cables, rods)}
    d = start_state(built)
    rolls = tuple(replace(r, angle=r.angle - float(rod_of[r.cable].twist(d.qpos, d.plastic).sum()))
                  if rod_of[r.cable] is not None else r for r in built.end_rolls)
    d = start_state(replace(built, end_rolls=rolls))
    for r in rolls:
        rod = rod_of[r.cable]
        left = 0.0 if rod is None else float(rod.twist(d.qpos, d.plastic).sum())
        if abs(left) > UNTWISTED * max(1.0, abs(r.angle)):
            raise RuntimeError(f"cable {r.cable!r}: turning its clamped end by {r.angle:.6g} rad left "
                               f"{left:.3g} rad of twist at t = 0")
    return rolls
