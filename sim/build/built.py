"""What building a scene yields: the models and what the run needs to know of each cable and part.

`Built` holds the compiled simulation model (and the detection model when
asked), the cables as built (`CableModel`: flex addresses, rest arc
lengths, held vertices as `Attachment`), the parts (`PartModel`: one geom
each, scene parts and the mjcf model's colliding geoms), the visual geoms,
the joints the script drives (`JointDrive`), the chosen simulation step
(`Substeps`) and the physics warnings found before running. Everything
read back out of a model is in the scene's world (`Built.origin` added).

This module holds the records only: it does not build (see `cablecheck.build.stages`),
write or read a MuJoCo model.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import NamedTuple

import mujoco
import numpy as np

from cablecheck.scene.format import Hold
from cablecheck.scene.records import Scene

CABLE_PREFIX = "cables/"
"""Prefix of every element the cables add to the model (bodies, flexes)."""


@dataclass(frozen=True)
class Attachment:
    """A cable vertex held by a body.

    Attributes:
      kind: "start", "end" or "clip".
      body: the scene's body name ("world", a [[bodies]] or mjcf body).
      vertex: index of the held vertex along the cable (0 = start).
      s: arc length of that vertex along the cable at rest, metres.
      hold: clamp (two vertices of one short edge are held, see
        `clamp_edges`) or pin (one vertex). Free anchors hold nothing and
        have no attachment.
      window: the attachment window's name in reports: "start", "end" or
        "clip N" (the cable's Nth clip as the scene lists them, from 1).
      parts: the parts (names or assembly paths) the scene says it is
        fastened to (`part`), or () for the parts it lies against.
    """

    kind: str
    body: str
    vertex: int
    s: float
    hold: Hold = Hold.CLAMP
    window: str = ""
    parts: tuple[str, ...] = ()


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
        held edge is shorter, see `clamp_edges`; `np.diff(rest_s)` has all).
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


def vertex_body(cable: str, vertex: int) -> str:
    """The name of the body of a cable's free vertex (flexcomp's `<name>_<i>`,
    under `CABLE_PREFIX`); a held vertex is one of its holder's instead."""
    return f"{CABLE_PREFIX}{cable}_{vertex}"


def end_roll_body(cable: str) -> str:
    """The name of the body (and of its hinge) that holds a cable's clamped end
    (`cablecheck.build.mjspec`)."""
    return f"{CABLE_PREFIX}{cable}/end_roll"


@dataclass(frozen=True)
class EndRoll:
    """The hinge of a cable's clamped end (`cablecheck.build.mjspec.end_roll_body`)
    and the angle the run holds it at, radians (`cablecheck.build.untwist`)."""

    cable: str
    qpos_adr: int
    dof_adr: int
    angle: float = 0.0


@dataclass(frozen=True, eq=False)
class ClipRoll:
    """A clamped clip's hold on the rod's roll (`cablecheck.run.cliphold`):
    the equality on the twist joint of the clip's held edge, the body
    holding it, where MuJoCo keeps that edge's reference frame, and the
    vector fixed in the body that the edge's material frame follows (its
    frame at t = 0, as the cable starts untwisted, `cablecheck.build.untwist`).

    Attributes:
      cable, window: the cable and the clip ("clip N").
      equality: the equality's id (`cablecheck.build.mjspec.clip_roll_name`).
      qpos_adr: the edge's twist joint's.
      body: the holding body's id.
      frame: plastic address of the edge's reference frame (tangent, then vector).
      local: (3,) the vector in the body's frame.
    """

    cable: str
    window: str
    equality: int
    qpos_adr: int
    body: int
    frame: int
    local: np.ndarray


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


class Named(NamedTuple):
    """A body or joint of a `BodyTree`, as `MjModel.body(i)` / `.joint(j)` give it."""

    id: int
    name: str


@dataclass(frozen=True, eq=False)
class BodyTree:
    """The bodies of a scene built without MuJoCo (`cablecheck.build.static`): the
    world, then each `[[bodies]]` body on its free joint, and the body of
    every part, numbered as MuJoCo would number them.

    The arrays are named as `mujoco.MjModel`'s and hold the same numbers, so
    what reads a built scene's tree (the pair filters and attachment windows
    of `cablecheck.run.stepcheck`, rigid groups in `cablecheck.build.checkview`, the recorder, the
    joint log, the script) reads either. Nothing else of a model is here.

    Attributes:
      body_names: per body, its name ("world" first).
      body_parentid, body_weldid, body_jntnum: (nbody,) int.
      jnt_bodyid: (njnt,) int; joint_names: per joint, its name.
      geom_bodyid: (ngeom,) int, the body of each part (by `PartModel.geom_id`).
      qpos0: the bodies' free joints at their `[[bodies]]` pose.
    """

    body_names: tuple[str, ...]
    body_parentid: np.ndarray
    body_weldid: np.ndarray
    body_jntnum: np.ndarray
    jnt_bodyid: np.ndarray
    joint_names: tuple[str, ...]
    geom_bodyid: np.ndarray
    qpos0: np.ndarray

    @property
    def nbody(self) -> int:
        return len(self.body_names)

    @property
    def njnt(self) -> int:
        return len(self.joint_names)

    @property
    def ngeom(self) -> int:
        return len(self.geom_bodyid)

    def body(self, i: int) -> Named:
        return Named(i, self.body_names[i])

    def joint(self, j: int) -> Named:
        return Named(j, self.joint_names[j])


@dataclass(frozen=True, eq=False)
class Built:
    """Everything the run loop needs about the compiled models.

    Attributes:
      scene: the scene.
      model: simulation model; for a scene built without MuJoCo
        (`cablecheck.build.static`), its bodies' tree (`BodyTree`).
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
    model: mujoco.MjModel | BodyTree
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
    model_skip: np.ndarray = field(default_factory=lambda: np.zeros((0, 0), bool))
    """(P, P) bool over `parts`: pairs the mjcf model tells MuJoCo never to
    collide (its own contact bits, `<contact><exclude>`; see `cablecheck.build.modelread`)."""
    warnings: tuple = ()
    """Physics warnings found before running (`tunnel_warnings`, capped substeps)."""
    substeps: "Substeps | None" = None
    """Simulation steps per scene step and why (`choose_substeps`); the
    simulation model's timestep is the scene's divided by `substeps.count`."""
    rods: tuple = ()
    """Per cable, where its twist is in the simulation's state
    (`cablecheck.build.rodtwist.RodTwist`, or None); empty for a scene not
    simulated."""
    end_rolls: tuple[EndRoll, ...] = ()
    """The clamped ends' hinges and the angles that start their cables
    untwisted; the run holds them there (`cablecheck.run.motion`)."""
    clip_rolls: tuple[ClipRoll, ...] = ()
    """The clamped clips' holds on their cables' roll (`cablecheck.run.cliphold`)."""


def mesh_parts(built: Built) -> np.ndarray:
    """Indices into `built.parts` of the mesh parts (MuJoCo collides each as
    its convex hull; the detection model may see its surface)."""
    return np.flatnonzero([p.shape == "mesh" for p in built.parts]).astype(np.int64)


@dataclass(frozen=True)
class Substeps:
    """How finely the simulation steps within one scene step.

    Attributes:
      count: simulation steps per scene timestep (>= 1).
      step: the simulation step, seconds.
      needed: the step each cable needs, seconds, by cable name.
      reasons: per cable, what sets its step ("bending", "speed", "contact",
        "damping" or "compression"), its fastest held point's speed (for "contact" the
        fastest part's, m/s; for "damping" its first bending mode, rad/s)
        and its regular element length (m).
      capped: the count needed exceeds `MAX_SUBSTEPS` and was capped.
    """

    count: int
    step: float
    needed: dict
    reasons: dict
    capped: bool
