"""The validated scene as frozen records, in SI units (see `cablecheck.scene`).

One record per table of the scene file (`Scene` holds them all), plus the
motion's keys and its sampled `Trajectory`. The records only hold values:
reading and checking the file is the table readers' job (`cablecheck.scene.load`
and its siblings), and building a model from them is `cablecheck.build.stages`'s.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from types import MappingProxyType
from typing import Mapping

import numpy as np

from cablecheck.scene.format import (
    DEFAULT_CLEARANCE,
    DEFAULT_DAMPING,
    DEFAULT_DENSITY,
    DEFAULT_YOUNG,
    INTERPOLATIONS,
    ZERO3,
    Hold,
)


@dataclass(frozen=True)
class Effects:
    """What the simulation includes.

    Attributes:
      dynamics: step the simulation; False checks the cables as routed.
      gravity: apply gravity.
      contact: interactions that push back physically, a subset of
        `INTERACTIONS`; the others are detected and compared, never resolved.
    """

    dynamics: bool = True
    gravity: bool = True
    contact: frozenset[str] = frozenset()


@dataclass(frozen=True)
class CheckSettings:
    """How interference is checked.

    Attributes:
      method: "points" (discrete points) or "exact" (segment distances).
      spacing: discrete-point spacing, a multiple of the cable radius.
      clearance: soft-interference distance, metres.
      every: check every Nth step (>= 1).
      validate: compare with MuJoCo's contacts at each checked step.
      attach_zone: length of cable next to an end or clip, in cable radii,
        where touching the body it rides on is expected. Measured along the
        cable's own material (rest arc length), so a stretched cable keeps
        the same piece of itself excused.
      attach_links: the attachment window also excuses the parts of bodies
        within this many joints of the held body in the mjcf model's
        kinematic tree (1: the links before and after a clamp's link);
        paths never pass through the world body, so a table or fence is
        never a neighbour. 0: the held body's own parts only.
    """

    method: str = "points"
    spacing: float = 2.0
    clearance: float = DEFAULT_CLEARANCE
    every: int = 1
    validate: bool = True
    attach_zone: float = 5.0
    attach_links: int = 0


@dataclass(frozen=True)
class AllowDef:
    """A contact that belongs to the design (`[[allow]]`): never an event.

    Attributes:
      a, b: each a part name, an assembly path prefix ("cell/table" covers
        "cell/table/top"), or a cable name. The pair matches interference
        records (self, cable-cable, cable-structure, keep-out, part-part;
        never bend or taut) between a name under `a` and a name under `b`,
        either way round.
      reason: why the contact is expected (listed in the report).
    """

    a: str
    b: str
    reason: str


@dataclass(frozen=True)
class Limits:
    """Sizes above which a scene is refused as a likely mistake (`[limits]`).

    A radius typed in metres in a mm scene, or a duration of 1e9 s, would
    otherwise start a run that never ends, silently. A scene that really
    needs more raises the limit in its `[limits]` table.

    Attributes:
      steps: simulated steps (settle plus duration, over the timestep).
      elements: MuJoCo elements of one cable (`segments`).
      points: discrete points of all cables in one check (method points:
        each cable's length over its spacing).
    """

    steps: int = 10_000_000
    elements: int = 2_000
    points: int = 2_000_000


@dataclass(frozen=True)
class BodyDef:
    """A rigid body moved by script (`[[bodies]]`).

    Attributes:
      name: unique body name (not "world", not an mjcf body).
      pos: (3,) world position at t = 0, metres.
      euler: (3,) world orientation at t = 0, degrees (intrinsic x, y, z).
    """

    name: str
    pos: tuple[float, float, float] = ZERO3
    euler: tuple[float, float, float] = ZERO3


@dataclass(frozen=True)
class PartDef:
    """A structure part (`[[parts]]`).

    Attributes:
      name: unique name; "/" separates assembly levels.
      body: "world", a `[[bodies]]` name or a body of the mjcf model.
      shape: one of `SHAPE_SIZES`.
      size: MuJoCo size in metres (half-extents, radius, half-length); ()
        for mesh; for plane () or MuJoCo's drawing size (half-sizes x, y
        and optionally the grid spacing; the plane itself is infinite; 0 or
        () draws it sized to the scene).
      pos: (3,) position in the body's frame, metres.
      euler: (3,) orientation in the body's frame, degrees.
      file: absolute mesh path for shape "mesh", else None.
      mesh_scale: multiplies the mesh file's coordinates into metres
        (the scene's `scale` times `Scene.scale`); 1.0 when not a mesh.
      keepout: a clearance zone: detected, never collides.
      node: for a part expanded from a glTF / GLB file, the mesh node's path
        in the file's node tree (the part is named ``<entry name>/<node>``);
        None otherwise.
      friction: sliding friction coefficient of its contacts with cables, or
        None: the cable's alone (`cablecheck.build.mjspec`: where both set one, MuJoCo's
        rule takes the larger).
    """

    name: str
    body: str
    shape: str
    size: tuple[float, ...]
    pos: tuple[float, float, float] = ZERO3
    euler: tuple[float, float, float] = ZERO3
    file: Path | None = None
    mesh_scale: float = 1.0
    keepout: bool = False
    node: str | None = None
    friction: float | None = None


@dataclass(frozen=True)
class Anchor:
    """A point of a cable held by a body (start, end or clip).

    Attributes:
      body: "world", a `[[bodies]]` name or a body of the mjcf model. With
        `hold` FREE nothing holds the point: `pos` is then only read in this
        body's frame at t = 0 to shape the initial route.
      pos: (3,) position in that body's frame, metres.
      hold: clamp (position and tangent), pin (position) or free.
      tangent: (3,) unit vector, the direction a clamp holds the cable in
        at this point (the direction of travel from start to end), in the
        body's frame; None: the route's (`cablecheck.build.cableplan`). Clamps only.
      parts: the parts (names or assembly paths) the scene says the point
        is fastened to (`part`): its attachment window excuses these alone.
        Empty: the parts of its body (and its neighbours, `attach_links`)
        that the held point lies within the cable radius plus the
        clearance of (`cablecheck.run.stepcheck.attachment_exclusions`).
    """

    body: str
    pos: tuple[float, float, float] = ZERO3
    hold: Hold = Hold.CLAMP
    parts: tuple[str, ...] = ()
    tangent: tuple[float, float, float] | None = None


@dataclass(frozen=True, eq=False)
class CableDef:
    """A flexible cable (`[[cables]]`). Compared by identity (it holds arrays).

    Attributes:
      name: unique cable name (not also a part name).
      radius: metres.
      start: first end. With `points` its pos is points[0] in its body frame.
      end: the other end. With `points` its pos is points[-1] in its body frame.
      via: (k, 3) routing waypoints, world metres at t = 0; k may be 0.
      points: (n, 3) routed centreline, world metres at t = 0, n >= 2; or None.
      length: requested length in metres, never shorter than the route; None:
        the route's length.
      clips: anchors holding the cable along its route.
      segments: number of MuJoCo elements, or None for the builder's choice.
      young: bending modulus, Pa.
      density: kg/m^3.
      min_bend_radius: metres, or None for no bend check.
      damping: fraction of critical damping of the first bending mode (>= 0).
      route: (m, 3) world polyline at t = 0, metres: start, via..., end, or
        `points`. Filled by the loader; None only for hand-built records.
      twist_stiffness: shear modulus G of the torsion, Pa, or None for
        MuJoCo's default E / 2 (see docs/twist.md).
      friction: sliding friction coefficient of its contacts, or None: the
        other side's where it sets one, else MuJoCo's default 1.0 (where
        both sides set one, the larger: MuJoCo's rule; `cablecheck.build.mjspec`).
    """

    name: str
    radius: float
    start: Anchor
    end: Anchor
    via: np.ndarray
    points: np.ndarray | None
    length: float | None
    clips: tuple[Anchor, ...]
    segments: int | None
    young: float = DEFAULT_YOUNG
    density: float = DEFAULT_DENSITY
    min_bend_radius: float | None = None
    route: np.ndarray | None = None
    twist_stiffness: float | None = None
    damping: float = DEFAULT_DAMPING
    friction: float | None = None

    @property
    def route_length(self) -> float:
        """Length of the route at t = 0 (`route`, else `points`), metres."""
        line = np.asarray(self.route if self.route is not None else self.points, float)
        return float(np.linalg.norm(np.diff(line, axis=0), axis=1).sum())


@dataclass(frozen=True)
class BodyKey:
    """A keyframe of a script-driven body: its world pose at time t.

    Attributes:
      t: seconds after t = 0.
      pos: (3,) world position, metres (the body's `[[bodies]]` pos if omitted).
      euler: (3,) world orientation, degrees (the body's `[[bodies]]` euler if
        omitted).
    """

    t: float
    pos: tuple[float, float, float]
    euler: tuple[float, float, float]


@dataclass(frozen=True)
class JointKey:
    """A keyframe of an mjcf joint.

    Attributes:
      t: seconds after t = 0.
      value: as written: degrees for hinge joints, scene units for slide
        joints (multiply by `Scene.scale` for metres).
    """

    t: float
    value: float


@dataclass(frozen=True)
class KeyframeKey:
    """A key naming a keyframe of the mjcf model (``{ t = 0.0, key = "home" }``).

    Attributes:
      t: seconds after t = 0 (as written, before `time_scale`).
      key: name of a ``<keyframe><key>`` of the model; its qpos gives the
        joint's value (in a joint's motion) or every hinge and slide joint's
        value (in a motion of keyframes only).
    """

    t: float
    key: str


@dataclass(frozen=True, eq=False)
class Trajectory:
    """A motion's samples in MuJoCo units on scene time. Compared by identity.

    Attributes:
      times: (n,) scene seconds (written times / `time_scale`), strictly increasing.
      joints: names of the mjcf hinge and slide joints it drives.
      joint_values: (n, J) radians (hinge) or metres (slide).
      bodies: names of the `[[bodies]]` it drives.
      body_pos: (n, B, 3) world positions, metres.
      body_euler: (n, B, 3) world orientations, degrees (intrinsic x, y, z),
        as written: consecutive samples may differ by any angle (0 then 270
        is a turn of 270 degrees, not of -90).
      interpolation: "cubic" or "linear" (`cablecheck.run.curves`).
    """

    times: np.ndarray
    joints: tuple[str, ...]
    joint_values: np.ndarray
    bodies: tuple[str, ...]
    body_pos: np.ndarray
    body_euler: np.ndarray
    interpolation: str


@dataclass(frozen=True, eq=False)
class MotionDef:
    """Scripted motion (`[[motion]]`): of one body, one joint, the mjcf
    model's keyframes, or whatever a file's columns name. Compared by identity.

    At most one of `body`, `joint` and `file` is set; none for a motion of
    keyframes only (every key a KeyframeKey).

    Attributes:
      body: a `[[bodies]]` name, or None.
      joint: a hinge or slide joint of the mjcf model, or None.
      keys: as written, with strictly increasing t: BodyKey for a body,
        JointKey or KeyframeKey for a joint, KeyframeKey for keyframes
        only; () for a file.
      file: absolute path of the CSV file of samples, or None.
      angles: "deg" or "rad": unit of hinge values (keys' `value`, file columns).
      interpolation: "cubic" or "linear".
      time_scale: plays the motion this many times faster.
      trajectory: the samples in MuJoCo units on scene time (filled by the
        loader; None only for hand-built records).
    """

    body: str | None
    joint: str | None
    keys: tuple[BodyKey, ...] | tuple[JointKey | KeyframeKey, ...]
    file: Path | None = None
    angles: str = "deg"
    interpolation: str = INTERPOLATIONS[0]
    time_scale: float = 1.0
    trajectory: Trajectory | None = None


@dataclass(frozen=True, eq=False)
class Scene:
    """A validated scene. Compared by identity (its cables hold arrays).

    Attributes:
      path: the scene file as given.
      name: scene name (used for output file names).
      units: "m" or "mm", as written.
      scale: metres per scene unit.
      duration: seconds of scripted motion after t = 0 (0: rest state only).
      timestep: simulation step, seconds.
      settle: seconds simulated with motion frozen before t = 0.
      mjcf: absolute path of the base MuJoCo model, or None.
      effects: what the simulation includes.
      check: how interference is checked.
      bodies, parts, cables, motions: in file order.
      allow: `[[allow]]` pairs in file order.
      start_frames: world frame of every body at t = 0 (see `cablecheck.scene`),
        name -> (origin (3,) metres, rotation (3, 3)), for
        "world", each `[[bodies]]` body and each named mjcf body. Read-only.
      limits: the sizes the scene was checked against.
      warnings: what loading found unusual but runnable (sizes unusual in
        the declared units, `cablecheck.scene.units`), one sentence each.
    """

    path: Path
    name: str
    units: str
    scale: float
    duration: float
    timestep: float
    settle: float
    mjcf: Path | None
    effects: Effects
    check: CheckSettings
    bodies: tuple[BodyDef, ...]
    parts: tuple[PartDef, ...]
    cables: tuple[CableDef, ...]
    motions: tuple[MotionDef, ...]
    allow: tuple[AllowDef, ...] = ()
    start_frames: Mapping[str, tuple[np.ndarray, np.ndarray]] = field(
        default_factory=lambda: MappingProxyType({}))
    limits: Limits = Limits()
    warnings: tuple[str, ...] = ()
