"""The scene written as a MuJoCo model, and compiled.

Why MjSpec: a scene may start from a user's own MJCF (a robot arm, a
fixture) whose relative mesh paths, defaults and names must survive intact.
`MjSpec.from_file` loads it exactly as MuJoCo would; scene bodies, parts and
meshes are then added through the spec API, and the cables, which only the
`flexcomp` macro can generate (twist bodies, pinning, the edge equality), are
written as one small MJCF string and attached into the spec. The held
points are then moved onto the bodies that hold them (`_hold_vertices`).

Scripted `[[bodies]]` are free bodies whose pose and velocity the script
sets every step (see `Built.free`); the base model's joints are driven the
same way. Both get a large armature so the cable's reaction barely moves
them within a step, and the loop puts them back on the script at each
step's end.

Two models come out of one scene (`compile_model`'s `detect`):
- the simulation model, in which only the interactions listed in
  `effects.contact` collide (`cablecheck.build.contactbits`), with no margin, so
  nothing the scene did not ask for pushes back;
- the detection model, with the same bodies and degrees of freedom (so the
  simulation's qpos can be copied into it) but every interaction enabled and
  margins set from the clearance. It is never stepped (`never_stepped`
  leaves out what only stepping reads): `mj_kinematics`, `mj_flex` and
  `mj_collision` on the simulated positions give MuJoCo's own view of every
  pair the checker may report, exact (a large contact `gap` in the simulation
  model would make MuJoCo's general convex collider inexact, see SPEC); a
  concave mesh is seen there as its own triangles, not as the convex hull
  MuJoCo collides a mesh geom with (`cablecheck.detection.mesh`).

This module does not plan the cables' shapes (see `cablecheck.build.cableplan`), choose
the step (see `cablecheck.build.substeps`) nor read the compiled model back (see
`cablecheck.build.modelread`).
"""

from __future__ import annotations

from xml.sax.saxutils import quoteattr

import mujoco
import numpy as np

from cablecheck.build.built import CABLE_PREFIX, end_roll_body, vertex_body
from cablecheck.build.cablephysics import (
    CONTACT_SOLIMP,
    EDGE_IMPEDANCE,
    contact_time_constant,
    edge_solimp,
    edge_time_constant,
    first_mode,
    rayleigh_damping,
)
from cablecheck.build.cableplan import CablePlan, clamped_clips
from cablecheck.build.contactbits import ContactBits, cable_bits, model_bits, part_bits
from cablecheck.build.startframes import Frames
from cablecheck.detection.mesh import add_surfaces, check_surfaces
from cablecheck.scene.errors import SceneError
from cablecheck.scene.frames import euler_matrix
from cablecheck.scene.mjcf import lean_spec
from cablecheck.scene.records import CableDef, PartDef, Scene

BASE_ARMATURE = 100.0
"""Armature added to the base model's joints, which are driven kinematically:
the cable's reaction barely moves them within the one step before the script
sets them again."""
ROLL_MASS = 1e-6
"""kg: an end roll body's (`_add_end_roll`): a body on a joint needs one; its hinge's armature rules."""

PLANE_GRID = 0.1
"""Grid spacing MuJoCo draws on a plane part given no size, metres."""

CABLE_PRIORITY = 1
"""Contact priority of a cable that sets no `friction`: above the parts'
MuJoCo default 0, so its contacts take the cable's solref and solimp
(`cablecheck.build.cablephysics.contact_time_constant`) and MuJoCo's default friction 1.0."""

FRICTION_PRIORITY = 2
"""Contact priority of a cable or part that sets `friction`. MuJoCo takes a
contact's friction (and solref, solimp, condim) from the side of higher
priority, and where the priorities are equal the element-wise maximum of
the frictions: so a side that sets friction wins over one that does not
(a cable's 0.3 on a part without friction is 0.3, not MuJoCo's default 1.0
of the part), and where both set one the larger applies (MuJoCo's rule).
A part that sets friction carries the cables' contact solref, solimp and
condim (and solmix 0: the cable's mix where they meet at equal priority),
so only the friction changes."""

SIM_MARGIN_FRACTION = 0.0
"""Contact margin in the simulation model, as a fraction of the thinnest cable radius: none.

Since MuJoCo 4 a margin inflates the surfaces it is set on (XMLreference,
geom margin; the two sides' margins are summed): a contact pushes once the
distance is below the margin, on `dist - margin`. With 0.25 r on the cables
and on the parts a cable rested half a radius off what it lay on (2.0 mm for
r = 4 mm) and never read as touching; with none it rests within 0.1 % of the
radius (tests/test_resting.py). A part then meets a cable only once they
overlap, as the tunnelling rule assumes (`cablecheck.build.substeps.tunnel_warnings`)."""


def euler_quat(euler_deg) -> np.ndarray:
    q = np.zeros(4)
    mujoco.mju_mat2Quat(q, euler_matrix(euler_deg).ravel())
    return q


def part_size(part: PartDef) -> list[float]:
    """MuJoCo's three size numbers of a primitive part, metres (unused ones 0)."""
    size = [float(x) for x in part.size] + [0.0] * (3 - len(part.size))
    if part.shape == "plane":
        # MuJoCo's plane is infinite whatever its size: x, y half-sizes
        # are for drawing (0: infinite), the third, the drawn grid's
        # spacing, must be positive
        size[2] = size[2] or max(size[0], size[1]) / 10.0 or PLANE_GRID
    return size


def base_spec(scene: Scene) -> mujoco.MjSpec:
    """The scene's mjcf model without what MuJoCo only draws
    (`cablecheck.scene.mjcf.lean_spec`), or an empty spec."""
    if scene.mjcf is None:
        return mujoco.MjSpec()
    try:
        return lean_spec(scene.mjcf)
    except Exception as e:  # MuJoCo raises ValueError with its parser message
        raise SceneError(scene.path, "scene.mjcf", f"MuJoCo cannot load {scene.mjcf}: {e}") from None


def _set_options(spec: mujoco.MjSpec, scene: Scene) -> None:
    opt = spec.option
    opt.timestep = scene.timestep
    opt.integrator = mujoco.mjtIntegrator.mjINT_DISCRETE  # rod elasticity needs it (SPEC)
    opt.solver = mujoco.mjtSolver.mjSOL_NEWTON
    # Elliptic friction cones: Coulomb friction the same in every direction of
    # the contact plane. MuJoCo's default pyramidal cone bounds |f1| + |f2| by
    # mu N in the contact frame (mu / sqrt 2 between its axes) and lets a
    # cable with friction 0.3 slide down a 15 degree slope (tan 15 = 0.27)
    # along some azimuths (tests/test_friction.py, docs/physics.md).
    opt.cone = mujoco.mjtCone.mjCONE_ELLIPTIC
    opt.tolerance = 1e-8
    opt.iterations = max(opt.iterations, 100)
    # no noslip pass: MuJoCo refuses it with flexes under the discrete integrator (an mjcf model's
    # `noslip_iterations`, gymnasium's Adroit hand 20, stopped every run on it)
    opt.noslip_iterations = 0
    opt.gravity = [0.0, 0.0, -9.81] if scene.effects.gravity else [0.0, 0.0, 0.0]
    opt.viscosity = 0.0  # no medium: cables are damped by their own material (`rayleigh_damping`)
    opt.density = 0.0
    # Unused features stay off: no actuators are driven, no sensors are read.
    opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_ACTUATION)
    opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_SENSOR)
    spec.compiler.autolimits = True


def _fmt(values) -> str:
    return " ".join(repr(float(v)) for v in np.ravel(values))


DETECT_CCD_TOLERANCE = 1e-7
"""The detection model's tolerance of MuJoCo's convex collision (GJK/EPA,
metres; MuJoCo's default 1e-6). At the default a cable resting on a part
read up to 1.4e-7 m apart from the exact distance, and a contact the
checker finds touching (-1.4e-7 m) MuJoCo read just clear (+2e-10 m):
classed hard and soft, a disagreement at every step, 17.5 % of a resting
hose's (step, pair) classifications on four primitives
(benchmarks/bench_near.py). At 1e-7 they agree; the robot cell's collision
pass costs 15 % more (1e-9: 45 %)."""

MUJOCO_MAJOR = 4
"""The MuJoCo these models are written for (pyproject: mujoco-core 4)."""


def require_mujoco(found: str) -> None:
    """Raise RuntimeError naming the MuJoCo found when it is not `MUJOCO_MAJOR`'s: another package's
    dependency on the `mujoco` package 3.x replaces mujoco-core 4's `mujoco` module, and the models
    then fail to compile in ways that name no cause (a flex not found by name)."""
    if int(found.split(".")[0]) != MUJOCO_MAJOR:
        raise RuntimeError(f"cablecheck needs MuJoCo {MUJOCO_MAJOR} (the mujoco-core package) but Python imports "
                           f"MuJoCo {found}: another package's `mujoco` {found.split('.')[0]}.x replaced its module "
                           "(pip uninstall mujoco; pip install --force-reinstall --no-deps mujoco-core)")


def compile_model(scene: Scene, plans: list[CablePlan], meshes: dict[str, tuple[np.ndarray, np.ndarray]],
             detect: bool, frames: Frames, rest: bool = False,
             like: mujoco.MjModel | None = None) -> tuple[mujoco.MjModel, np.ndarray]:
    """The model, and (ngeom, 2) contype, conaffinity of each geom of the mjcf
    model as written (0, 0 for the geoms the scene adds).

    `rest`: the held vertices sit on the cables' straight rest shape. MuJoCo
    takes a rod's rest curvature from its shape at qpos0, where the free
    vertices lie on the straight rest shape but held vertices would be
    where their bodies hold them on the route: each vertex next to a held
    one would keep a kink as rest curvature. `build` compiles the
    simulation model with `rest` and then moves the held vertices to their
    routed places (`move_held`: `flex_vert` only), so every cable is
    straight at rest.

    `detect`: the detection model; `like` is then the simulation model,
    compiled from the same scene and plans, whose meshes (as MuJoCo
    processed them) give the concave meshes' surfaces
    (`cablecheck.detection.mesh.add_surfaces`)."""
    require_mujoco(mujoco.__version__)
    origin = frames.origin
    spec = base_spec(scene)
    _set_options(spec, scene)
    # Model coordinates are the scene's world less `origin` (see scene_origin).
    for child in spec.worldbody.bodies:
        child.pos = list(np.asarray(child.pos, float) - origin)
    for g in spec.worldbody.geoms:
        g.pos = list(np.asarray(g.pos, float) - origin)
    for j in spec.joints:
        j.armature = BASE_ARMATURE
    for b in spec.bodies:
        if b.name != "world":
            b.gravcomp = 1.0

    radii = [c.radius for c in scene.cables] or [1.0]
    margin = scene.check.clearance if detect else SIM_MARGIN_FRACTION * min(radii)

    # The base model's colliding geoms are structure parts; they keep their own
    # bits, and the scene's are added (cablecheck.build.contactbits). Visual geoms (both 0)
    # stay out of every collision.
    colliding = [g for g in spec.geoms if g.contype or g.conaffinity]
    own = [(g, int(g.contype), int(g.conaffinity)) for g in colliding]
    used = 0
    for g in colliding:
        used |= int(g.contype) | int(g.conaffinity)
    try:
        bits = ContactBits.free_of(used)
    except ValueError as e:
        raise SceneError(scene.path, "scene.mjcf", str(e)) from None
    for g in colliding:
        g.contype, g.conaffinity = model_bits(scene, bits, detect, (int(g.contype), int(g.conaffinity)))
        g.margin = margin

    neutral = neutral_default(spec)     # what the scene adds takes MuJoCo's defaults, not the mjcf model's
    for body in scene.bodies:
        b = spec.worldbody.add_body(default=neutral, name=body.name, pos=list(np.asarray(body.pos, float) - origin),
                                    quat=list(euler_quat(body.euler)), gravcomp=1.0)
        b.add_joint(default=neutral, type=mujoco.mjtJoint.mjJNT_FREE, name=f"{body.name}/free").armature = BASE_ARMATURE
        # a free body needs mass; parts on it carry none of their own here
        b.explicitinertial = True
        b.mass = 1.0
        b.inertia = [1.0, 1.0, 1.0]
    for part in scene.parts:
        parent = spec.worldbody if part.body == "world" else spec.body(part.body)
        contype, conaff = part_bits(scene, bits, detect, part.keepout)
        pos = np.asarray(part.pos, float) - (origin if part.body == "world" else 0.0)
        # MuJoCo's defaults, not the body's childclass nor the model's main class: a part on an mjcf
        # link keeps cablecheck's contact parameters, not the robot's (Fetch's gripper class gives
        # condim 4, solref and solimp)
        common = dict(default=neutral, name=part.name, pos=list(pos), quat=list(euler_quat(part.euler)),
                      contype=contype, conaffinity=conaff, margin=margin,
                      rgba=[0.9, 0.5, 0.1, 0.3] if part.keepout else [0.6, 0.6, 0.65, 1.0])
        if part.shape == "mesh":
            verts, faces = meshes[part.name]
            spec.add_mesh(name=f"mesh:{part.name}", uservert=verts.ravel().tolist(),
                          userface=faces.ravel().tolist())
            geom = parent.add_geom(type=mujoco.mjtGeom.mjGEOM_MESH, meshname=f"mesh:{part.name}", **common)
        else:
            gtype = getattr(mujoco.mjtGeom, f"mjGEOM_{part.shape.upper()}")
            geom = parent.add_geom(type=gtype, size=part_size(part), **common)
        if part.friction is not None:
            _set_friction(geom, part.friction, scene.timestep)

    if plans:
        child = mujoco.MjSpec.from_string(_cables_xml(plans, scene, bits, detect, margin))
        spec.attach(child, frame=spec.worldbody.add_frame(), prefix=CABLE_PREFIX)
        placed = frames.at_qpos0(scene, plans) if rest else frames
        for plan in plans:
            _hold_vertices(spec, plan, placed, rest)
            _add_end_roll(spec, plan, frames, neutral)
            _add_clip_rolls(spec, plan, scene.timestep)
    if detect:
        if like is None:
            raise ValueError("the detection model reads its meshes from the simulation's: pass it as `like`")
        spec.option.ccd_tolerance = DETECT_CCD_TOLERANCE
    # concave meshes as their true surface, not MuJoCo's hull (cablecheck.detection.mesh)
    surfaces = add_surfaces(spec, like, bits.cable) if detect else []
    try:
        model = spec.compile()
        if detect:
            never_stepped(model)
    except Exception as e:  # MuJoCo's compiler raises ValueError with its message
        raise SceneError(scene.path, "(model)", f"MuJoCo cannot compile the scene: {e}") from None
    check_surfaces(surfaces)
    own_bits = np.zeros((model.ngeom, 2), np.int64)
    for g, contype, conaff in own:
        own_bits[g.id] = contype, conaff
    return model, own_bits


def _set_friction(geom, friction: float, timestep: float) -> None:
    """A part's geom that sets `friction` (see FRICTION_PRIORITY)."""
    geom.priority = FRICTION_PRIORITY
    geom.friction = [friction, geom.friction[1], geom.friction[2]]
    geom.condim = 3
    geom.solmix = 0.0
    geom.solref = [contact_time_constant(timestep), 1.0]
    geom.solimp = list(CONTACT_SOLIMP)


def _friction_geoms(m: mujoco.MjModel) -> np.ndarray:
    """The geoms of parts that set friction (`_set_friction`)."""
    return (m.geom_priority == FRICTION_PRIORITY) & (m.geom_solmix == 0.0)


def never_stepped(model: mujoco.MjModel) -> None:
    """Leave out of the detection model what only stepping reads: its flexes'
    edge equality, edge stiffness and damping and their damping. mj_flex
    then skips their edges' Jacobians (it computes them only for a flex with
    one of these), and nothing else of the pass reads them: the vertices,
    element boxes, trees, edge lengths and contacts are the same, and the
    pass needs no mj_comPos (the Jacobians were the only reader of its
    output there)."""
    model.flex_edgeequality[:] = 0
    model.flex_edgestiffness[:] = 0.0
    model.flex_edgedamping[:] = 0.0
    model.flex_damping[:] = 0.0


def _hold_vertices(spec: mujoco.MjSpec, plan: CablePlan, frames: Frames, rest: bool) -> None:
    """Put each held vertex on the body that holds it; give free vertices their mass.

    A held vertex is a vertex of its body (MuJoCo's flex takes vertices on
    articulated bodies), at its routed position in that body's frame: it
    moves exactly with the body, with no constraint between them to lag or
    stretch, and the body takes the cable's reaction. The flexcomp pins the
    held points (so it omits the twist joint of a clamped end edge); they are
    moved here from the flexcomp's frame to their bodies.

    `rest`: place the held vertices on the straight rest shape instead (see
    `compile_model`: the model whose rest curvature is copied).

    Masses are lumped per vertex: the cable's mass per length times half
    the length of the elements meeting there (flexcomp would give every
    point the same share, a whole element's worth at a free end)."""
    c = plan.cable
    flex = next(f for f in spec.flexes if f.name == f"{CABLE_PREFIX}{c.name}")
    bodies = list(flex.vertbody)
    vert = np.array(flex.vert, float).reshape(-1, 3)
    shape = plan.straight if rest else plan.routed
    for h in plan.held:
        bodies[h.vertex] = h.body
        vert[h.vertex] = frames.to_local(h.body, shape[h.vertex])
    flex.vertbody = bodies
    flex.vert = vert.ravel().tolist()
    seg = np.linalg.norm(np.diff(plan.straight, axis=0), axis=1)
    share = 0.5 * (np.concatenate([[0.0], seg]) + np.concatenate([seg, [0.0]]))
    per_length = c.density * np.pi * c.radius ** 2
    held = {h.vertex for h in plan.held}
    for v in range(len(plan.straight)):
        if v in held:
            continue
        b = spec.body(vertex_body(c.name, v))
        b.mass = per_length * share[v]
        b.inertia = [b.mass * (2.0 * c.radius) ** 2 / 6.0] * 3


NEUTRAL_CLASS = "cablecheck:neutral"
"""The default class `neutral_default` adds to a model."""

_NEUTRAL_JOINT = ("limited", "range", "actfrclimited", "actfrcrange", "actgravcomp", "stiffness", "springref",
                  "springdamper", "damping", "frictionloss", "margin", "solref_limit", "solimp_limit",
                  "solref_friction", "solimp_friction", "armature", "ref", "group")
_NEUTRAL_GEOM = ("condim", "contype", "conaffinity", "friction", "solref", "solimp", "solmix", "priority", "gap",
                 "margin", "group", "density", "fluid_ellipsoid", "fluid_coefs")


def neutral_default(spec: mujoco.MjSpec) -> mujoco.MjsDefault:
    """A default class of `spec` whose joints and geoms take MuJoCo's own
    defaults (those of an empty model) for every attribute that acts on the
    physics, whatever the mjcf model's main class sets: for the bodies,
    joints and geoms the scene adds (its parts, its scripted bodies, an end's
    roll hinge). A class of the model's would give them its values: Adroit's
    main class limits every joint (`limited="true"`, no range: MuJoCo refuses
    the roll hinge), damps it and adds friction loss; Fetch's and the kitchen
    Franka's childclasses did the same on their links."""
    own = spec.add_default(NEUTRAL_CLASS, spec.default)
    empty = mujoco.MjSpec()              # kept alive while its defaults are read
    for attr in _NEUTRAL_JOINT:
        setattr(own.joint, attr, getattr(empty.default.joint, attr))
    for attr in _NEUTRAL_GEOM:
        setattr(own.geom, attr, getattr(empty.default.geom, attr))
    return own


def end_clamp(plan: CablePlan) -> tuple[str, list[int]] | None:
    """The body and the two vertices of a cable's clamped end, or None (a pinned or free end)."""
    held = [h for h in plan.held if h.kind == "end"]
    if len(held) != 2:
        return None
    return held[0].body, sorted(h.vertex for h in held)


def _add_end_roll(spec: mujoco.MjSpec, plan: CablePlan, frames: Frames, neutral: mujoco.MjsDefault) -> None:
    """Hold a clamped end through a child body of its holder, the end roll
    body: at the routed end point, on a hinge about the routed end edge
    (on which both held vertices lie, so turning it moves nothing), which
    the run holds at the angle `cablecheck.build.untwist` finds, so the cable
    starts untwisted as routed (`Built.end_rolls`).

    MuJoCo fixes a clamped end edge's material frame to its body as the
    body turns from its pose at qpos0, the cable is compiled straight, and
    as routed its end frame is turned from the frame carried along the
    route by an angle that depends on the route alone (docs/twist.md). The
    hinge turns that frame; a turn of the body's own `quat` would not (it
    turns the pose at qpos0 too). Like every joint the run drives, it has a
    large armature, so the rod's moment barely turns it within a step."""
    clamp = end_clamp(plan)
    if clamp is None:
        return
    body, (inner, end) = clamp
    parent = spec.worldbody if body == "world" else spec.body(body)
    name = end_roll_body(plan.cable.name)
    pos = frames.to_local(body, plan.routed[end])
    axis = pos - frames.to_local(body, plan.routed[inner])
    # MuJoCo's defaults (`neutral_default`), not a class of the model's: a link's class or
    # the model's main one may limit its joints (range 0 0, which MuJoCo refuses: Adroit's main
    # class) or damp them (Fetch's: 50)
    roll = parent.add_body(default=neutral, name=name, pos=list(pos), gravcomp=1.0)
    roll.explicitinertial = True
    roll.mass = ROLL_MASS
    roll.inertia = [ROLL_MASS * plan.cable.radius ** 2] * 3
    roll.add_joint(default=neutral, name=name, type=mujoco.mjtJoint.mjJNT_HINGE, axis=list(axis / np.linalg.norm(axis)),
                   armature=BASE_ARMATURE)
    flex = next(f for f in spec.flexes if f.name == f"{CABLE_PREFIX}{plan.cable.name}")
    bodies = list(flex.vertbody)
    vert = np.array(flex.vert, float).reshape(-1, 3)
    for v in (inner, end):
        bodies[v] = name
        vert[v] -= pos
    flex.vertbody = bodies
    flex.vert = vert.ravel().tolist()


def clip_roll_name(cable: str, window: str) -> str:
    """The name of the equality that holds a clamped clip's roll (`_add_clip_rolls`)."""
    return f"{CABLE_PREFIX}{cable}/{window} roll"


def _add_clip_rolls(spec: mujoco.MjSpec, plan: CablePlan, timestep: float) -> None:
    """An equality on the twist joint of each clamped clip's held edge, whose
    angle the run sets every step so the edge's material frame follows the
    clip's body (`cablecheck.run.cliphold`): MuJoCo's rod clamps the frames
    of its first and last edges only. As stiff as the edges' equalities
    (their time constant and impedance, `EDGE_IMPEDANCE` at every angle)."""
    for window, vertices in clamped_clips(plan.held).items():
        spec.add_equality(name=clip_roll_name(plan.cable.name, window), type=mujoco.mjtEq.mjEQ_JOINT,
                          objtype=mujoco.mjtObj.mjOBJ_JOINT,
                          name1=f"{CABLE_PREFIX}{plan.cable.name}_twist_{min(vertices)}",
                          solref=[edge_time_constant(timestep), 1.0],
                          solimp=[EDGE_IMPEDANCE, EDGE_IMPEDANCE, 0.001, 0.5, 2.0])


def _cables_xml(plans: list[CablePlan], scene: Scene, bits: ContactBits, detect: bool, margin: float) -> str:
    contype, conaff = cable_bits(scene, bits, detect)
    selfcollide = "auto" if (detect or "self" in scene.effects.contact) else "none"
    contact_solref = contact_time_constant(scene.timestep)
    parts = []
    for plan in plans:
        c = plan.cable
        n = len(plan.straight)
        seg = np.linalg.norm(np.diff(plan.straight, axis=0), axis=1)
        length = float(seg.sum())
        omega = first_mode(np.concatenate([[0.0], np.cumsum(seg)]), [h.vertex for h in plan.held], c)
        mass = c.density * np.pi * c.radius ** 2 * length
        pins = sorted({h.vertex for h in plan.held})
        pin = f'<pin id="{" ".join(map(str, pins))}"/>' if pins else ""
        elements = " ".join(f"{i} {i + 1}" for i in range(n - 1))
        if c.friction is None:
            friction = f'priority="{CABLE_PRIORITY}"'
        else:
            friction = f'priority="{FRICTION_PRIORITY}" friction="{c.friction!r} 0.005 0.0001"'
        # inertiabox: the vertex bodies only slide, so their rotational
        # inertia never acts; the cable's radius keeps it well scaled.
        parts.append(f"""
  <flexcomp name={quoteattr(c.name)} type="direct" dim="1" radius="{c.radius!r}" mass="{mass!r}"
            inertiabox="{2.0 * c.radius!r}" point="{_fmt(plan.straight)}" element="{elements}">
    {pin}
    <edge equality="true" solref="{edge_time_constant(scene.timestep)!r} 1" solimp="{edge_solimp(plan)}"/>
    <elasticity young="{c.young!r}" damping="{rayleigh_damping(c.damping, omega, scene.timestep)!r}"{_shear(c)}/>
    <contact selfcollide="{selfcollide}" contype="{contype}" conaffinity="{conaff}"
             margin="{margin!r}" condim="3" solref="{contact_solref!r} 1"
             solimp="{_fmt(CONTACT_SOLIMP)}" {friction}/>
  </flexcomp>""")
    return "<mujoco><worldbody>" + "".join(parts) + "\n</worldbody></mujoco>"


def _shear(cable: CableDef) -> str:
    """The rod's torsional (shear) modulus attribute: `twist_stiffness`, else
    MuJoCo's default E / (2 (1 + poisson)) = E / 2 (docs/twist.md)."""
    return "" if cable.twist_stiffness is None else f' shear="{cable.twist_stiffness!r}"'


def move_held(m: mujoco.MjModel, plans: list[CablePlan], frames: Frames) -> None:
    """Move the held vertices of a model compiled with `rest` to their routed
    places on their bodies (`flex_vert`: vertex positions in body frames;
    a clamped end's in its end roll body, `_add_end_roll`)."""
    for plan in plans:
        fid = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_FLEX, f"{CABLE_PREFIX}{plan.cable.name}")
        adr = int(m.flex_vertadr[fid])
        clamp = end_clamp(plan)
        roll = None if clamp is None else m.body(end_roll_body(plan.cable.name)).id
        for h in plan.held:
            local = frames.to_local(h.body, plan.routed[h.vertex])
            if roll is not None and h.vertex in clamp[1]:
                local = local - m.body_pos[roll]
            m.flex_vert[adr + h.vertex] = local


def set_step(m: mujoco.MjModel, step: float, damping: dict[int, tuple[float, float]] | None = None) -> None:
    """Set the simulation step and what is tied to it (the time constants
    of the edge equalities and of the cables' contacts and, for each flex
    id in `damping`, its Rayleigh damping from (damping ratio, first
    mode), `cablecheck.build.cablephysics.rayleigh_damping`: the integrator's own
    damping depends on the step)."""
    m.opt.timestep = step
    for f, (zeta, omega) in (damping or {}).items():
        m.flex_damping[f] = rayleigh_damping(zeta, omega, step)
    m.flex_solref[:, 0] = contact_time_constant(step)
    m.geom_solref[_friction_geoms(m), 0] = contact_time_constant(step)
    flex_eq = m.eq_type == int(mujoco.mjtEq.mjEQ_FLEX)
    m.eq_solref[flex_eq, 0] = edge_time_constant(step)
    rolls = [i for i in range(m.neq) if (mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_EQUALITY, i) or "").startswith(
        CABLE_PREFIX)]     # the clamped clips' (`_add_clip_rolls`)
    m.eq_solref[rolls, 0] = edge_time_constant(step)
