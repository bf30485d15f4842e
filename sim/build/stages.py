"""Build a validated scene into MuJoCo models: the stages in order.

1. Place the scene at t = 0 in model coordinates (`cablecheck.build.startframes`: the
   model's origin, body frames, mesh parts read once).
2. Plan every cable: its routed shape, drooping clear of the parts it
   collides with (`cablecheck.build.obstacles`), its held vertices and its straight rest
   shape (`cablecheck.build.cableplan`).
3. Write and compile the simulation model, then the detection model
   (`cablecheck.build.mjspec`, with the contact bits of `cablecheck.build.contactbits` and the cable
   parameters of `cablecheck.build.cablephysics`). `build` does both; a run calls
   `build_simulation` and later `with_detection`, so the simulation can
   settle while the detection model is compiled (`cablecheck.run.runner`).
4. Read the compiled model back as a `Built` (`cablecheck.build.modelread`).
5. Choose the simulation step from the cables' stiffness and the script's
   speeds, and warn about parts too fast for it (`cablecheck.build.substeps`).

docs/physics.md explains the model and its numbers.

This module does not step, move or read the simulation; see `cablecheck.run.loop`.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from cablecheck.build.built import (
    Built,
)
from cablecheck.build.cablephysics import (
    first_mode,
    shear_modulus,
)
from cablecheck.build.cableplan import CablePlan, has_slack, plan_cable
from cablecheck.build.mjspec import compile_model, move_held, set_step
from cablecheck.build.modelread import read_built
from cablecheck.build.obstacles import Obstacles
from cablecheck.build.pinch import contacts_at, held_pinch
from cablecheck.build.rodtwist import rod_twist
from cablecheck.build.startframes import Frames, part_meshes, scene_origin
from cablecheck.build.substeps import (
    MAX_SUBSTEPS,
    choose_substeps,
    script_poses,
    tunnel_warnings,
)
from cablecheck.build.untwist import untwisted
from cablecheck.scene.records import Scene


def plan_cables(scene: Scene) -> tuple[Frames, dict[str, tuple[np.ndarray, np.ndarray]], list[CablePlan]]:
    """The scene placed at t = 0 (body frames in model coordinates), its mesh
    parts read (name -> vertices, faces) and every cable planned."""
    frames = Frames(scene, scene_origin(scene))
    meshes = part_meshes(scene)
    obstacles = None
    if "cable-structure" in scene.effects.contact and any(has_slack(c) for c in scene.cables):
        obstacles = Obstacles(scene, frames, meshes)
    plans = [plan_cable(c, frames, f"cables[{i}]", scene, obstacles) for i, c in enumerate(scene.cables)]
    return frames, meshes, plans


def check_cables(scene: Scene) -> None:
    """Raise the SceneError `plan_cables` would raise for the scene's cables
    (a length shorter than the route through the clips, or than the route
    leaving its clamps along their tangents; too few segments), without
    shaping them: no droop found (nor scipy loaded for it), no part
    prepared. A study checks every variant so before any runs."""
    frames = Frames(scene, scene_origin(scene))
    for i, c in enumerate(scene.cables):
        plan_cable(c, frames, f"cables[{i}]", scene, shaped=False)


def build(scene: Scene, detect: bool = True) -> Built:
    """Compile the simulation model (and, if `detect`, the detection model),
    then choose its step (`choose_substeps`)."""
    planned = plan_cables(scene)
    built = build_simulation(scene, planned)
    return with_detection(built, planned) if detect else built


def build_simulation(scene: Scene, planned: tuple) -> Built:
    """`build` without the detection model, from the scene's `plan_cables`."""
    frames, meshes, plans = planned
    origin = frames.origin
    sim, own_bits = compile_model(scene, plans, meshes, detect=False, frames=frames, rest=True)
    move_held(sim, plans, frames)
    read = read_built(scene, sim, None, plans, origin, own_bits)   # the model as compiled, not yet stepped
    if scene.effects.dynamics:
        read, stateless = untwisted(replace(read, rods=cable_rods(read)))
    poses = script_poses(read) if scene.effects.dynamics else None
    substeps = choose_substeps(read, poses)
    set_step(sim, substeps.step, cable_damping(read))
    warnings = tuple(tunnel_warnings(read, poses))
    if substeps.capped:
        need = min(substeps.needed.values())
        warnings += (f"the cables need a simulation step of {need:.3g} s (see docs/physics.md) but "
                     f"at most {MAX_SUBSTEPS} steps are taken per scene timestep; scene.timestep "
                     f"<= {need * MAX_SUBSTEPS:.3g} s would do",)
    warnings += held_pinch_warnings(read)
    if scene.effects.dynamics:
        warnings += tuple(f"cable {name!r}: MuJoCo keeps no twist state for its rod, so a turned end or clip "
                          "winds nothing in it and its twist reads 0 (docs/twist.md)" for name in stateless)
    return replace(read, substeps=substeps, warnings=warnings)


def held_pinch_warnings(built: Built) -> tuple[str, ...]:
    """One warning per cable whose held point MuJoCo finds pressed into a part of another body at
    t = 0, as routed (`cablecheck.build.pinch`): the simulation starts with its hold and a contact
    fighting, which a run may not survive."""
    if "cable-structure" not in built.scene.effects.contact:
        return ()
    out = []
    at_start = contacts_at(built, built.qpos0)      # one collision pass for every cable
    for i in range(len(built.cables)):
        found = held_pinch(built, at_start, i, None)
        if found is not None:
            out.append(f"at t = 0, as routed, {found}: the simulation starts with the hold and that contact "
                       "fighting (the settling may push the cable out, or the run diverge); route the cable clear "
                       "of that part next to its hold")
    return tuple(out)


def cable_rods(built: Built) -> tuple:
    """Each cable's twist layout in the simulation model (`cablecheck.build.rodtwist`),
    with its `shear_modulus`."""
    defs = {c.name: c for c in built.scene.cables}
    return tuple(rod_twist(built.model, c.flex_id, c.rest_s, shear_modulus(defs[c.name]), c.radius)
                 for c in built.cables)


def cable_damping(built: Built) -> dict[int, tuple[float, float]]:
    """Each cable's flex id -> (its `damping`, its first bending mode as held, `first_mode`)."""
    defs = {c.name: c for c in built.scene.cables}
    return {c.flex_id: (defs[c.name].damping, first_mode(c.rest_s, [a.vertex for a in c.attachments], defs[c.name]))
            for c in built.cables}


def with_detection(built: Built, planned: tuple) -> Built:
    """`built` (`build_simulation`) with its detection model, compiled from
    the same `plan_cables`: a new record, `built` itself unchanged."""
    scene = built.scene
    frames, meshes, plans = planned
    # compiled on the rest shape as the simulation is, then held where it holds:
    # on the routed shape a held end could fold exactly back onto the free
    # vertices' rest line, which MuJoCo refuses (a degenerate flex hinge)
    det = compile_model(scene, plans, meshes, detect=True, frames=frames, rest=True, like=built.model)[0]
    move_held(det, plans, frames)
    if det.nq != built.model.nq or det.ngeom != built.model.ngeom:
        raise RuntimeError("detection and simulation models differ in structure")
    return replace(built, detect=det)
