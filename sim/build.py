"""Build MuJoCo models from a validated scene.

Why MjSpec: a scene may start from a user's own MJCF (a robot arm, a
fixture) whose relative mesh paths, defaults and names must survive intact.
`MjSpec.from_file` loads it exactly as MuJoCo would; scene bodies, parts and
meshes are then added through the spec API, and the cables, which only the
`flexcomp` macro can generate (twist bodies, pinning, the edge equality), are
written as one small MJCF string and attached into the spec. Sites and
`connect` equalities that tie cable vertices to moving bodies are added last,
once the vertex bodies exist.

Scripted `[[bodies]]` are free bodies whose pose and velocity the script
sets every step (see `Built.free`); the base model's joints are driven the
same way. Both get a large armature so the cable's reaction barely moves
them within a step.

Two models come out of one scene:
- the simulation model, in which only the interactions listed in
  `effects.contact` collide (contype/conaffinity bits, below), with small
  margins, so nothing the scene did not ask for pushes back;
- the detection model, with the same bodies and degrees of freedom (so the
  simulation's qpos can be copied into it) but every interaction enabled and
  margins set from the clearance. It is never stepped: `mj_kinematics` +
  `mj_collision` on the simulated positions give MuJoCo's own view of every
  pair the checker may report, exact (a large contact `gap` in the simulation
  model would make MuJoCo's general convex collider inexact, see SPEC).

An mjcf model is taken as it comes. Its geoms that MuJoCo never collides
(`contype` and `conaffinity` both 0 as written: visual meshes) stay so in both
models; they are `Built.visuals`, drawn in the recording and never checker
parts. Its other geoms are parts whose own bits say which of them meet each
other; the scene's interactions use three bits the model leaves unused
(`ContactBits`), added to the model geoms' conaffinity only, so they never
make two model geoms meet:
- detection model: the model geoms keep their own bits plus the cable and
  part bits (scene parts carry the part bit as contype), so MuJoCo reports
  cable contacts with every part, scene part against model geom, and model
  geom against model geom exactly where the model itself would collide;
  the checker leaves out the same model-geom pairs (their own bits never
  meet, or their bodies form a `<contact><exclude>` pair: `Built.model_skip`);
- simulation model, cable-structure: the model geoms' conaffinity is the
  cable bit, so cables push on every link;
- simulation model, part-part: the model geoms keep their own bits (a
  robot's self-collision as its author set it) plus the part bit, so they
  also meet the scene's parts. Without part-part their contype is 0: the
  base model is driven kinematically, and contacts among its own geoms (a
  housing resting on its column) could only fight the script.

Cables are 1D flexcomp rods built straight (their rest shape, since a rod
keeps as rest curvature whatever bend its qpos0 has) along the tangent of
the route's first element and then put into the routed shape through qpos,
so bending energy is stored where a real cable would have it. The routed
shape (`sim.route`) has every route point as a vertex and droops clear of
the parts the cable collides with, placed at t = 0 (`_Obstacles`).

This module does not step, move or read the simulation; see `loop`.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import mujoco
import numpy as np

from checker.shapes import Shape, ShapeType, least_signed_distance, mesh_shape
from sim.meshfile import mesh_nodes
from sim.route import initial_shape, run_elements
from sim.scene import CableDef, Scene, SceneError, euler_matrix

CABLE_PREFIX = "cables/"
"""Prefix of every element the cables add to the model (bodies, flexes)."""

DRAG_RATE = 5.0
"""Velocity damping rate of cable vertices, 1/s (time constant 0.2 s).

A numerical drag, not air: it settles the cable and keeps it quasi-static
while its ends move, as a harness behaves at the speeds mechanisms move.
MuJoCo forbids joint damping on flex vertex bodies, so the drag comes from the
medium viscosity (`VISCOSITY`) acting on each vertex's inertia box, whose side
is chosen per cable to give this rate (MuJoCo: f = -6 pi mu r_eq v with r_eq
half the box side)."""

VISCOSITY = 1.0
"""Medium viscosity in the simulation model, Pa s (see `DRAG_RATE`)."""

BASE_ARMATURE = 100.0
"""Armature added to the base model's joints, which are driven kinematically:
the cable's reaction barely moves them within the one step before the script
sets them again."""

PLANE_GRID = 0.1
"""Grid spacing MuJoCo draws on a plane part given no size, metres."""

SIM_MARGIN_FRACTION = 0.25
"""Contact margin in the simulation model, as a fraction of the thinnest cable radius."""


@dataclass(frozen=True)
class ContactBits:
    """The scene's contype/conaffinity bits (a pair collides when
    (type1 & aff2) | (type2 & aff1)): three bits no geom of the base model
    uses, so the model's own bits keep their meaning beside them.

    Attributes:
      cable: cable contype; conaffinity of parts when cable-structure is on.
      cable_cable: cable conaffinity and contype when cable-cable is on.
      part: scene parts' contype; conaffinity of all parts when part-part is on.
    """

    cable: int
    cable_cable: int
    part: int

    @classmethod
    def free_of(cls, used: int) -> "ContactBits":
        """The three lowest bits not set in `used` (the model's bits, or'ed)."""
        free = [1 << k for k in range(32) if not used & (1 << k)]
        if len(free) < 3:
            raise ValueError("the mjcf model uses 30 or more of MuJoCo's 32 contact bits; "
                             "three free ones are needed for the cables and the scene's parts")
        return cls(*free[:3])


@dataclass(frozen=True)
class Attachment:
    """A cable vertex held by a body.

    Attributes:
      kind: "start", "end" or "clip".
      body: the scene's body name ("world", a [[bodies]] or mjcf body).
      vertex: index of the held vertex along the cable (0 = start).
      s: arc length of that vertex along the cable at rest, metres.
    """

    kind: str
    body: str
    vertex: int
    s: float


@dataclass(frozen=True, eq=False)
class CableModel:
    """A cable as built.

    Attributes:
      name: the scene's cable name.
      radius: metres.
      flex_id: index of its flex in the model.
      vert_adr: first index of its vertices in `mjData.flexvert_xpos`.
      count: number of vertices (elements + 1).
      length: rest length, metres.
      element_length: rest length of one element, metres.
      routed: (count, 3) routed shape at t = 0 (before settling), scene world, metres.
      attachments: vertices held by bodies.
      min_bend_radius: metres or None.
      rest_s: (count,) arc length of each vertex along the rest shape, metres.
    """

    name: str
    radius: float
    flex_id: int
    vert_adr: int
    count: int
    length: float
    element_length: float
    routed: np.ndarray
    attachments: tuple[Attachment, ...]
    min_bend_radius: float | None
    rest_s: np.ndarray


@dataclass(frozen=True, eq=False)
class PartModel:
    """A structure part as built: one MuJoCo geom.

    Attributes:
      name: scene part name, or for a geom of the mjcf model
        `<body>/<geom name>`, else `<body>/<mesh name>`, else
        `<body>/<type><k>` (k: the geom's index among its body's colliding
        geoms, or among its visual geoms for a visual one).
      geom_id: the geom's id (same in both models).
      body: scene body name the part rides on.
      shape: "box", "sphere", "cylinder", "capsule", "ellipsoid", "plane" or "mesh".
      size: MuJoCo size (half-extents, radius, half-length), metres.
      vertices: (V, 3) mesh vertices in the geom frame (MuJoCo recentres
        meshes; these are MuJoCo's own, stored as float32: about 1e-7
        relative to the mesh's size), or None.
      faces: (F, 3) mesh faces, or None.
      keepout: a clearance zone, never colliding.
    """

    name: str
    geom_id: int
    body: str
    shape: str
    size: np.ndarray
    vertices: np.ndarray | None
    faces: np.ndarray | None
    keepout: bool


@dataclass(frozen=True)
class JointDrive:
    """A base-model joint held or driven kinematically.

    Attributes:
      name: joint name.
      type: mjtJoint value.
      qpos_adr, dof_adr: addresses in qpos and qvel.
      scale: multiplies keyframe values into MuJoCo units (radians for a
        hinge, metres for a slide).
    """

    name: str
    type: int
    qpos_adr: int
    dof_adr: int
    scale: float


@dataclass(eq=False)
class Built:
    """Everything the run loop needs about the compiled models.

    Attributes:
      scene: the scene.
      model: simulation model.
      detect: detection model (same dofs), or None when not requested.
      cables, parts: in scene order (parts: scene parts, then mjcf geoms).
      free: scene body name -> (qpos address, dof address) of its free joint.
        Scripted bodies are free bodies driven kinematically (qpos and qvel
        set every step), not mocap bodies: MuJoCo gives mocap bodies no
        velocity, so a cable end held to one lags behind it by its speed
        times the constraint's time constant (measured: 1 mm at 0.1 m/s).
      body_ids: scene body name -> body id ("world" is 0).
      base_qpos_adr, base_dof_adr: qpos / dof addresses of the base model's
        joints (all driven kinematically).
      joints: joint name -> JointDrive for the base model's hinge and slide joints.
      qpos0: qpos of the routed state at t = 0.
    """

    scene: Scene
    model: mujoco.MjModel
    detect: mujoco.MjModel | None
    cables: list[CableModel]
    parts: list[PartModel]
    free: dict[str, tuple[int, int]]
    body_ids: dict[str, int]
    base_qpos_adr: np.ndarray
    base_dof_adr: np.ndarray
    joints: dict[str, JointDrive]
    qpos0: np.ndarray
    origin: np.ndarray = field(default_factory=lambda: np.zeros(3))
    """Scene-world position of the model's origin (see `scene_origin`):
    model coordinates + origin = scene world coordinates."""
    visuals: list[PartModel] = field(default_factory=list)
    """Geoms of the mjcf model MuJoCo never collides (contype = conaffinity = 0
    as written): drawn in the recording, never checked."""
    model_skip: np.ndarray = field(default_factory=lambda: np.zeros((0, 0), bool))
    """(P, P) bool over `parts`: pairs the mjcf model tells MuJoCo never to
    collide (its own contact bits, `<contact><exclude>`), see `_model_skip`."""


def default_segments(length: float, radius: float) -> int:
    """Elements for a cable: about 25 mm each, at least 4 radii, 8 to 80 elements.

    Elements longer than 2 r keep MuJoCo's self-collision from touching
    elements two apart along a straight cable (SPEC); 80 bounds the cost of
    long cables (the flex costs about 0.2 ms per step at 40 points)."""
    target = max(0.025, 4.0 * radius)
    return int(np.clip(round(length / target), 8, 80))


def _quat(euler_deg) -> np.ndarray:
    q = np.zeros(4)
    mujoco.mju_mat2Quat(q, euler_matrix(euler_deg).ravel())
    return q


def _base_spec(scene: Scene) -> mujoco.MjSpec:
    if scene.mjcf is None:
        return mujoco.MjSpec()
    try:
        return mujoco.MjSpec.from_file(str(scene.mjcf))
    except Exception as e:  # MuJoCo raises ValueError with its parser message
        raise SceneError(scene.path, "scene.mjcf", f"MuJoCo cannot load {scene.mjcf}: {e}") from None


def _set_options(spec: mujoco.MjSpec, scene: Scene) -> None:
    opt = spec.option
    opt.timestep = scene.timestep
    opt.integrator = mujoco.mjtIntegrator.mjINT_DISCRETE  # rod elasticity needs it (SPEC)
    opt.solver = mujoco.mjtSolver.mjSOL_NEWTON
    opt.tolerance = 1e-8
    opt.iterations = max(opt.iterations, 100)
    opt.gravity = [0.0, 0.0, -9.81] if scene.effects.gravity else [0.0, 0.0, 0.0]
    opt.viscosity = VISCOSITY
    opt.density = 0.0
    # Unused features stay off: no actuators are driven, no sensors are read.
    opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_ACTUATION)
    opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_SENSOR)
    spec.compiler.autolimits = True


def _part_bits(scene: Scene, bits: ContactBits, detect: bool, keepout: bool) -> tuple[int, int]:
    """contype, conaffinity of a scene part."""
    contact = scene.effects.contact
    if detect:
        return bits.part, bits.cable | bits.part
    if keepout:
        return 0, 0
    contype = bits.part if "part-part" in contact else 0
    conaff = (bits.cable if "cable-structure" in contact else 0) | contype
    return contype, conaff


def _model_bits(scene: Scene, bits: ContactBits, detect: bool, own: tuple[int, int]) -> tuple[int, int]:
    """contype, conaffinity of a colliding geom of the mjcf model (see the
    module docstring): the scene's bits go into conaffinity only, so the
    model's geoms meet each other only as their own bits say; in the
    simulation model those own bits act only when part-part is asked."""
    contact = scene.effects.contact
    if detect:
        return own[0], own[1] | bits.cable | bits.part
    cable = bits.cable if "cable-structure" in contact else 0
    if "part-part" not in contact:
        return 0, cable
    return own[0], own[1] | cable | bits.part


def _cable_bits(scene: Scene, bits: ContactBits, detect: bool) -> tuple[int, int]:
    if detect or "cable-cable" in scene.effects.contact:
        return bits.cable | bits.cable_cable, bits.cable_cable
    return bits.cable, 0


def _fmt(values) -> str:
    return " ".join(repr(float(v)) for v in np.ravel(values))


@dataclass
class _CablePlan:
    cable: CableDef
    routed: np.ndarray    # (n, 3) routed shape at t = 0
    straight: np.ndarray  # (n, 3) rest shape: straight along the first element
    holds: list[tuple[str, str, int, np.ndarray]]  # (kind, body, vertex, local pos on body)
    pinned_to_world: bool


def scene_origin(scene: Scene) -> np.ndarray:
    """Where the model's origin sits in the scene's world, metres.

    MuJoCo is given coordinates relative to this point (the mean of the
    cables' routes, else of the parts' and bodies' positions), so a scene
    placed far from its world origin (plant coordinates, CAD assemblies at
    1e4 mm) simulates with the same rounding as one near it: measured on a
    cable following a moving body 2.2e4 m out, the unshifted model settled
    2.6 mm away from the same scene at the origin, the shifted one 1e-12 m.
    Everything read back out is shifted back."""
    points = [np.asarray(c.route, float) for c in scene.cables if c.route is not None]
    if not points:
        points = [np.asarray([p.pos for p in scene.parts if p.body == "world"], float).reshape(-1, 3),
                  np.asarray([b.pos for b in scene.bodies], float).reshape(-1, 3)]
    stacked = np.concatenate(points) if points else np.zeros((0, 3))
    return stacked.mean(axis=0) if len(stacked) else np.zeros(3)


class _Frames:
    """Pose of every body at t = 0 (`Scene.start_frames`), in model coordinates
    (the scene's world less `origin`)."""

    def __init__(self, scene: Scene, origin: np.ndarray):
        self.poses = scene.start_frames
        self.origin = origin

    def to_world(self, body: str, pos) -> np.ndarray:
        p, r = self.poses[body]
        return np.asarray(p, float) - self.origin + np.asarray(r, float) @ np.asarray(pos, float)

    def to_local(self, body: str, point) -> np.ndarray:
        """A model-coordinate point in the frame of `body` as built in the model."""
        if body == "world":  # the model's world frame is the model origin itself
            return np.asarray(point, float)
        p, r = self.poses[body]
        return np.asarray(r, float).T @ (np.asarray(point, float) + self.origin - np.asarray(p, float))


class _Obstacles:
    """The parts a scene's cables collide with, placed at t = 0 in model
    coordinates: what an initial shape must not droop into (`sim.route`).

    Scene parts that are not keep-outs, and the base mjcf model's colliding
    geoms (compiled once more on their own for their local poses and sizes)
    on the bodies whose t = 0 frames the scene knows. Only built when some
    cable has slack and `cable-structure` contact is on."""

    def __init__(self, scene: Scene, frames: _Frames, meshes: dict):
        shapes, rot, pos = [], [], []

        def place(body: str, local_pos, local_rot) -> None:
            p, r = frames.poses[body]
            r = np.asarray(r, float)
            rot.append(r @ local_rot)
            pos.append(np.asarray(p, float) - frames.origin + r @ np.asarray(local_pos, float))

        for part in scene.parts:
            if part.keepout:
                continue
            if part.shape == "mesh":
                shapes.append(mesh_shape(*meshes[part.name]))
            else:
                shapes.append(Shape(ShapeType(part.shape), np.asarray(part.size, float) if part.size else np.zeros(3)))
            place(part.body, part.pos, euler_matrix(part.euler))
        if scene.mjcf is not None:
            m = _base_spec(scene).compile()
            for g in range(m.ngeom):
                gtype = int(m.geom_type[g])
                body = m.body(int(m.geom_bodyid[g])).name or "world"
                if gtype not in _SHAPES or body not in frames.poses:
                    continue
                if m.geom_contype[g] == 0 and m.geom_conaffinity[g] == 0:
                    continue    # visual geoms never collide
                if gtype == int(mujoco.mjtGeom.mjGEOM_MESH):
                    mid = int(m.geom_dataid[g])
                    va, vn = int(m.mesh_vertadr[mid]), int(m.mesh_vertnum[mid])
                    fa, fn = int(m.mesh_faceadr[mid]), int(m.mesh_facenum[mid])
                    shapes.append(mesh_shape(m.mesh_vert[va:va + vn].astype(float),
                                             m.mesh_face[fa:fa + fn].astype(int)))
                else:
                    shapes.append(Shape(ShapeType(_SHAPES[gtype]), m.geom_size[g].copy()))
                local = np.zeros(9)
                mujoco.mju_quat2Mat(local, m.geom_quat[g])
                place(body, m.geom_pos[g], local.reshape(3, 3))
        self.shapes = shapes
        self.rot = np.asarray(rot, float).reshape(-1, 3, 3)
        self.pos = np.asarray(pos, float).reshape(-1, 3)
        # world boxes (a plane's is infinite): only parts whose box comes
        # near the queried points are measured
        self.lo = np.full((len(shapes), 3), -np.inf)
        self.hi = np.full((len(shapes), 3), np.inf)
        for k, sh in enumerate(shapes):
            if sh.type is not ShapeType.PLANE:
                lo, hi = sh.local_bounds()
                corners = np.array(np.meshgrid(*zip(lo, hi), indexing="ij")).reshape(3, -1).T
                world = corners @ self.rot[k].T + self.pos[k]
                self.lo[k], self.hi[k] = world.min(axis=0), world.max(axis=0)

    def measure(self, radius: float):
        """depth(points) for a cable of `radius`: radius less the signed
        distance (-inf where no part's box comes within the radius)."""
        def depth(points: np.ndarray) -> np.ndarray:
            lo, hi = points.min(axis=0) - radius, points.max(axis=0) + radius
            near = np.flatnonzero(np.all((self.lo <= hi) & (self.hi >= lo), axis=1))
            shapes = [self.shapes[k] for k in near]
            return radius - least_signed_distance(shapes, self.rot[near], self.pos[near], points)
        return depth


def _closest_arc(route: np.ndarray, point: np.ndarray) -> tuple[int, float]:
    """(segment index, arc length) of the point of `route` closest to `point`."""
    a, b = route[:-1], route[1:]
    ab = b - a
    denom = np.maximum(np.einsum("ij,ij->i", ab, ab), 1e-300)
    t = np.clip(np.einsum("ij,ij->i", point - a, ab) / denom, 0.0, 1.0)
    dist = np.linalg.norm(a + t[:, None] * ab - point, axis=1)
    k = int(np.argmin(dist))
    seglen = np.sqrt(denom)
    return k, float(seglen[:k].sum() + t[k] * seglen[k])


def _plan_cable(cable: CableDef, frames: _Frames, where: str, scene: Scene,
                depth: "_Obstacles | None" = None) -> _CablePlan:
    """Routed shape through start, via or points, clips and end, with the cable's length.

    Every waypoint (start, each via or given point, each clip, end) is a
    vertex (`sim.route`): each clip is inserted where the route passes
    closest to it, the elements are shared among the straight runs between
    waypoints in proportion to their lengths (`segments`, or the default
    element count raised to one element per run; with slack and no run of
    two elements, two per run), and the runs droop to make up the length,
    away from the parts the cable collides with when `depth` is given."""
    route = np.asarray(cable.route if cable.route is not None else cable.points, float) - frames.origin
    route[0] = frames.to_world(cable.start.body, cable.start.pos)
    route[-1] = frames.to_world(cable.end.body, cable.end.pos)
    clips = []
    for clip in cable.clips:
        point = frames.to_world(clip.body, clip.pos)
        k, s = _closest_arc(route, point)
        clips.append((s, k, point, clip))
    clips.sort(key=lambda c: c[0])
    # Insert clip points (from the last, so earlier segment indices stay valid).
    for s, k, point, clip in sorted(clips, key=lambda c: (c[1], c[0]), reverse=True):
        route = np.insert(route, k + 1, point, axis=0)
    keep = np.concatenate([[True], np.linalg.norm(np.diff(route, axis=0), axis=1) > 0])
    route = route[keep]
    runs = np.linalg.norm(np.diff(route, axis=0), axis=1)
    total = float(runs.sum())
    length = max(cable.length if cable.length is not None else total, total)
    slack = length > total * (1.0 + 1e-9)
    if cable.segments is not None:
        if cable.segments < len(runs) + (1 if slack else 0):
            need = len(runs) + (1 if slack else 0)
            raise SceneError(scene.path, f"{where}.segments",
                             f"{cable.segments} elements cannot pass through all {len(runs) + 1} "
                             f"route points and clips{' and droop to the length' if slack else ''}; "
                             f"give at least {need}")
        counts = run_elements(runs, cable.segments)
    else:
        counts = run_elements(runs, max(default_segments(length, cable.radius), len(runs)))
        if slack and counts.max() < 2:
            counts = np.full(len(runs), 2)
    measure = None if (depth is None or not slack) else depth.measure(cable.radius)
    routed = initial_shape(route, length, counts, depth=measure)
    cuts = [int(np.argmin(np.linalg.norm(route - c[2], axis=1))) for c in clips]
    clip_vertices = np.concatenate([[0], np.cumsum(counts)])[cuts]
    seg = np.linalg.norm(np.diff(routed, axis=0), axis=1)
    tangent = (routed[1] - routed[0]) / seg[0]
    s = np.concatenate([[0.0], np.cumsum(seg)])
    straight = routed[0] + s[:, None] * tangent[None, :]
    n = len(routed)
    pinned = cable.start.body == "world"
    holds = []
    if not pinned:
        holds += [("start", cable.start.body, 0), ("start", cable.start.body, 1)]
    holds += [("end", cable.end.body, n - 2), ("end", cable.end.body, n - 1)]
    holds += [("clip", c[3].body, int(v)) for c, v in zip(clips, clip_vertices)]
    holds = [(kind, body, v, frames.to_local(body, routed[v])) for kind, body, v in holds]
    return _CablePlan(cable, routed, straight, holds, pinned)


def _cables_xml(plans: list[_CablePlan], scene: Scene, bits: ContactBits, detect: bool, margin: float) -> str:
    contype, conaff = _cable_bits(scene, bits, detect)
    selfcollide = "auto" if (detect or "self" in scene.effects.contact) else "none"
    contact_solref = max(0.004, 2.0 * scene.timestep)
    parts = []
    for plan in plans:
        c = plan.cable
        n = len(plan.straight)
        mass = c.density * np.pi * c.radius ** 2 * float(np.linalg.norm(np.diff(plan.straight, axis=0), axis=1).sum())
        vertex_mass = mass / n
        inertiabox = DRAG_RATE * vertex_mass / (3.0 * np.pi * VISCOSITY)
        pin = '<pin id="0 1"/>' if plan.pinned_to_world else ""
        elements = " ".join(f"{i} {i + 1}" for i in range(n - 1))
        parts.append(f"""
  <flexcomp name="{c.name}" type="direct" dim="1" radius="{c.radius!r}" mass="{mass!r}"
            inertiabox="{inertiabox!r}" point="{_fmt(plan.straight)}" element="{elements}">
    {pin}
    <edge equality="true" solref="{_edge_solref(scene)} 1" solimp="{_edge_solimp(plan)}"/>
    <elasticity young="{c.young!r}"{_shear(c)}/>
    <contact selfcollide="{selfcollide}" contype="{contype}" conaffinity="{conaff}"
             margin="{margin!r}" condim="3" solref="{contact_solref!r} 1"/>
  </flexcomp>""")
    return "<mujoco><worldbody>" + "".join(parts) + "\n</worldbody></mujoco>"


def _shear(cable: CableDef) -> str:
    """The rod's torsional (shear) modulus attribute: `twist_stiffness`, else
    MuJoCo's default E / (2 (1 + poisson)) = E / 2 (docs/twist.md)."""
    return "" if cable.twist_stiffness is None else f' shear="{cable.twist_stiffness!r}"'


def _edge_solref(scene: Scene) -> float:
    """Time constant of the edge-length equality, seconds.

    MuJoCo's default (0.02 s) lets a 1 m cable hanging under gravity stretch by
    over 1 %; measured with 40 elements: 0.004 s with solimp 0.99-0.999 keeps
    it within 0.1 %, 0.002 s within 0.03 % (see `_edge_solimp`). Two
    timesteps is the stiffest the discrete-time constraint resolves stably."""
    return max(2.0 * scene.timestep, 0.002)


def _edge_solimp(plan: _CablePlan) -> str:
    """Impedance of the edge-length equality: stiff at small strain, yielding beyond a few %.

    A soft equality holds a static edge at strain ~ (1 - d) / d times the
    edge's unconstrained acceleration (its tension over its mass) over k, so
    d sets the length accuracy: d = 0.999 keeps a 1 m, 80-element cable
    hanging as a catenary within 0.04 % (0.42 % with the former d = 0.99).
    But the tension of a taut edge acts on the transverse (string) motion
    explicitly, which goes unstable once strain * d / (1 - d) exceeds a
    constant, independent of the timestep: with d = 0.999 at every strain, a
    cable whose ends are pulled 10 % past its length vibrated chaotically
    (edges at 50 % strain, cable kinetic energy 0.7 J on 75 g, never settling;
    tests/test_stability.py). So d falls from 0.999 to 0.95 between 0 and
    4 % edge strain (power 6: flat near 0), bounding the tension of an
    overstretched cable: it then rests at the strain its ends force, reported
    as taut. MuJoCo's width is a length, hence per cable.

    Limits (measured, tests/test_stability.py): past the yield the tension
    falls as the strain grows, so the stretch of an overstretched cable
    gathers in the edges next to its held ends (ends 10 % past the length:
    11 edges at 41 %, the rest at 0.8 %); the cable's total strain, which is
    what is reported, is right, its distribution is not. And a rod whose
    bending load compresses its edges past the yield collapses further: a
    200 GPa, 3 mm steel rod bowed between ends 0.5 m apart with 0.6 m of
    length shortens by 9-27 % (4-6 % with d = 0.99-0.999); such a rod needs
    a smaller timestep."""
    seg = np.linalg.norm(np.diff(plan.straight, axis=0), axis=1)
    return f"0.999 0.95 {0.04 * float(seg.mean())!r} 0.5 6"


def build(scene: Scene, detect: bool = True) -> Built:
    """Compile the simulation model (and, if `detect`, the detection model)."""
    origin = scene_origin(scene)
    frames = _Frames(scene, origin)
    meshes = _part_meshes(scene)
    obstacles = None
    if "cable-structure" in scene.effects.contact and any(_has_slack(c) for c in scene.cables):
        obstacles = _Obstacles(scene, frames, meshes)
    plans = [_plan_cable(c, frames, f"cables[{i}]", scene, obstacles) for i, c in enumerate(scene.cables)]
    sim, own_bits = _compile(scene, plans, meshes, detect=False, origin=origin)
    det = _compile(scene, plans, meshes, detect=True, origin=origin)[0] if detect else None
    if det is not None and (det.nq != sim.nq or det.ngeom != sim.ngeom):
        raise RuntimeError("detection and simulation models differ in structure")
    return _finish(scene, sim, det, plans, origin, own_bits)


def _has_slack(cable: CableDef) -> bool:
    """The cable is longer than its route (clips aside), so its initial shape droops."""
    route = np.asarray(cable.route if cable.route is not None else cable.points, float)
    total = float(np.linalg.norm(np.diff(route, axis=0), axis=1).sum())
    return cable.length is not None and cable.length > total * (1.0 + 1e-9)


def _part_meshes(scene: Scene) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Mesh part name -> (vertices in metres, faces), reading each file once
    (a glTF file holds the meshes of several parts; both models use them)."""
    files: dict = {}
    out = {}
    for part in scene.parts:
        if part.shape != "mesh":
            continue
        if part.file not in files:
            files[part.file] = {m.path: m for m in mesh_nodes(part.file)}
        nodes = files[part.file]
        mesh = nodes[part.node] if part.node is not None else next(iter(nodes.values()))
        out[part.name] = (np.asarray(mesh.vertices, float) * part.mesh_scale, np.asarray(mesh.faces, int))
    return out


def _compile(scene: Scene, plans: list[_CablePlan], meshes: dict[str, tuple[np.ndarray, np.ndarray]],
             detect: bool, origin: np.ndarray) -> tuple[mujoco.MjModel, np.ndarray]:
    """The model, and (ngeom, 2) contype, conaffinity of each geom of the mjcf
    model as written (0, 0 for the geoms the scene adds)."""
    spec = _base_spec(scene)
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
    # bits, and the scene's are added (module docstring). Visual geoms (both 0)
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
        g.contype, g.conaffinity = _model_bits(scene, bits, detect, (int(g.contype), int(g.conaffinity)))
        g.margin = margin

    for body in scene.bodies:
        b = spec.worldbody.add_body(name=body.name, pos=list(np.asarray(body.pos, float) - origin),
                                    quat=list(_quat(body.euler)), gravcomp=1.0)
        b.add_freejoint(name=f"{body.name}/free").armature = BASE_ARMATURE
        # a free body needs mass; parts on it carry none of their own here
        b.explicitinertial = True
        b.mass = 1.0
        b.inertia = [1.0, 1.0, 1.0]
    for part in scene.parts:
        parent = spec.worldbody if part.body == "world" else spec.body(part.body)
        contype, conaff = _part_bits(scene, bits, detect, part.keepout)
        pos = np.asarray(part.pos, float) - (origin if part.body == "world" else 0.0)
        common = dict(name=part.name, pos=list(pos), quat=list(_quat(part.euler)),
                      contype=contype, conaffinity=conaff, margin=margin,
                      rgba=[0.9, 0.5, 0.1, 0.3] if part.keepout else [0.6, 0.6, 0.65, 1.0])
        if part.shape == "mesh":
            verts, faces = meshes[part.name]
            spec.add_mesh(name=f"mesh:{part.name}", uservert=verts.ravel().tolist(),
                          userface=faces.ravel().tolist())
            parent.add_geom(type=mujoco.mjtGeom.mjGEOM_MESH, meshname=f"mesh:{part.name}", **common)
        else:
            size = list(part.size) + [0.0] * (3 - len(part.size))
            if part.shape == "plane":
                # MuJoCo's plane is infinite whatever its size: x, y half-sizes
                # are for drawing (0: infinite), the third, the drawn grid's
                # spacing, must be positive
                size[2] = size[2] or max(size[0], size[1]) / 10.0 or PLANE_GRID
            gtype = getattr(mujoco.mjtGeom, f"mjGEOM_{part.shape.upper()}")
            parent.add_geom(type=gtype, size=size, **common)

    if plans:
        child = mujoco.MjSpec.from_string(_cables_xml(plans, scene, bits, detect, margin))
        spec.worldbody.add_frame().attach_body(child.worldbody, CABLE_PREFIX, "")
        for plan in plans:
            _add_holds(spec, scene, plan)
    try:
        model = spec.compile()
    except Exception as e:  # MuJoCo's compiler raises ValueError with its message
        raise SceneError(scene.path, "(model)", f"MuJoCo cannot compile the scene: {e}") from None
    own_bits = np.zeros((model.ngeom, 2), np.int64)
    for g, contype, conaff in own:
        own_bits[g.id] = contype, conaff
    return model, own_bits


def _add_holds(spec: mujoco.MjSpec, scene: Scene, plan: _CablePlan) -> None:
    """Sites and connect equalities tying held vertices to their bodies.

    Site-to-site connects hold wherever the bodies are at qpos0, which is the
    straight rest shape, not the routed one; a site on the body at the vertex's
    routed position is what the vertex must meet."""
    c = plan.cable
    solref = _edge_solref(scene)
    for k, (kind, body, vertex, local) in enumerate(plan.holds):
        vsite = f"{CABLE_PREFIX}{c.name}/{kind}{k}/vertex"
        bsite = f"{CABLE_PREFIX}{c.name}/{kind}{k}/body"
        spec.body(f"{CABLE_PREFIX}{c.name}_{vertex}").add_site(name=vsite)
        target = spec.worldbody if body == "world" else spec.body(body)
        target.add_site(name=bsite, pos=list(local))
        eq = spec.add_equality(type=mujoco.mjtEq.mjEQ_CONNECT, objtype=mujoco.mjtObj.mjOBJ_SITE,
                               name1=vsite, name2=bsite)
        eq.solref = [solref, 1.0]
        eq.solimp = [0.99, 0.999, 0.001, 0.5, 2.0]


_SHAPES = {int(mujoco.mjtGeom.mjGEOM_PLANE): "plane", int(mujoco.mjtGeom.mjGEOM_SPHERE): "sphere",
           int(mujoco.mjtGeom.mjGEOM_CAPSULE): "capsule", int(mujoco.mjtGeom.mjGEOM_ELLIPSOID): "ellipsoid",
           int(mujoco.mjtGeom.mjGEOM_CYLINDER): "cylinder", int(mujoco.mjtGeom.mjGEOM_BOX): "box",
           int(mujoco.mjtGeom.mjGEOM_MESH): "mesh"}


def _mesh_arrays(m: mujoco.MjModel, g: int) -> tuple[np.ndarray | None, np.ndarray | None]:
    """MuJoCo's own vertices (geom frame) and faces of a mesh geom, else None, None."""
    if int(m.geom_type[g]) != int(mujoco.mjtGeom.mjGEOM_MESH):
        return None, None
    mid = int(m.geom_dataid[g])
    va, vn = int(m.mesh_vertadr[mid]), int(m.mesh_vertnum[mid])
    fa, fn = int(m.mesh_faceadr[mid]), int(m.mesh_facenum[mid])
    return m.mesh_vert[va:va + vn].astype(float).copy(), m.mesh_face[fa:fa + fn].astype(int).copy()


def _body_name(m: mujoco.MjModel, bid: int) -> str:
    return m.body(bid).name or ("world" if bid == 0 else f"body{bid}")


def _geom_names(m: mujoco.MjModel, geoms: list[int]) -> list[str]:
    """Names of one body's geoms (all colliding, or all visual), in model order:
    `<body>/<geom name>`, else `<body>/<mesh name>`, else `<body>/<type><k>`
    with k the geom's index among `geoms`; names that would repeat within the
    body fall back to `<type><k>` for each of them. Counting within the
    colliding geoms only keeps part names when visual geoms come or go."""
    if not geoms:
        return []
    bname = _body_name(m, int(m.geom_bodyid[geoms[0]]))
    own = []
    for g in geoms:
        name = m.geom(g).name
        if not name and int(m.geom_type[g]) == int(mujoco.mjtGeom.mjGEOM_MESH):
            name = m.mesh(int(m.geom_dataid[g])).name
        own.append(name)
    counts: dict[str, int] = {}
    for name in own:
        counts[name] = counts.get(name, 0) + 1
    return [f"{bname}/{name}" if name and counts[name] == 1 else f"{bname}/{_SHAPES[int(m.geom_type[g])]}{k}"
            for k, (g, name) in enumerate(zip(geoms, own))]


def _geom_parts(scene: Scene, m: mujoco.MjModel, own_bits: np.ndarray) -> tuple[list[PartModel], list[PartModel]]:
    """(parts, visuals): the scene's parts and the mjcf model's colliding geoms
    in model order; the mjcf model's visual geoms (contype = conaffinity = 0)."""
    scene_parts = {p.name: p for p in scene.parts}
    named: dict[int, tuple[str, str, bool]] = {}   # geom id -> (name, body, keepout)
    visual: set[int] = set()
    per_body: dict[tuple[int, bool], list[int]] = {}
    for g in range(m.ngeom):
        if int(m.geom_type[g]) not in _SHAPES:
            continue  # heightfields and SDFs are not parts the checker knows
        gname = m.geom(g).name
        if gname in scene_parts:
            sp = scene_parts[gname]
            named[g] = (sp.name, sp.body, sp.keepout)
            continue
        if m.body(int(m.geom_bodyid[g])).name.startswith(CABLE_PREFIX):
            continue
        is_visual = not own_bits[g].any()
        if is_visual:
            visual.add(g)
        per_body.setdefault((int(m.geom_bodyid[g]), is_visual), []).append(g)
    for (bid, _), geoms in per_body.items():
        for g, name in zip(geoms, _geom_names(m, geoms)):
            named[g] = (name, _body_name(m, bid), False)
    parts, visuals, seen = [], [], {}
    for g in sorted(named):
        name, body, keepout = named[g]
        if g not in visual:
            if name in seen:
                raise SceneError(scene.path, "parts", f"two parts are named {name!r} (a scene part and a "
                                                      f"geom of the mjcf model); rename the scene part")
            seen[name] = g
        verts, faces = _mesh_arrays(m, g)
        gtype = int(m.geom_type[g])
        (visuals if g in visual else parts).append(
            PartModel(name, g, body, _SHAPES[gtype], m.geom_size[g].copy(), verts, faces, keepout))
    return parts, visuals


def _model_skip(scene: Scene, m: mujoco.MjModel, parts: list[PartModel], own_bits: np.ndarray) -> np.ndarray:
    """(P, P) bool: part pairs MuJoCo is told never to collide, which the
    checker leaves out too: two geoms of the mjcf model whose own bits never
    meet as written ((type1 & aff2) | (type2 & aff1) == 0), and any two parts
    on a body pair of the model's `<contact><exclude>`. The parent-child and
    same-body filters are `sim.stepcheck.part_pairs_skipped`'s."""
    scene_names = {p.name for p in scene.parts}
    gid = np.array([p.geom_id for p in parts], np.int64)
    base = np.array([p.name not in scene_names for p in parts], bool)
    ct, ca = own_bits[gid, 0], own_bits[gid, 1]
    meet = ((ct[:, None] & ca[None, :]) | (ca[:, None] & ct[None, :])) != 0
    skip = ~meet & base[:, None] & base[None, :]
    if m.nexclude:
        body = m.geom_bodyid[gid].astype(np.int64)
        sig = m.exclude_signature.astype(np.int64)
        pair = np.zeros((m.nbody, m.nbody), bool)
        pair[sig >> 16, sig & 0xFFFF] = True
        pair |= pair.T
        skip |= pair[body[:, None], body[None, :]]
    return skip


def _finish(scene: Scene, m: mujoco.MjModel, det: mujoco.MjModel | None,
            plans: list[_CablePlan], origin: np.ndarray, own_bits: np.ndarray) -> Built:
    parts, visuals = _geom_parts(scene, m, own_bits)
    model_skip = _model_skip(scene, m, parts, own_bits)
    cables = []
    qpos0 = m.qpos0.copy()
    for plan in plans:
        c = plan.cable
        fid = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_FLEX, f"{CABLE_PREFIX}{c.name}")
        n = len(plan.routed)
        for v in range(n):
            try:
                bid = m.body(f"{CABLE_PREFIX}{c.name}_{v}").id
            except KeyError:
                continue  # pinned to the world
            ja = int(m.body_jntadr[bid])
            # The three slides run along the parent's (the world's) x, y, z axes.
            qpos0[m.jnt_qposadr[ja:ja + 3]] += plan.routed[v] - plan.straight[v]
        seg = np.linalg.norm(np.diff(plan.straight, axis=0), axis=1)
        s = np.concatenate([[0.0], np.cumsum(seg)])
        attachments = [Attachment("start", c.start.body, v, float(s[v])) for v in ((0, 1) if plan.pinned_to_world else ())]
        attachments += [Attachment(kind, body, v, float(s[v])) for kind, body, v, _ in plan.holds]
        cables.append(CableModel(c.name, c.radius, fid, int(m.flex_vertadr[fid]), n, float(s[-1]),
                                 float(seg.mean()), plan.routed + origin,
                                 tuple(sorted(attachments, key=lambda a: a.vertex)), c.min_bend_radius, s))

    scene_bodies = {b.name for b in scene.bodies}
    free = {}
    for b in scene_bodies:
        j = int(m.body_jntadr[m.body(b).id])
        free[b] = (int(m.jnt_qposadr[j]), int(m.jnt_dofadr[j]))
    body_ids = {"world": 0}
    for i in range(1, m.nbody):
        name = m.body(i).name
        if name and not name.startswith(CABLE_PREFIX):
            body_ids[name] = i
    base_joints = [j for j in range(m.njnt) if not m.joint(j).name.startswith(CABLE_PREFIX)
                   and not m.body(int(m.jnt_bodyid[j])).name.startswith(CABLE_PREFIX)
                   and m.body(int(m.jnt_bodyid[j])).name not in scene_bodies]
    qadr_list, dadr_list, joints = [], [], {}
    nq_of = {int(mujoco.mjtJoint.mjJNT_FREE): 7, int(mujoco.mjtJoint.mjJNT_BALL): 4}
    nv_of = {int(mujoco.mjtJoint.mjJNT_FREE): 6, int(mujoco.mjtJoint.mjJNT_BALL): 3}
    for j in base_joints:
        jt = int(m.jnt_type[j])
        qa, da = int(m.jnt_qposadr[j]), int(m.jnt_dofadr[j])
        qadr_list += range(qa, qa + nq_of.get(jt, 1))
        dadr_list += range(da, da + nv_of.get(jt, 1))
        name = m.joint(j).name
        if name and jt in (int(mujoco.mjtJoint.mjJNT_HINGE), int(mujoco.mjtJoint.mjJNT_SLIDE)):
            scale = np.pi / 180.0 if jt == int(mujoco.mjtJoint.mjJNT_HINGE) else scene.scale
            joints[name] = JointDrive(name, jt, qa, da, scale)
    return Built(scene, m, det, cables, parts, free, body_ids,
                 np.array(qadr_list, int), np.array(dadr_list, int), joints, qpos0, origin,
                 visuals, model_skip)
