"""Build MuJoCo models from a validated scene.

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

The simulation step is chosen from the cables' stiffness and the script's
speeds (`choose_substeps`), and parts too fast for it are warned about
(`tunnel_warnings`); docs/physics.md explains the model and its numbers.

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
from sim.route import initial_shape, polyline_length, run_elements
from sim.scene import Anchor, CableDef, Hold, Scene, SceneError, euler_matrix

CABLE_PREFIX = "cables/"
"""Prefix of every element the cables add to the model (bodies, flexes)."""

CLAMP_EDGE = 0.05
"""Length of the held edge a clamp puts at its end or clip, as a fraction of
the cable's element length (see `_clamp_edges`): short enough that the rigid
piece it adds changes a cantilever's deflection by about 4 x 0.05 / N."""

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
      hold: clamp (two vertices of one short edge are held, see
        `_clamp_edges`) or pin (one vertex). Free anchors hold nothing and
        have no attachment.
    """

    kind: str
    body: str
    vertex: int
    s: float
    hold: Hold = Hold.CLAMP


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
      element_length: rest length of a regular element, metres (a clamp's
        held edge is shorter, see `_clamp_edges`; `np.diff(rest_s)` has all).
      routed: (count, 3) routed shape at t = 0 (before settling), scene world, metres.
      attachments: vertices held by bodies.
      min_bend_radius: metres or None.
      rest_s: (count,) arc length of each vertex along the rest shape, metres.
      elements: the regular elements (count - 1 less one short held edge per clamp).
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
    elements: int = 0


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
        set every step), not mocap bodies: cable vertices ride the bodies
        that hold them, and MuJoCo does not take flex vertices with elastic
        damping on mocap bodies (XMLreference, flex elasticity).
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
    warnings: tuple = ()
    """Physics warnings found before running (`tunnel_warnings`, capped substeps)."""
    substeps: "Substeps | None" = None
    """Simulation steps per scene step and why (`choose_substeps`); the
    simulation model's timestep is the scene's divided by `substeps.count`."""


@dataclass(frozen=True)
class Substeps:
    """How finely the simulation steps within one scene step.

    Attributes:
      count: simulation steps per scene timestep (>= 1).
      step: the simulation step, seconds.
      needed: the step each cable needs, seconds, by cable name.
      reasons: per cable, what sets its step ("bending" or "speed"), its
        fastest held point's speed (m/s) and its regular element length (m).
      capped: the count needed exceeds `MAX_SUBSTEPS` and was capped.
    """

    count: int
    step: float
    needed: dict
    reasons: dict
    capped: bool


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
    opt.viscosity = 0.0  # no medium: cables are damped by their own material (`rayleigh_damping`)
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


@dataclass(frozen=True)
class _Held:
    """One held vertex: which end or clip, the body, the vertex, the hold kind."""

    kind: str      # "start", "end" or "clip"
    body: str
    vertex: int
    hold: Hold


@dataclass
class _CablePlan:
    cable: CableDef
    routed: np.ndarray    # (n, 3) routed shape at t = 0, model coordinates
    straight: np.ndarray  # (n, 3) rest shape: straight along the first element
    held: list[_Held]     # held vertices, by vertex


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

    def __init__(self, scene: Scene, origin: np.ndarray, poses=None):
        self.poses = scene.start_frames if poses is None else poses
        self.origin = origin

    def at_qpos0(self, scene: Scene, plans: list["_CablePlan"]) -> "_Frames":
        """The same frames where the compiled model has its bodies at qpos0:
        `[[bodies]]` at their `[[bodies]]` pose (their first key may differ),
        the mjcf model's bodies at its qpos0 (its first motion sample may
        differ). Where a cable's rest shape is placed (`_compile`'s `rest`)."""
        poses = dict(self.poses)
        for b in scene.bodies:
            poses[b.name] = (np.asarray(b.pos, float), euler_matrix(b.euler))
        held = {h.body for plan in plans for h in plan.held}
        if scene.mjcf is not None and held & self._mjcf_names(scene):
            model = mujoco.MjModel.from_xml_path(str(scene.mjcf))
            data = mujoco.MjData(model)
            mujoco.mj_kinematics(model, data)
            for i in range(1, model.nbody):
                name = model.body(i).name
                if name in poses:
                    poses[name] = (data.xpos[i].copy(), data.xmat[i].reshape(3, 3).copy())
        return _Frames(scene, self.origin, poses)

    @staticmethod
    def _mjcf_names(scene: Scene) -> set:
        return set(scene.start_frames) - {"world"} - {b.name for b in scene.bodies}

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
    cuts = [int(np.argmin(np.linalg.norm(route - c[2], axis=1))) for c in clips]
    clip_vertices = np.concatenate([[0], np.cumsum(counts)])[cuts]
    anchors = ([(0, "start", cable.start)] + [(int(v), "clip", c[3]) for c, v in zip(clips, clip_vertices)]
               + [(int(counts.sum()), "end", cable.end)])
    droop = length
    for _ in range(2):
        # A clip's held edge along the corner's bisector leaves the route by a
        # little; with slack the second pass droops that much less, so the
        # cable keeps its length (to second order in the clamp edge).
        drooped = initial_shape(route, droop, counts, depth=measure)
        shortest = float(np.linalg.norm(np.diff(drooped, axis=0), axis=1).min())
        routed, held = _clamp_edges(drooped, anchors, CLAMP_EDGE * shortest)
        excess = polyline_length(routed) - length
        if not slack or abs(excess) <= 1e-12 * length or droop - excess < total:
            break
        droop -= excess
    seg = np.linalg.norm(np.diff(routed, axis=0), axis=1)
    tangent = (routed[1] - routed[0]) / seg[0]
    s = np.concatenate([[0.0], np.cumsum(seg)])
    straight = routed[0] + s[:, None] * tangent[None, :]
    return _CablePlan(cable, routed, straight, held)


def _clamp_edges(routed: np.ndarray, anchors: list[tuple[int, str, Anchor]],
                 edge: float) -> tuple[np.ndarray, list[_Held]]:
    """Insert a short held edge at every clamp; list the held vertices.

    A clamp holds position and tangent. In MuJoCo's discrete elastic rod
    the bending energy of a vertex stands for the rod within half an element
    either side, so holding a whole element (its two vertices) leaves the
    first half element rigid and clamps the rod half an element too far in:
    measured, a cantilever deflected 1.6 / N too little with N elements.
    Instead a clamp holds an edge of length `edge` (CLAMP_EDGE of an
    element) along the route's tangent at the held point, inside the cable:
    the next vertex's bending then stands for the rod from the clamp on.
    At the end the edge leads into the end point, at a clip it leaves the
    clip point along the bisector of the route's corner there (so a route
    turning at a clip bends by half the turn on either side of the clamp,
    not all of it on one). A pin holds the one vertex, a free anchor
    nothing."""
    points = [p for p in routed]
    held: list[_Held] = []
    shift = 0
    for vertex, kind, anchor in anchors:
        v = vertex + shift
        if anchor.hold == Hold.FREE:
            continue
        if anchor.hold == Hold.PIN:
            held.append(_Held(kind, anchor.body, v, anchor.hold))
            continue
        if kind == "end":
            t = points[v] - points[v - 1]
            points.insert(v, points[v] - edge * t / np.linalg.norm(t))
            held += [_Held(kind, anchor.body, v, anchor.hold), _Held(kind, anchor.body, v + 1, anchor.hold)]
        else:
            out = points[v + 1] - points[v]
            t = out / np.linalg.norm(out)
            if kind == "clip":  # along the route's bisector, so the route's corner splits both sides
                into = points[v] - points[v - 1]
                bisector = t + into / np.linalg.norm(into)
                if np.linalg.norm(bisector) > 1e-9 and np.dot(bisector, out) > edge * np.linalg.norm(bisector):
                    t = bisector / np.linalg.norm(bisector)
            points.insert(v + 1, points[v] + edge * t)
            held += [_Held(kind, anchor.body, v, anchor.hold), _Held(kind, anchor.body, v + 1, anchor.hold)]
        shift += 1
    return np.array(points), held


def _cables_xml(plans: list[_CablePlan], scene: Scene, bits: ContactBits, detect: bool, margin: float) -> str:
    contype, conaff = _cable_bits(scene, bits, detect)
    selfcollide = "auto" if (detect or "self" in scene.effects.contact) else "none"
    contact_solref = contact_time_constant(scene.timestep)
    parts = []
    for plan in plans:
        c = plan.cable
        n = len(plan.straight)
        length = float(np.linalg.norm(np.diff(plan.straight, axis=0), axis=1).sum())
        mass = c.density * np.pi * c.radius ** 2 * length
        pins = sorted({h.vertex for h in plan.held})
        pin = f'<pin id="{" ".join(map(str, pins))}"/>' if pins else ""
        elements = " ".join(f"{i} {i + 1}" for i in range(n - 1))
        # inertiabox: the vertex bodies only slide, so their rotational
        # inertia never acts; the cable's radius keeps it well scaled.
        parts.append(f"""
  <flexcomp name="{c.name}" type="direct" dim="1" radius="{c.radius!r}" mass="{mass!r}"
            inertiabox="{2.0 * c.radius!r}" point="{_fmt(plan.straight)}" element="{elements}">
    {pin}
    <edge equality="true" solref="{edge_time_constant(scene.timestep)!r} 1" solimp="{_edge_solimp(plan)}"/>
    <elasticity young="{c.young!r}" damping="{rayleigh_damping(c, length)!r}"{_shear(c)}/>
    <contact selfcollide="{selfcollide}" contype="{contype}" conaffinity="{conaff}"
             margin="{margin!r}" condim="3" solref="{contact_solref!r} 1"
             solimp="{_fmt(CONTACT_SOLIMP)}" priority="1"/>
  </flexcomp>""")
    return "<mujoco><worldbody>" + "".join(parts) + "\n</worldbody></mujoco>"


def _shear(cable: CableDef) -> str:
    """The rod's torsional (shear) modulus attribute: `twist_stiffness`, else
    MuJoCo's default E / (2 (1 + poisson)) = E / 2 (docs/twist.md)."""
    return "" if cable.twist_stiffness is None else f' shear="{cable.twist_stiffness!r}"'


FIRST_BENDING_MODE = 4.7300407448627040
"""beta_1 L of a beam's first bending mode with both ends clamped (or both
free): cos(bL) cosh(bL) = 1, omega_1 = (beta_1 L)^2 sqrt(EI / (mu L^4))."""


def first_bending_frequency(cable: CableDef, length: float) -> float:
    """omega_1 of the cable as a beam of its length clamped at both ends, rad/s.

    EI / mu = E (pi r^4 / 4) / (rho pi r^2) = E r^2 / (4 rho)."""
    return float(FIRST_BENDING_MODE ** 2 / length ** 2 * np.sqrt(cable.young * cable.radius ** 2 / (4.0 * cable.density)))


def rayleigh_damping(cable: CableDef, length: float) -> float:
    """MuJoCo's flex elasticity `damping` (Rayleigh, stiffness-proportional), seconds.

    MuJoCo damps a rod with the force -beta K v, K its bending (and
    torsion) stiffness; a mode of frequency omega then has the damping ratio
    zeta = beta omega / 2. The cable's `damping` is zeta at its first
    bending mode (`first_bending_frequency`), so beta = 2 zeta / omega_1;
    higher bending modes are damped in proportion to their frequency, and
    what gravity or tension alone restores (a hanging chain's swing) is not
    damped at all: there is no air drag."""
    return float(2.0 * cable.damping / first_bending_frequency(cable, length))


CONTACT_SOLIMP = (0.99, 0.999, 0.001, 0.5, 2.0)
"""solimp of the cables' contacts: d from 0.99 at first touch to 0.999 at a
penetration of 1 mm. MuJoCo's default (0.9 to 0.95) lets 5 to 10 % of the
approach speed through each step."""


def contact_time_constant(step: float) -> float:
    """solref time constant of the cables' contacts for simulation step `step`, seconds.

    Two steps: with b = 2 / tc a contact removes the approach speed within
    one step, so a part moving at v into a cable penetrates it by about
    v h before pushing it along. The cables' contacts take priority over
    the parts' (`priority`), whose MuJoCo default (0.02 s) would otherwise
    be averaged in: with 4 ms averaged with it, a 10 mm plate lifted at
    2 m/s into a sagging cable went through it."""
    return 2.0 * step


EDGE_IMPEDANCE = 0.9999
"""solimp d of the edge-length equality at small strain: MuJoCo's largest
(`mjMAXIMP`). A soft constraint's regularisation is (1 - d) / d of the
constraint's inertia, so the edge's axial stiffness is the edge mass times
d / ((1 - d) tc^2): ten times stiffer than with 0.999."""


def edge_time_constant(step: float) -> float:
    """solref time constant of the edge-length equality for simulation step `step`, seconds.

    Two steps, the stiffest that MuJoCo's discrete-time constraint resolves
    stably (its default safety clamp). With d = `EDGE_IMPEDANCE` the
    damping b = 2 / tc removes a velocity error along an edge within one
    step. It must follow the step: a floor of 2 ms (the former setting) kept
    the edges as soft at a 0.25 ms step as at 1 ms, and a cable whose end
    moves 0.12 m at 20 Hz stretched 2.4 % instead of 0.5 %."""
    return 2.0 * step


EDGE_YIELD = 0.995
"""solimp d of the edge-length equality beyond 4 % edge strain (see
`_edge_solimp`). Measured with ends pulled 10 % past a 1 m cable's length:
yielding to 0.95 (500 times softer than `EDGE_IMPEDANCE`) gathered the
whole stretch in one edge (198 %); 0.995 spreads it (edges below 60 %) and
the cable still comes to rest."""


def _edge_solimp(plan: _CablePlan) -> str:
    """Impedance of the edge-length equality: stiff at small strain, yielding beyond a few %.

    d sets the length accuracy (see `EDGE_IMPEDANCE`). But the tension of a
    taut edge acts on the transverse (string) motion explicitly, which goes
    unstable once strain * d / (1 - d) exceeds a constant: with a stiff
    edge at every strain, a cable whose ends are pulled 10 % past its length
    vibrated chaotically (edges at 50 % strain, never settling;
    tests/test_stability.py). So d falls to `EDGE_YIELD` between 0 and 4 %
    edge strain (power 6: flat near 0, still 0.9998 at 1 %), bounding the tension
    of an overstretched cable: it then rests at the strain its ends force,
    reported as taut. Strains that loads and motion cause are kept far below
    the yield by the step (`choose_substeps`), not by the yield. MuJoCo's
    width is a length, hence per cable (the regular element's length)."""
    seg = np.linalg.norm(np.diff(plan.straight, axis=0), axis=1)
    return f"{EDGE_IMPEDANCE!r} {EDGE_YIELD!r} {0.04 * float(seg.max())!r} 0.5 6"


def build(scene: Scene, detect: bool = True) -> Built:
    """Compile the simulation model (and, if `detect`, the detection model),
    then choose its step (`choose_substeps`)."""
    origin = scene_origin(scene)
    frames = _Frames(scene, origin)
    meshes = _part_meshes(scene)
    obstacles = None
    if "cable-structure" in scene.effects.contact and any(_has_slack(c) for c in scene.cables):
        obstacles = _Obstacles(scene, frames, meshes)
    plans = [_plan_cable(c, frames, f"cables[{i}]", scene, obstacles) for i, c in enumerate(scene.cables)]
    sim, own_bits = _compile(scene, plans, meshes, detect=False, frames=frames, rest=True)
    _move_held(sim, plans, frames)
    det = _compile(scene, plans, meshes, detect=True, frames=frames)[0] if detect else None
    if det is not None and (det.nq != sim.nq or det.ngeom != sim.ngeom):
        raise RuntimeError("detection and simulation models differ in structure")
    built = _finish(scene, sim, det, plans, origin, own_bits)
    poses = _script_poses(built) if scene.effects.dynamics else None
    built.substeps = choose_substeps(built, poses)
    _set_step(sim, built.substeps.step)
    built.warnings = tuple(tunnel_warnings(built, poses))
    if built.substeps.capped:
        need = min(built.substeps.needed.values())
        built.warnings += (f"the cables need a simulation step of {need:.3g} s (see docs/physics.md) but "
                           f"at most {MAX_SUBSTEPS} steps are taken per scene timestep; scene.timestep "
                           f"<= {need * MAX_SUBSTEPS:.3g} s would do",)
    return built


MAX_SUBSTEPS = 64
"""Most simulation steps per scene step `choose_substeps` takes; beyond it
the run warns (the scene's timestep should be smaller)."""

SPEED_FRACTION = 0.05
"""Largest fraction of a cable's element that its fastest held point may
travel in one simulation step (see `choose_substeps`)."""

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


def _script_poses(built: Built) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Every body's pose along the script: times (T,), xpos (T, nbody, 3),
    xmat (T, nbody, 3, 3), model coordinates.

    Samples the script `SPEED_SAMPLES` times over the duration and at every
    key through forward kinematics, so bodies, their rotations and mjcf
    joints all count. Empty when nothing moves."""
    from sim.motion import Motion  # motion builds on this module's Built

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
    times, xpos, xmat = poses if poses is not None else _script_poses(built)
    m = built.model
    out = {}
    for c in built.cables:
        verts = np.array([a.vertex + c.vert_adr for a in c.attachments], int)
        out[c.name] = _max_speed(times, xpos, xmat, m.flex_vertbodyid[verts], m.flex_vert[verts])
    return out


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

    A contact pushes only once a cable overlaps a part and removes the
    approach speed within one step (`contact_time_constant`), so a part
    moving at v overlaps a cable by up to v h before carrying it; once
    v h exceeds the cable's radius plus half the part's thickness the
    cable's centreline can be past the part's middle and is pushed out the
    far side. Checked for every moving part against every cable when
    cable-structure contact pushes back; the warning names the speed, the
    thickness and the timestep that would do (scene units)."""
    scene, m = built.scene, built.model
    if not scene.effects.dynamics or "cable-structure" not in scene.effects.contact or not built.cables:
        return []
    times, xpos, xmat = poses if poses is not None else _script_poses(built)
    if len(times) < 2:
        return []
    h = built.model.opt.timestep
    thinnest = min(c.radius for c in built.cables)
    unit = scene.units
    out = []
    for part in built.parts:
        half = _part_extent(m, part)
        if part.keepout or half is None:
            continue
        corners = np.array(np.meshgrid([-1, 1], [-1, 1], [-1, 1])).reshape(3, -1).T * half
        rot = np.zeros(9)
        mujoco.mju_quat2Mat(rot, m.geom_quat[part.geom_id])
        local = m.geom_pos[part.geom_id] + corners @ rot.reshape(3, 3).T
        body = np.full(len(local), int(m.geom_bodyid[part.geom_id]))
        v = _max_speed(times, xpos, xmat, body, local)
        reach = thinnest + float(half.min())
        if v * h > reach:
            need = reach / v
            out.append(f"part {part.name!r} moves at up to {v / scene.scale:.4g} {unit}/s: a simulation "
                       f"step of {h:.3g} s carries it {v * h / scene.scale:.4g} {unit}, more than the "
                       f"thinnest cable's radius plus half its thickness ({thinnest / scene.scale:.4g} + "
                       f"{half.min() / scene.scale:.4g} {unit}), so a cable can pass through it; "
                       f"scene.timestep <= {need:.3g} s would do")
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
    The scene's timestep is divided by the smallest whole number that meets
    every cable's need, at most `MAX_SUBSTEPS`."""
    scene = built.scene
    dt = scene.timestep
    needed, reasons = {}, {}
    speeds = held_speeds(built, poses) if scene.effects.dynamics else {}
    defs = {c.name: c for c in scene.cables}
    for c in built.cables:
        bend = bending_step(c, defs[c.name])
        v = speeds.get(c.name, 0.0)
        speed = SPEED_FRACTION * c.element_length / v if v > 0.0 else np.inf
        needed[c.name] = float(min(bend, speed))
        reasons[c.name] = ("bending" if bend <= speed else "speed", v, c.element_length)
    h = min(needed.values(), default=dt)
    count = max(1, int(np.ceil(dt / h * (1.0 - 1e-9)))) if scene.effects.dynamics else 1
    capped = count > MAX_SUBSTEPS
    count = min(count, MAX_SUBSTEPS)
    return Substeps(count, dt / count, needed, reasons, capped)


def _set_step(m: mujoco.MjModel, step: float) -> None:
    """Set the simulation step and what is tied to it (the time constants
    of the edge equalities and of the cables' contacts)."""
    m.opt.timestep = step
    m.flex_solref[:, 0] = contact_time_constant(step)
    flex_eq = m.eq_type == int(mujoco.mjtEq.mjEQ_FLEX)
    m.eq_solref[flex_eq, 0] = edge_time_constant(step)


def _move_held(m: mujoco.MjModel, plans: list[_CablePlan], frames: _Frames) -> None:
    """Move the held vertices of a model compiled with `rest` to their routed
    places on their bodies (`flex_vert`: vertex positions in body frames)."""
    for plan in plans:
        fid = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_FLEX, f"{CABLE_PREFIX}{plan.cable.name}")
        adr = int(m.flex_vertadr[fid])
        for h in plan.held:
            m.flex_vert[adr + h.vertex] = frames.to_local(h.body, plan.routed[h.vertex])


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
             detect: bool, frames: _Frames, rest: bool = False) -> tuple[mujoco.MjModel, np.ndarray]:
    """The model, and (ngeom, 2) contype, conaffinity of each geom of the mjcf
    model as written (0, 0 for the geoms the scene adds).

    `rest`: the held vertices sit on the cables' straight rest shape. MuJoCo
    takes a rod's rest curvature from its shape at qpos0, where the free
    vertices lie on the straight rest shape but held vertices would be
    where their bodies hold them on the route: each vertex next to a held
    one would keep a kink as rest curvature. `build` compiles the
    simulation model with `rest` and then moves the held vertices to their
    routed places (`_move_held`: `flex_vert` only), so every cable is
    straight at rest."""
    origin = frames.origin
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
        placed = frames.at_qpos0(scene, plans) if rest else frames
        for plan in plans:
            _hold_vertices(spec, plan, placed, rest)
    try:
        model = spec.compile()
    except Exception as e:  # MuJoCo's compiler raises ValueError with its message
        raise SceneError(scene.path, "(model)", f"MuJoCo cannot compile the scene: {e}") from None
    own_bits = np.zeros((model.ngeom, 2), np.int64)
    for g, contype, conaff in own:
        own_bits[g.id] = contype, conaff
    return model, own_bits


def _hold_vertices(spec: mujoco.MjSpec, plan: _CablePlan, frames: _Frames, rest: bool) -> None:
    """Put each held vertex on the body that holds it; give free vertices their mass.

    A held vertex is a vertex of its body (MuJoCo's flex takes vertices on
    articulated bodies), at its routed position in that body's frame: it
    moves exactly with the body, with no constraint between them to lag or
    stretch, and the body takes the cable's reaction. The flexcomp pins the
    held points (so it omits the twist joint of a clamped end edge); they are
    moved here from the flexcomp's frame to their bodies.

    `rest`: place the held vertices on the straight rest shape instead (see
    `_compile`: the model whose rest curvature is copied).

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
        b = spec.body(f"{CABLE_PREFIX}{c.name}_{v}")
        b.mass = per_length * share[v]
        b.inertia = [b.mass * (2.0 * c.radius) ** 2 / 6.0] * 3


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
        attachments = [Attachment(h.kind, h.body, h.vertex, float(s[h.vertex]), h.hold) for h in plan.held]
        cables.append(CableModel(c.name, c.radius, fid, int(m.flex_vertadr[fid]), n, float(s[-1]),
                                 float(seg.max()), plan.routed + origin,
                                 tuple(sorted(attachments, key=lambda a: a.vertex)), c.min_bend_radius, s,
                                 n - 1 - sum(h.hold == Hold.CLAMP for h in plan.held) // 2))

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
