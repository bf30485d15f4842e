"""How finely the simulation steps, and which parts move too fast for it.

`choose_substeps` divides the scene's timestep so that every cable's
edges stay stiffer than its bending (`bending_step`) and give at most half
the 0.1 % tolerance under its buckling load (`cablecheck.build.cablephysics.
compression_step`), its first mode is damped as declared, its fastest held
point moves a small fraction of an element per step (`held_speeds`, from
the script sampled through forward kinematics, `script_poses`) and, where
parts push cables, no moving part travels more than the cable's radius
in a step (`part_speeds`); `tunnel_warnings` names parts still fast enough
to carry a cable through themselves within one step. docs/physics.md explains the numbers.

This module reads a built model and evaluates the script on its own data;
it does not step the simulation nor change the model (the step is set by
`cablecheck.build.mjspec.set_step`).
"""

from __future__ import annotations

import mujoco
import numpy as np

from cablecheck.build.built import Built, CableModel, PartModel, Substeps
from cablecheck.build.cablephysics import (
    EDGE_IMPEDANCE,
    buckling_load,
    compression_step,
    damping_step,
    first_mode,
)
from cablecheck.scene.records import CableDef

MAX_SUBSTEPS = 64
"""Most simulation steps per scene step `choose_substeps` takes; beyond it
the run warns (the scene's timestep should be smaller)."""

SPEED_FRACTION = 0.05
"""Largest fraction of a cable's element that its fastest held point may
travel in one simulation step (see `choose_substeps`)."""

CONTACT_FRACTION = 1.0
"""Largest fraction of a cable's radius that a moving part may travel in one
simulation step when cable-structure contact pushes (see `choose_substeps`)."""

SPEED_SAMPLES = 400
"""Samples of the script over its duration when measuring held points' speeds."""


def bending_step(cable: CableModel, cable_def: CableDef) -> float:
    """Largest step at which the edges stay stiffer than the rod bends, seconds.

    The highest bending mode of a rod discretised into elements of length l
    has omega_b = (2 / l)^2 sqrt(EI / mu) (the beam stencil's largest
    eigenvalue, 16 EI / l^4, over mu). A soft edge constraint of time
    constant tc = 2 h and impedance d stands for an axial spring of
    frequency omega_a = 1 / (tc sqrt(1 - d)). With omega_a below omega_b,
    the rod's bending loads compress its edges instead of bending it:
    measured, a 200 GPa, 3 mm steel rod bowed between ends 0.5 m apart with
    0.6 m of length (24 elements, omega_b = 4.8e4 /s) shortened by 6.6 % at
    h = 2 ms (omega_a = 2.5e4 /s) and by 0.25 % at 1 ms (5e4 /s). So
    h <= 1 / (2 sqrt(1 - d) omega_b)."""
    l = cable.element_length
    omega_b = (2.0 / l) ** 2 * np.sqrt(cable_def.young * cable_def.radius ** 2 / (4.0 * cable_def.density))
    return float(1.0 / (2.0 * np.sqrt(1.0 - EDGE_IMPEDANCE) * omega_b))


def script_poses(built: Built) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Every body's pose along the script: times (T,), xpos (T, nbody, 3),
    xmat (T, nbody, 3, 3), model coordinates.

    Samples the script `SPEED_SAMPLES` times over the duration and at every
    key through forward kinematics, so bodies, their rotations and mjcf
    joints all count. Empty when nothing moves."""
    from cablecheck.run.motion import (
        Motion,  # motion imports cablecheck.build.stages, which imports this module
    )

    scene, m = built.scene, built.model
    if scene.duration <= 0.0 or not scene.motions:
        return np.zeros(0), np.zeros((0, m.nbody, 3)), np.zeros((0, m.nbody, 3, 3))
    times = set(np.linspace(0.0, scene.duration, SPEED_SAMPLES + 1).tolist())
    for mo in scene.motions:  # every key or file sample, on scene time
        keyed = mo.trajectory.times if mo.trajectory is not None else [k.t for k in mo.keys]
        times.update(float(t) for t in keyed if t <= scene.duration)
    times = np.unique(np.round(np.array(sorted(times)), 9))
    motion = Motion(built)
    d = mujoco.MjData(m)
    d.qpos[:] = built.qpos0
    xpos, xmat = [], []
    for t in times:
        motion.apply(d, float(t))
        mujoco.mj_kinematics(m, d)
        xpos.append(d.xpos.copy())
        xmat.append(d.xmat.reshape(-1, 3, 3).copy())
    return times, np.array(xpos), np.array(xmat)


def _max_speed(times: np.ndarray, xpos: np.ndarray, xmat: np.ndarray, body: np.ndarray,
               local: np.ndarray) -> float:
    """Fastest speed of points `local` (n, 3) riding bodies `body` (n,) along sampled poses, m/s."""
    if len(times) < 2 or len(body) == 0:
        return 0.0
    world = xpos[:, body] + np.einsum("tnij,nj->tni", xmat[:, body], local)
    return float((np.linalg.norm(np.diff(world, axis=0), axis=2) / np.diff(times)[:, None]).max())


def held_speeds(built: Built, poses=None) -> dict[str, float]:
    """Fastest speed of any held point of each cable over the script, m/s."""
    times, xpos, xmat = poses if poses is not None else script_poses(built)
    m = built.model
    out = {}
    for c in built.cables:
        verts = np.array([a.vertex + c.vert_adr for a in c.attachments], int)
        out[c.name] = _max_speed(times, xpos, xmat, m.flex_vertbodyid[verts], m.flex_vert[verts])
    return out


def part_speeds(built: Built, poses=None) -> list[tuple[PartModel, np.ndarray, float]]:
    """Each moving part that can push a cable: the part, its box's
    half-extents (`_part_extent`) and the fastest speed of the box's corners
    over the script, m/s (keepout parts and planes left out)."""
    times, xpos, xmat = poses if poses is not None else script_poses(built)
    m = built.model
    out = []
    if len(times) < 2:
        return out
    # a part on a body at the same pose at every sample moves at 0 exactly: not measured (a harness's
    # thousand parts on the world, one at a time, were a fifth of its model's build)
    moves = (np.any(xpos != xpos[:1], axis=(0, 2)) | np.any(xmat != xmat[:1], axis=(0, 2, 3)))
    for part in built.parts:
        if not moves[int(m.geom_bodyid[part.geom_id])]:
            continue
        half = _part_extent(m, part)
        if part.keepout or half is None:
            continue
        corners = np.array(np.meshgrid([-1, 1], [-1, 1], [-1, 1])).reshape(3, -1).T * half
        rot = np.zeros(9)
        mujoco.mju_quat2Mat(rot, m.geom_quat[part.geom_id])
        local = m.geom_pos[part.geom_id] + corners @ rot.reshape(3, 3).T
        body = np.full(len(local), int(m.geom_bodyid[part.geom_id]))
        v = _max_speed(times, xpos, xmat, body, local)
        if v > 0.0:
            out.append((part, half, v))
    return out


def _pushes(built: Built) -> bool:
    """Whether the simulation is stepped with cable-structure contact and has cables."""
    scene = built.scene
    return bool(scene.effects.dynamics and "cable-structure" in scene.effects.contact and built.cables)


def _part_extent(m: mujoco.MjModel, part: PartModel) -> np.ndarray | None:
    """Half-extents (3,) of a part's box in its geom frame (None for a plane)."""
    size = m.geom_size[part.geom_id]
    if part.shape == "plane":
        return None
    if part.shape == "mesh":
        return 0.5 * (part.vertices.max(axis=0) - part.vertices.min(axis=0))
    if part.shape == "sphere":
        return np.full(3, size[0])
    if part.shape in ("capsule", "cylinder"):
        return np.array([size[0], size[0], size[1] + (size[0] if part.shape == "capsule" else 0.0)])
    return np.asarray(size[:3], float)


def tunnel_warnings(built: Built, poses=None) -> list[str]:
    """Parts that move too fast for the simulation step to stop a cable.

    A contact pushes only once a cable overlaps a part (the simulation has
    no contact margin, `cablecheck.build.mjspec.SIM_MARGIN_FRACTION`), so a part moving
    at v overlaps a cable by up to v h before the contact acts. Measured
    (a plate lifted through a sagging cable, r 2 and 4 mm, plates 1 to 10
    mm thick, 1 to 8 m/s): carried in every case with v h up to the
    cable's radius; a plate 10 mm thick went through a 2 mm cable at 3 m/s
    with v h = 6 mm, below the radius plus half the thickness, and 1 mm
    plates at 1.5 radii a step. `choose_substeps` keeps v h within the
    radius; this names the parts for which `MAX_SUBSTEPS` cannot, with the
    speed and the timestep that would do (scene units)."""
    scene = built.scene
    if not _pushes(built):
        return []
    h = built.model.opt.timestep
    count = built.substeps.count if built.substeps is not None else 1
    thinnest = min(c.radius for c in built.cables)
    reach = CONTACT_FRACTION * thinnest
    unit = scene.units
    out = []
    for part, half, v in part_speeds(built, poses):
        if v * h > reach * (1.0 + 1e-9):
            out.append(f"part {part.name!r} moves at up to {v / scene.scale:.4g} {unit}/s: a simulation "
                       f"step of {h:.3g} s carries it {v * h / scene.scale:.4g} {unit}, more than the "
                       f"thinnest cable's radius ({thinnest / scene.scale:.4g} {unit}; the part is "
                       f"{2.0 * half.min() / scene.scale:.4g} {unit} thick), so a cable can pass through it; "
                       f"scene.timestep <= {reach / v * count:.3g} s would do")
    return out


def choose_substeps(built: Built, poses=None) -> Substeps:
    """Simulation steps per scene step, from each cable's stiffness and speed.

    Two causes stretch or compress a cable's edges, whose length is held
    by soft equality constraints of time constant 2 h (h the simulation
    step, `edge_time_constant`), and both shrink with h:
    - bending: a stiff rod's bending loads compress its edges unless the
      edges are stiffer than its highest bending mode (`bending_step`);
    - speed: MuJoCo linearises each edge's length at the start of a step,
      so an edge turning by an angle a per step gains about a^2 / 2 of
      strain, and a held end moving v h per step stretches the edge next
      to it. Keeping v h below `SPEED_FRACTION` of an element (v the
      fastest held point of that cable, `held_speeds`) kept a 1.2 m cable
      whose end moves 0.12 m back and forth at 5 Hz (v = 1.2 m/s, reversing
      instantly) within 0.2 % strain, and the same at 20 Hz within 0.5 %
      (measured: 5 Hz 0.55 % at h = 2 ms, 0.17 % at 1 ms; 20 Hz 3.7 % at
      2 ms, 0.5 % at 0.25 ms).
    And damping: the integrator damps the first bending mode by about
    omega_1 h / 2 of its own (`cablecheck.build.cablephysics.step_damping_ratio`), which
    the Rayleigh damping makes up to the declared ratio
    (`rayleigh_damping`); h is kept small enough that it supplies at most
    half of it (`damping_step`; a 0.2 m, r 4 mm, 400 MPa cantilever's first
    mode at 90.8 rad/s damped 0.090 at h = 2 ms with `damping` 0).
    And compression: the edge equality gives under an axial load F by
    `(1 - d) (tc + h)^2 F / (mu l^2)` of strain (`cablecheck.build.cablephysics.
    compression_strain`), so h is kept small enough that under the
    cable's buckling load (`buckling_load`: its stiffest run's Euler load,
    clamped between holds, a cantilever to a free end; past it a rod
    buckles) that is at most half of the 0.1 %
    tolerance (`compression_step`).
    And where cable-structure contact pushes, contact: a contact acts only
    once a part overlaps a cable, so no moving part may travel more than
    `CONTACT_FRACTION` of the cable's radius in a step (v the fastest
    part's speed, `part_speeds`; measured in `tunnel_warnings`).
    The scene's timestep is divided by the smallest whole number that meets
    every cable's need, at most `MAX_SUBSTEPS`."""
    scene = built.scene
    dt = scene.timestep
    needed, reasons = {}, {}
    speeds = held_speeds(built, poses) if scene.effects.dynamics else {}
    parts = max((v for _, _, v in part_speeds(built, poses)), default=0.0) if _pushes(built) else 0.0
    defs = {c.name: c for c in scene.cables}
    for c in built.cables:
        cd = defs[c.name]
        bend = bending_step(c, cd)
        v = speeds.get(c.name, 0.0)
        speed = SPEED_FRACTION * c.element_length / v if v > 0.0 else np.inf
        contact = CONTACT_FRACTION * c.radius / parts if parts > 0.0 else np.inf
        held = [a.vertex for a in c.attachments]
        omega = first_mode(c.rest_s, held, cd)
        damp = damping_step(cd.damping, omega)
        squeeze = compression_step(buckling_load(c.rest_s, held, cd), c.element_length, cd)
        needed[c.name] = float(min(bend, speed, contact, damp, squeeze))
        if squeeze < min(bend, speed, contact, damp):
            reasons[c.name] = ("compression", v, c.element_length)
        elif damp < min(bend, speed, contact):
            reasons[c.name] = ("damping", omega, c.element_length)
        elif contact < min(bend, speed):
            reasons[c.name] = ("contact", parts, c.element_length)
        else:
            reasons[c.name] = ("bending" if bend <= speed else "speed", v, c.element_length)
    h = min(needed.values(), default=dt)
    count = max(1, int(np.ceil(dt / h * (1.0 - 1e-9)))) if scene.effects.dynamics else 1
    capped = count > MAX_SUBSTEPS
    count = min(count, MAX_SUBSTEPS)
    return Substeps(count, dt / count, needed, reasons, capped)
