"""Load a cablecheck scene (TOML) into validated, SI-unit records.

`load_scene` reads the file, `parse_scene` checks a dict as `tomllib` returns
it. Every problem is a `SceneError` naming the file, the key path (for example
``cables[1].radius``, 0-based indices) and the problem; nothing else escapes.

Conventions of the records:

- Lengths are in metres (MuJoCo simulates in SI); `Scene.scale` is metres per
  scene unit so that reports can convert back. Angles stay in degrees
  (`euler`, MuJoCo's default intrinsic x-y-z sequence). Young's modulus (Pa),
  density (kg/m^3) and times (s) are unchanged.
- `check.spacing` and `check.attach_zone` are multiples of the cable radius;
  `check.clearance` is in metres.
- Joint keyframe values stay as written (degrees for hinges, scene units for
  slides) in `MotionDef.keys`; every motion's `Trajectory` holds its samples
  in MuJoCo units (radians, metres), on scene time (`time_scale` applied).
- Positions of parts, clips and cable ends are in the frame of the body they
  ride on; `via`, `points` and `CableDef.route` are world coordinates at t = 0.
  "At t = 0" is the pose the motion script gives: a keyframed body at its
  first key's pose (before the first key a body holds it), any other
  `[[bodies]]` body at its `[[bodies]]` pose, and the mjcf model at `qpos0`
  with each driven joint at its first sample's value. `Scene.start_frames`
  holds these frames, so the builder need not work them out again.

The mjcf model is compiled once here (to know its bodies, joints and the
pose of its bodies at qpos0); meshes are loaded with trimesh to check they
exist, load, and (for keepout parts) are closed. The builder loads both again.
A mesh part whose file is glTF / GLB expands into one part per mesh node of
the file, named ``<name>/<node path>`` (`sim.meshfile`).

A `[[motion]]` gives keys, the mjcf model's keyframes (``key = "home"``) or a
CSV file of samples (`read_samples`); every sample of a joint with a range
(`jnt_limited`) must lie in it. Both interpolations (`sim.curves`) stay
between neighbouring samples, so the samples bound the whole motion.

`[[allow]]` names (`AllowDef`) must cover a scene part or cable (by name or
assembly path prefix) or, with an mjcf model, begin with one of its bodies:
its geoms' part names are the builder's, so those are checked against the
built parts once the model exists (`check_allow_names`).
"""

from __future__ import annotations

import csv
import difflib
import io
import math
import re
import tomllib
from dataclasses import dataclass, field, replace
from enum import Enum
from pathlib import Path
from types import MappingProxyType
from typing import Any, Mapping

import mujoco
import numpy as np
import trimesh

from sim.curves import INTERPOLATIONS
from sim.meshfile import MeshFileError, is_tree, mesh_nodes
from sim.route import polyline_length

UNITS = {"m": 1.0, "mm": 0.001}
"""Scene units and their size in metres."""

SHAPE_SIZES = {"box": 3, "sphere": 1, "cylinder": 2, "capsule": 2, "ellipsoid": 3,
               "plane": 0, "mesh": 0}
"""Number of `size` entries per part shape (MuJoCo's convention; 0: no size)."""

INTERACTIONS = ("cable-structure", "cable-cable", "self", "part-part")
"""Names allowed in `effects.contact`."""

METHODS = ("points", "exact")
"""Values allowed in `check.method`."""

DEFAULT_CLEARANCE = 0.005
"""`check.clearance` when absent: 5 mm, in metres, whatever the scene units."""

DEFAULT_YOUNG = 5.0e7
"""Cable bending modulus when absent, Pa.

A PVC-jacketed wire or small harness bends like a rod of effective modulus
10-100 MPa: plasticised PVC is 10-50 MPa, and stranded copper adds little in
bending because its strands slide. Measured harness bending stiffness EI of
about 0.02 N m^2 at 10 mm diameter (I = pi r^4 / 4 = 4.9e-10 m^4) gives
E = 4e7 Pa; we round to 5e7."""

DEFAULT_DENSITY = 1500.0
"""Cable density when absent, kg/m^3: PVC (~1400) with some copper and air."""

DEFAULT_DAMPING = 0.02
"""`damping` when absent: fraction of critical damping of a cable's first
bending mode (see `sim.build.rayleigh_damping` and docs/physics.md). 2 % is
the loss of a polymer-jacketed cable swinging in air; a hanging cable keeps
swinging for many periods."""


class Hold(str, Enum):
    """How an end or clip holds the cable (SPEC, additions)."""

    CLAMP = "clamp"   # position and tangent
    PIN = "pin"       # position only, free to turn
    FREE = "free"     # not held: the position only shapes the initial route

LARGEST = 1e15
"""No number in a scene may exceed this magnitude (keeps squares and sums finite)."""

ROUTE_TOLERANCE = 1e-9
"""Relative tolerance by which `length` may fall short of its route."""

POINTS_LENGTH_TOLERANCE = 1e-6
"""Relative tolerance by which `length` may exceed a `points` route with
dynamics off (the route's length printed to 6 digits is accepted)."""

SELF_CONTACT_ELEMENT = 2.25
"""Shortest element, in cable radii, when self-contact pushes back: MuJoCo's
flex self-collision skips only elements sharing a vertex, so elements two
apart along a straight cable are one element length apart and touch (within
the simulation's contact margin of 0.25 r, `sim.build.SIM_MARGIN_FRACTION`)
unless it exceeds 2 r + 0.25 r. Without self-contact MuJoCo sets no such
limit on the element length."""

DEGENERATE = 1e-6
"""A route segment shorter than this many cable radii has zero length."""

_TOP_KEYS = ("scene", "effects", "check", "bodies", "parts", "cables", "motion", "limits", "allow")
_LIMIT_KEYS = ("steps", "elements", "points")
_SCENE_KEYS = ("name", "units", "duration", "timestep", "settle", "mjcf")
_EFFECTS_KEYS = ("dynamics", "gravity", "contact")
_CHECK_KEYS = ("method", "spacing", "clearance", "every", "validate", "attach_zone", "attach_links")
_ALLOW_KEYS = ("a", "b", "reason")
_BODY_KEYS = ("name", "pos", "euler")
_PART_KEYS = ("name", "body", "shape", "size", "pos", "euler", "file", "scale", "keepout")
_CABLE_KEYS = ("name", "radius", "start", "end", "via", "length", "points", "clips",
               "segments", "young", "density", "min_bend_radius", "twist_stiffness",
               "damping")
_ANCHOR_KEYS = ("body", "pos", "hold")
_MOTION_KEYS = ("body", "joint", "file", "keys", "angles", "interpolation", "time_scale")
_BODY_KEY_KEYS = ("t", "pos", "euler")
_JOINT_KEY_KEYS = ("t", "value", "key")
ANGLES = {"deg": math.pi / 180.0, "rad": 1.0}
"""Values of `[[motion]] angles` and radians per unit."""
BODY_AXES = ("x", "y", "z", "rx", "ry", "rz")
"""Column suffixes of a body in a motion file: position (scene units), euler angles (degrees)."""
_REQUIRED = object()
_ZERO3 = (0.0, 0.0, 0.0)


class SceneError(Exception):
    """A scene file that cannot be used.

    Attributes:
      file: the scene file (as given to `load_scene` / `parse_scene`).
      key: where in the file: a key path such as ``cables[1].radius`` (0-based
        indices), ``line 3, column 5`` for TOML syntax, ``(file)`` for I/O.
      problem: what is wrong, in words.
    """

    def __init__(self, file: Path, key: str, problem: str):
        super().__init__(f"{file}: {key}: {problem}")
        self.file = file
        self.key = key
        self.problem = problem


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
    pos: tuple[float, float, float] = _ZERO3
    euler: tuple[float, float, float] = _ZERO3


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
    """

    name: str
    body: str
    shape: str
    size: tuple[float, ...]
    pos: tuple[float, float, float] = _ZERO3
    euler: tuple[float, float, float] = _ZERO3
    file: Path | None = None
    mesh_scale: float = 1.0
    keepout: bool = False
    node: str | None = None


@dataclass(frozen=True)
class Anchor:
    """A point of a cable held by a body (start, end or clip).

    Attributes:
      body: "world", a `[[bodies]]` name or a body of the mjcf model. With
        `hold` FREE nothing holds the point: `pos` is then only read in this
        body's frame at t = 0 to shape the initial route.
      pos: (3,) position in that body's frame, metres.
      hold: clamp (position and tangent), pin (position) or free.
    """

    body: str
    pos: tuple[float, float, float] = _ZERO3
    hold: Hold = Hold.CLAMP


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
        unwrapped: consecutive samples differ by at most 180 degrees per angle.
      interpolation: "cubic" or "linear" (`sim.curves`).
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
      start_frames: world frame of every body at t = 0 (see the module
        docstring), name -> (origin (3,) metres, rotation (3, 3)), for
        "world", each `[[bodies]]` body and each named mjcf body. Read-only.
      limits: the sizes the scene was checked against.
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


def load_scene(path: str | Path) -> Scene:
    """Read and validate a scene file; raise SceneError (only) when it is bad."""
    path = Path(path)
    try:
        text = path.read_bytes().decode("utf-8")
    except OSError as e:
        raise SceneError(path, "(file)", f"cannot read: {e.strerror or e}") from None
    except UnicodeDecodeError as e:
        raise SceneError(path, "(file)",
                         f"not UTF-8 text (byte {e.start}: {e.reason})") from None
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        message = str(e)
        where = re.search(r"\s*\(at (line \d+, column \d+)\)$", message)
        if where:
            raise SceneError(path, where.group(1),
                             f"invalid TOML: {message[:where.start()]}") from None
        raise SceneError(path, "(syntax)", f"invalid TOML: {message}") from None
    return parse_scene(data, path)


def parse_scene(data: dict, path: Path) -> Scene:
    """Validate a scene given as the dict `tomllib` returns for the file `path`.

    Relative file names (mjcf, meshes) are resolved against `path`'s folder.
    Raises SceneError (only) for the first problem found.
    """
    return _Parser(Path(path)).scene(data)


def euler_matrix(euler_deg) -> np.ndarray:
    """(3, 3) rotation of MuJoCo's default euler sequence (intrinsic x, y, z), degrees."""
    a, b, c = np.radians(np.asarray(euler_deg, float))
    ca, sa, cb, sb, cc, sc = np.cos(a), np.sin(a), np.cos(b), np.sin(b), np.cos(c), np.sin(c)
    rx = np.array([[1, 0, 0], [0, ca, -sa], [0, sa, ca]])
    ry = np.array([[cb, 0, sb], [0, 1, 0], [-sb, 0, cb]])
    rz = np.array([[cc, -sc, 0], [sc, cc, 0], [0, 0, 1]])
    return rx @ ry @ rz


def _describe(value: Any) -> str:
    """A value's TOML type and (short) text, for error messages."""
    kinds = {bool: "a boolean", int: "an integer", float: "a float", str: "a string",
             list: "an array", dict: "a table"}
    kind = next((k for t, k in kinds.items() if type(value) is t), type(value).__name__)
    text = repr(value)
    return f"{kind} ({text if len(text) <= 40 else text[:37] + '...'})"


def _is_number(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


@dataclass(frozen=True)
class _MjcfInfo:
    """What the loader needs of the base mjcf model."""

    model: mujoco.MjModel
    bodies: dict[str, int]   # name -> body id
    joints: dict[str, int]   # name -> joint id
    keyframes: dict[str, int]   # name -> keyframe id


class _Parser:
    """Validates one scene dict; holds the file for error messages."""

    def __init__(self, file: Path):
        self.file = file
        self._meshes: dict[Path, list] = {}
        self.folder = file.parent
        self.scale = 1.0
        self.mjcf: _MjcfInfo | None = None
        # body name -> (origin, rotation) at t = 0; mjcf bodies are None until motions are read
        self.frames: dict[str, tuple[np.ndarray, np.ndarray] | None] = {}
        self.body_index: dict[str, str] = {}   # [[bodies]] name -> its key path
        self.effects_read = Effects()

    # -- generic readers ---------------------------------------------------

    def error(self, key: str, problem: str) -> SceneError:
        return SceneError(self.file, key, problem)

    def table(self, value: Any, where: str, allowed: tuple[str, ...],
              required: tuple[str, ...] = ()) -> dict:
        """Check that `value` is a table with only `allowed` keys and all `required` ones."""
        if not isinstance(value, dict):
            raise self.error(where, f"expected a table, got {_describe(value)}")
        for key in value:
            if key not in allowed:
                close = difflib.get_close_matches(key, allowed, n=1, cutoff=0.6)
                hint = (f"did you mean '{close[0]}'?" if close
                        else "valid keys: " + ", ".join(allowed))
                raise self.error(_join(where, key), f"unknown key ({hint})")
        for key in required:
            if key not in value:
                raise self.error(_join(where, key), "missing (required)")
        return value

    def tables(self, value: Any, where: str) -> list:
        """An array of tables (`[[where]]`)."""
        if not isinstance(value, list) or not all(isinstance(v, dict) for v in value):
            raise self.error(where, f"expected an array of tables ([[{where}]]), "
                                    f"got {_describe(value)}")
        return value

    def number(self, value: Any, where: str, *, positive: bool = False,
               nonnegative: bool = False) -> float:
        if not _is_number(value):
            raise self.error(where, f"expected a number, got {_describe(value)}")
        if isinstance(value, float) and not math.isfinite(value):
            raise self.error(where, f"must be a finite number, got {value}")
        if abs(value) > LARGEST:
            raise self.error(where, f"out of range: magnitude above {LARGEST:g}")
        value = float(value)
        if positive and value <= 0:
            raise self.error(where, f"must be positive, got {_g(value)}")
        if nonnegative and value < 0:
            raise self.error(where, f"must not be negative, got {_g(value)}")
        return value

    def integer(self, value: Any, where: str, minimum: int) -> int:
        if not isinstance(value, int) or isinstance(value, bool):
            raise self.error(where, f"expected an integer, got {_describe(value)}")
        if value < minimum:
            raise self.error(where, f"must be at least {minimum}, got {value}")
        return value

    def boolean(self, value: Any, where: str) -> bool:
        if not isinstance(value, bool):
            raise self.error(where, f"expected true or false, got {_describe(value)}")
        return value

    def string(self, value: Any, where: str, choices: tuple[str, ...] | None = None) -> str:
        if not isinstance(value, str):
            raise self.error(where, f"expected a string, got {_describe(value)}")
        if choices is not None and value not in choices:
            raise self.error(where, f"must be one of {', '.join(map(repr, choices))}, "
                                    f"got {value!r}")
        return value

    def name(self, value: Any, where: str) -> str:
        value = self.string(value, where)
        if not value.strip():
            raise self.error(where, "must not be empty")
        return value

    def vector(self, value: Any, where: str, length: int = 3) -> tuple[float, ...]:
        if not isinstance(value, list):
            raise self.error(where, f"expected an array of {length} numbers, "
                                    f"got {_describe(value)}")
        if len(value) != length:
            raise self.error(where, f"expected {length} numbers, got {len(value)}")
        return tuple(self.number(v, f"{where}[{i}]") for i, v in enumerate(value))

    def length(self, value: Any, where: str, **kw) -> float:
        """A length in scene units, returned in metres."""
        return self.number(value, where, **kw) * self.scale

    def position(self, value: Any, where: str) -> tuple[float, float, float]:
        """A (3,) position in scene units, returned in metres."""
        return tuple(v * self.scale for v in self.vector(value, where))

    def point_list(self, value: Any, where: str) -> np.ndarray:
        """An array of 3-vectors in scene units, returned as a read-only (k, 3) in metres."""
        if not isinstance(value, list):
            raise self.error(where, f"expected an array of [x, y, z] points, "
                                    f"got {_describe(value)}")
        out = np.array([self.vector(v, f"{where}[{i}]") for i, v in enumerate(value)],
                       float).reshape(-1, 3) * self.scale
        out.setflags(write=False)
        return out

    def file_path(self, value: Any, where: str) -> Path:
        """A path relative to the scene file, which must exist as a file."""
        text = self.name(value, where)
        try:
            path = (self.folder / text).resolve()
            found = path.is_file()
        except (OSError, ValueError):      # a NUL byte, a name too long for the file system
            raise self.error(where, f"not a usable file name: {text!r}") from None
        if not found:
            raise self.error(where, f"file not found: {path}")
        return path

    # -- sections ---------------------------------------------------------

    def scene(self, data: dict) -> Scene:
        data = self.table(data, "(top level)", _TOP_KEYS, ("scene",))
        head = self.table(data["scene"], "scene", _SCENE_KEYS, ("name", "units", "duration"))
        name = self.name(head["name"], "scene.name")
        if "/" in name or "\\" in name or name in (".", ".."):
            raise self.error("scene.name", f"is used as a file name; it may not contain "
                                           f"'/' or '\\' or be '.' or '..', got {name!r}")
        units = self.string(head["units"], "scene.units", tuple(UNITS))
        self.scale = UNITS[units]
        duration = self.number(head["duration"], "scene.duration", nonnegative=True)
        timestep = self.number(head.get("timestep", 0.002), "scene.timestep", positive=True)
        settle = self.number(head.get("settle", 0.0), "scene.settle", nonnegative=True)
        mjcf = None
        if "mjcf" in head:
            mjcf = self.file_path(head["mjcf"], "scene.mjcf")
            self.mjcf = self.compile_mjcf(mjcf)
            self.frames.update(dict.fromkeys(self.mjcf.bodies))   # names now, frames below
        self.frames["world"] = _frame(np.zeros(3), np.eye(3))

        effects = self.effects(data.get("effects", {}))
        self.effects_read = effects
        check = self.check(data.get("check", {}))
        bodies = tuple(self.body(b, f"bodies[{i}]")
                       for i, b in enumerate(self.tables(data.get("bodies", []), "bodies")))
        parts = tuple(node for i, p in enumerate(self.tables(data.get("parts", []), "parts"))
                      for node in self.expand_nodes(self.part(p, f"parts[{i}]"), f"parts[{i}]"))
        self.unique(parts, "parts", "part")
        motions = tuple(self.motion(m, f"motion[{i}]", {b.name: b for b in bodies})
                        for i, m in enumerate(self.tables(data.get("motion", []), "motion")))
        driven: dict[str, int] = {}
        for i, m in enumerate(motions):
            traj = m.trajectory
            for target in ([f"body {b!r}" for b in traj.bodies]
                           + [f"joint {j!r}" for j in traj.joints]):
                if target in driven:
                    raise self.error(f"motion[{i}]", f"{target} is already driven by "
                                                     f"motion[{driven[target]}]")
                driven[target] = i
            for k, b in enumerate(traj.bodies):
                self.frames[b] = _frame(traj.body_pos[0, k], euler_matrix(traj.body_euler[0, k]))
        if self.mjcf is not None:
            self.frames.update(self.mjcf_frames(motions))
        cables = tuple(self.cable(c, f"cables[{i}]", effects.dynamics)
                       for i, c in enumerate(self.tables(data.get("cables", []), "cables")))
        self.unique(cables, "cables", "cable")
        part_index = {p.name: i for i, p in enumerate(parts)}
        for i, cable in enumerate(cables):
            if cable.name in part_index:
                raise self.error(f"cables[{i}].name", f"{cable.name!r} is also the name of "
                                 f"parts[{part_index[cable.name]}]; names must differ")
        limits = self.limits(data.get("limits", {}))
        self.within_limits(limits, duration + settle, timestep, check, cables)
        names = [p.name for p in parts] + [c.name for c in cables]
        allow = tuple(self.allow(a, f"allow[{i}]", names)
                      for i, a in enumerate(self.tables(data.get("allow", []), "allow")))
        return Scene(path=self.file, name=name, units=units, scale=self.scale,
                     duration=duration, timestep=timestep, settle=settle, mjcf=mjcf,
                     effects=effects, check=check, bodies=bodies, parts=parts,
                     cables=cables, motions=motions, allow=allow,
                     start_frames=MappingProxyType(dict(self.frames)), limits=limits)

    def limits(self, value: Any) -> Limits:
        t = self.table(value, "limits", _LIMIT_KEYS)
        return Limits(**{k: self.integer(t[k], f"limits.{k}", 1) for k in _LIMIT_KEYS if k in t})

    def within_limits(self, limits: Limits, seconds: float, timestep: float,
                      check: CheckSettings, cables: tuple[CableDef, ...]) -> None:
        """Refuse sizes above `limits`, naming the key, the size and how to raise the limit."""
        steps = seconds / timestep
        if steps > limits.steps:
            raise self.error("scene.duration", f"{_g(seconds)} s (settle and duration) at a timestep "
                             f"of {_g(timestep)} s is {steps:.3g} steps, above the limit of "
                             f"{limits.steps:,} (raise it with [limits] steps = ...)")
        for i, c in enumerate(cables):
            if c.segments is not None and c.segments > limits.elements:
                raise self.error(f"cables[{i}].segments", f"{c.segments:,} elements, above the limit "
                                 f"of {limits.elements:,} per cable (raise it with [limits] "
                                 "elements = ...)")
        if check.method != "points" or not cables:
            return
        lengths = np.array([c.length or polyline_length(c.route) for c in cables])
        radii = np.array([c.radius for c in cables])
        points = lengths / (check.spacing * radii) + 1.0
        if points.sum() > limits.points:
            k = int(np.argmax(points))
            raise self.error(f"cables[{k}].radius", f"the cables need {points.sum():.3g} discrete points "
                             f"per check ({points[k]:.3g} for {cables[k].name!r}: "
                             f"{_g(lengths[k] / self.scale)} {self._units()} at a spacing of "
                             f"{_g(check.spacing)} radii of {_g(radii[k] / self.scale)} {self._units()}), "
                             f"above the limit of {limits.points:,}; check the radius and units "
                             "(raise the limit with [limits] points = ...)")

    def compile_mjcf(self, path: Path) -> _MjcfInfo:
        try:
            model = mujoco.MjModel.from_xml_path(str(path))
        except Exception as e:   # MuJoCo raises ValueError; any failure is the file's
            message = " ".join(str(e).split())
            raise self.error("scene.mjcf", f"MuJoCo cannot compile {path.name}: "
                                           f"{message}") from None
        bodies = {model.body(i).name: i for i in range(model.nbody) if model.body(i).name}
        joints = {model.joint(i).name: i for i in range(model.njnt) if model.joint(i).name}
        keyframes = {model.key(i).name: i for i in range(model.nkey) if model.key(i).name}
        return _MjcfInfo(model=model, bodies=bodies, joints=joints, keyframes=keyframes)

    def mjcf_frames(self, motions: tuple[MotionDef, ...]) -> dict:
        """World frames of the mjcf bodies at t = 0: qpos0, driven joints at their first sample."""
        model = self.mjcf.model
        data = mujoco.MjData(model)
        for m in motions:
            for j, name in enumerate(m.trajectory.joints):
                data.qpos[model.jnt_qposadr[self.mjcf.joints[name]]] = m.trajectory.joint_values[0, j]
        mujoco.mj_kinematics(model, data)
        return {name: _frame(data.xpos[i], data.xmat[i].reshape(3, 3))
                for name, i in self.mjcf.bodies.items()}

    def effects(self, value: Any) -> Effects:
        t = self.table(value, "effects", _EFFECTS_KEYS)
        contact = t.get("contact", [])
        if not isinstance(contact, list):
            raise self.error("effects.contact", f"expected an array of strings, "
                                                f"got {_describe(contact)}")
        names = frozenset(self.string(c, f"effects.contact[{i}]", INTERACTIONS)
                          for i, c in enumerate(contact))
        return Effects(dynamics=self.boolean(t.get("dynamics", True), "effects.dynamics"),
                       gravity=self.boolean(t.get("gravity", True), "effects.gravity"),
                       contact=names)

    def check(self, value: Any) -> CheckSettings:
        t = self.table(value, "check", _CHECK_KEYS)
        clearance = (self.length(t["clearance"], "check.clearance", nonnegative=True)
                     if "clearance" in t else DEFAULT_CLEARANCE)
        return CheckSettings(
            method=self.string(t.get("method", "points"), "check.method", METHODS),
            spacing=self.number(t.get("spacing", 2.0), "check.spacing", positive=True),
            clearance=clearance,
            every=self.integer(t.get("every", 1), "check.every", 1),
            validate=self.boolean(t.get("validate", True), "check.validate"),
            attach_zone=self.number(t.get("attach_zone", 5.0), "check.attach_zone",
                                    nonnegative=True),
            attach_links=self.integer(t.get("attach_links", 0), "check.attach_links", 0))

    def allow(self, value: dict, where: str, names: list[str]) -> AllowDef:
        """An `[[allow]]` pair. Its names must cover a scene part or cable
        (or, with an mjcf model, begin with one of its bodies: the geoms'
        names are the builder's, checked against the built parts by
        :func:`check_allow_names`)."""
        t = self.table(value, where, _ALLOW_KEYS, ("a", "b", "reason"))
        out = []
        for key in ("a", "b"):
            name = self.name(t[key], f"{where}.{key}")
            bodies = (set(self.mjcf.bodies) | {"world"}) if self.mjcf is not None else set()
            if not covers(name, names) and name.split("/")[0] not in bodies:
                raise self.error(f"{where}.{key}", unknown_name(name, names + sorted(bodies)))
            out.append(name)
        reason = self.name(t["reason"], f"{where}.reason")
        return AllowDef(out[0], out[1], reason)

    def body(self, value: dict, where: str) -> BodyDef:
        t = self.table(value, where, _BODY_KEYS, ("name",))
        name = self.name(t["name"], f"{where}.name")
        if name == "world":
            raise self.error(f"{where}.name", "'world' is the fixed world frame; "
                                              "choose another name")
        if name in self.body_index:
            raise self.error(f"{where}.name", f"duplicate body name {name!r} "
                                              f"(also {self.body_index[name]})")
        if name in self.frames:
            raise self.error(f"{where}.name", f"{name!r} is already a body of the mjcf "
                                              "model; choose another name")
        self.body_index[name] = where
        body = BodyDef(name=name, pos=self.position(t.get("pos", [0, 0, 0]), f"{where}.pos"),
                       euler=self.vector(t.get("euler", [0, 0, 0]), f"{where}.euler"))
        self.frames[name] = _frame(body.pos, euler_matrix(body.euler))
        return body

    def body_ref(self, value: Any, where: str) -> str:
        """A body a part or anchor rides on: world, a [[bodies]] body or an mjcf body."""
        name = self.name(value, where)
        if name not in self.frames:
            known = sorted(self.frames)
            close = difflib.get_close_matches(name, known, n=1, cutoff=0.6)
            hint = f"did you mean {close[0]!r}?" if close else "known: " + ", ".join(known)
            raise self.error(where, f"no body named {name!r} in [[bodies]]"
                                    f"{' or the mjcf model' if self.mjcf else ''} ({hint})")
        return name

    def part(self, value: dict, where: str) -> PartDef:
        t = self.table(value, where, _PART_KEYS, ("name", "shape"))
        name = self.name(t["name"], f"{where}.name")
        if any(not level.strip() for level in name.split("/")):
            raise self.error(f"{where}.name", f"empty assembly level in {name!r} "
                                              "('/' separates non-empty levels)")
        shape = self.string(t["shape"], f"{where}.shape", tuple(SHAPE_SIZES))
        arity = SHAPE_SIZES[shape]
        if shape == "plane":
            size = self.plane_size(t.get("size"), f"{where}.size")
        elif arity == 0:
            if "size" in t:
                raise self.error(f"{where}.size", f"not used by shape {shape!r} (see file, scale)")
            size = ()
        else:
            if "size" not in t:
                raise self.error(f"{where}.size", f"missing (required for shape {shape!r})")
            raw = t["size"]
            if isinstance(raw, list) and len(raw) != arity:
                raise self.error(f"{where}.size", f"shape {shape!r} takes {arity} "
                                 f"number{'s' if arity > 1 else ''} ({_SIZE_HELP[shape]}), "
                                 f"got {len(raw)}")
            size = tuple(self.length(v, f"{where}.size[{i}]", positive=True)
                         for i, v in enumerate(self.vector(raw, f"{where}.size", arity)))
        for key in ("file", "scale"):
            if key in t and shape != "mesh":
                raise self.error(f"{where}.{key}", f"only for shape 'mesh', not {shape!r}")
        keepout = self.boolean(t.get("keepout", False), f"{where}.keepout")
        file, mesh_scale = None, 1.0
        if shape == "mesh":
            if "file" not in t:
                raise self.error(f"{where}.file", "missing (required for shape 'mesh')")
            file = self.file_path(t["file"], f"{where}.file")
            mesh_scale = self.number(t.get("scale", 1.0), f"{where}.scale",
                                     positive=True) * self.scale
            self.check_mesh(file, f"{where}.file", closed=keepout)
        return PartDef(name=name, body=self.body_ref(t.get("body", "world"), f"{where}.body"),
                       shape=shape, size=size,
                       pos=self.position(t.get("pos", [0, 0, 0]), f"{where}.pos"),
                       euler=self.vector(t.get("euler", [0, 0, 0]), f"{where}.euler"),
                       file=file, mesh_scale=mesh_scale, keepout=keepout)

    def plane_size(self, value: Any, where: str) -> tuple[float, ...]:
        """A plane's optional drawing size in metres (MuJoCo's: half-sizes x,
        y and optionally the grid spacing); () when absent.

        The plane is the infinite half-space below its local z = 0 for the
        simulation and the checker whatever the size; the size only says how
        much of it a recording draws (0 or absent: sized to the scene)."""
        if value is None:
            return ()
        if not isinstance(value, list) or len(value) not in (2, 3):
            got = f"{len(value)}" if isinstance(value, list) else _describe(value)
            raise self.error(where, "shape 'plane' takes 2 or 3 numbers (drawn half-sizes x, y "
                                    f"and grid spacing; the plane itself is infinite), got {got}")
        size = tuple(self.length(v, f"{where}[{i}]", nonnegative=True)
                     for i, v in enumerate(self.vector(value, where, len(value))))
        if len(size) == 3 and size[2] == 0:
            raise self.error(f"{where}[2]", "the grid spacing must be positive (MuJoCo's rule)")
        return size

    def mesh_nodes(self, path: Path, where: str) -> list:
        """The meshes of a file, read once however many parts use it."""
        if path not in self._meshes:
            try:
                self._meshes[path] = mesh_nodes(path)
            except MeshFileError as e:
                raise self.error(where, str(e)) from None
        return self._meshes[path]

    def check_mesh(self, path: Path, where: str, closed: bool) -> None:
        nodes = self.mesh_nodes(path, where)
        if not closed:
            return
        for node in nodes:
            if not trimesh.Trimesh(node.vertices, node.faces).is_watertight:
                label = f"{path.name}" + (f" node {node.path!r}" if node.path else "")
                raise self.error(where, f"{label} is not a closed surface (keepout zones "
                                        "need an inside); close its holes")

    def expand_nodes(self, part: PartDef, where: str) -> list[PartDef]:
        """A glTF / GLB mesh part becomes one part per mesh node, named
        ``<name>/<node path>``; any other part stays as it is."""
        if part.shape != "mesh" or not is_tree(part.file):
            return [part]
        nodes = self.mesh_nodes(part.file, f"{where}.file")
        return [replace(part, name=f"{part.name}/{n.path}", node=n.path) for n in nodes]

    def anchor(self, value: Any, where: str, with_pos: bool = True) -> Anchor:
        t = self.table(value, where, _ANCHOR_KEYS if with_pos else ("body", "hold"))
        hold = Hold(self.string(t.get("hold", "clamp"), f"{where}.hold",
                                tuple(h.value for h in Hold)))
        return Anchor(body=self.body_ref(t.get("body", "world"), f"{where}.body"),
                      pos=self.position(t.get("pos", [0, 0, 0]), f"{where}.pos")
                      if with_pos else _ZERO3, hold=hold)

    def to_world(self, anchor: Anchor) -> np.ndarray:
        """The anchor's world position at t = 0, metres."""
        origin, rotation = self.frames[anchor.body]
        return origin + rotation @ np.asarray(anchor.pos)

    def from_world(self, body: str, point: np.ndarray) -> tuple[float, float, float]:
        """A world point at t = 0 in the frame of `body`, metres."""
        origin, rotation = self.frames[body]
        return tuple(float(v) for v in rotation.T @ (point - origin))

    def cable(self, value: dict, where: str, dynamics: bool = True) -> CableDef:
        t = self.table(value, where, _CABLE_KEYS, ("name", "radius"))
        name = self.name(t["name"], f"{where}.name")
        radius = self.length(t["radius"], f"{where}.radius", positive=True)
        if "points" in t:
            if "via" in t:
                raise self.error(f"{where}.via", "not allowed with 'points' (the points "
                                                 "are the whole route)")
            points = self.point_list(t["points"], f"{where}.points")
            if len(points) < 2:
                raise self.error(f"{where}.points", f"needs at least 2 points, "
                                                    f"got {len(points)}")
            route = points
            ends = []
            for key, point in (("start", points[0]), ("end", points[-1])):
                if key in t and isinstance(t[key], dict) and "pos" in t[key]:
                    raise self.error(f"{where}.{key}.pos",
                                     f"not allowed with 'points': the {key} is "
                                     f"points[{0 if key == 'start' else -1}] (give only body)")
                anchor = self.anchor(t.get(key, {}), f"{where}.{key}", with_pos=False)
                ends.append(Anchor(anchor.body, self.from_world(anchor.body, point), anchor.hold))
            start, end = ends
            via = np.zeros((0, 3))
            via.setflags(write=False)
            labels = [f"{where}.points[{i}]" for i in range(len(points))]
        else:
            for key in ("start", "end"):
                if key not in t:
                    raise self.error(f"{where}.{key}", "missing (required unless "
                                                       "'points' gives the route)")
            start = self.anchor(t["start"], f"{where}.start")
            end = self.anchor(t["end"], f"{where}.end")
            via = self.point_list(t.get("via", []), f"{where}.via")
            points = None
            route = np.vstack([self.to_world(start), via, self.to_world(end)])
            route.setflags(write=False)
            labels = ([f"{where}.start"] + [f"{where}.via[{i}]" for i in range(len(via))]
                      + [f"{where}.end"])
        steps = np.linalg.norm(np.diff(route, axis=0), axis=1)
        short = np.flatnonzero(steps <= DEGENERATE * radius)
        if len(short):
            i = short[0]
            raise self.error(labels[i + 1], f"coincides with the route point before it "
                                            f"({labels[i].rsplit('.', 1)[-1]} at t = 0): "
                                            "a zero-length route segment")
        route_length = float(steps.sum())
        length = None
        if "length" in t:
            length = self.length(t["length"], f"{where}.length", positive=True)
            if length < route_length * (1 - ROUTE_TOLERANCE):
                along = ("along points" if points is not None
                         else "from start through via to end")
                raise self.error(f"{where}.length",
                                 f"{_g(length / self.scale)} {self._units()} is shorter than "
                                 f"the route ({_g(route_length / self.scale)} {self._units()} "
                                 f"{along} at t = 0)")
            if (points is not None and not dynamics
                    and length > route_length * (1 + POINTS_LENGTH_TOLERANCE)):
                raise self.error(f"{where}.length",
                                 f"{_g(length / self.scale)} {self._units()} is longer than the "
                                 f"route along points ({_g(route_length / self.scale)} "
                                 f"{self._units()}): with dynamics = false a points route is "
                                 "checked as given, so the cable's length is the route's "
                                 "(omit length)")
        clips = t.get("clips", [])
        if not isinstance(clips, list):
            raise self.error(f"{where}.clips", f"expected an array of tables, "
                                               f"got {_describe(clips)}")
        clips = tuple(self.anchor(c, f"{where}.clips[{i}]") for i, c in enumerate(clips))
        segments = None
        if "segments" in t:
            segments = self.integer(t["segments"], f"{where}.segments", 2)
            slack = length is not None and length > route_length * (1 + ROUTE_TOLERANCE)
            need = len(route) - 1 + len(clips) + (1 if slack else 0)
            if segments < need:
                raise self.error(f"{where}.segments",
                                 f"{segments} elements cannot have all {len(route)} route points"
                                 f"{' and the clips' if clips else ''} as vertices"
                                 f"{' and droop to the length' if slack else ''}: give at least "
                                 f"{need} (or omit segments)")
            element = (length or route_length) / segments
            if "self" in self.effects_read.contact and element <= SELF_CONTACT_ELEMENT * radius:
                most = max(2, math.ceil((length or route_length)
                                        / (SELF_CONTACT_ELEMENT * radius)) - 1)
                raise self.error(f"{where}.segments",
                                 f"{segments} elements are {_g(element / self.scale)} "
                                 f"{self._units()} long; with 'self' in effects.contact "
                                 f"elements two apart along a straight cable would touch "
                                 f"unless longer than {_g(SELF_CONTACT_ELEMENT)} radii "
                                 f"({_g(SELF_CONTACT_ELEMENT * radius / self.scale)} "
                                 f"{self._units()}); use at most {most}")
        bend = (self.length(t["min_bend_radius"], f"{where}.min_bend_radius", positive=True)
                if "min_bend_radius" in t else None)
        return CableDef(
            name=name, radius=radius, start=start, end=end, via=via, points=points,
            length=length, clips=clips, segments=segments,
            young=self.number(t.get("young", DEFAULT_YOUNG), f"{where}.young", positive=True),
            density=self.number(t.get("density", DEFAULT_DENSITY), f"{where}.density",
                                positive=True),
            min_bend_radius=bend, route=route,
            twist_stiffness=(self.number(t["twist_stiffness"], f"{where}.twist_stiffness",
                                         positive=True) if "twist_stiffness" in t else None),
            damping=self.number(t.get("damping", DEFAULT_DAMPING), f"{where}.damping",
                                nonnegative=True))

    def motion(self, value: dict, where: str, bodies: dict[str, BodyDef]) -> MotionDef:
        t = self.table(value, where, _MOTION_KEYS)
        targets = [k for k in ("body", "joint", "file") if k in t]
        if "file" in t and "keys" in t:
            raise self.error(f"{where}.keys", "not allowed with 'file' (the file holds "
                                              "the samples)")
        if "file" not in t and "keys" not in t:
            raise self.error(f"{where}.keys", "missing (required unless 'file' gives "
                                              "the samples)")
        keys_raw = t.get("keys", [])
        if "keys" in t:
            if (not isinstance(keys_raw, list)
                    or not all(isinstance(k, dict) for k in keys_raw)):
                raise self.error(f"{where}.keys", f"expected an array of tables "
                                                  f"({{ t = ..., ... }}), got {_describe(keys_raw)}")
            if not keys_raw:
                raise self.error(f"{where}.keys", "empty: give at least one keyframe")
        keyframes_only = not targets and all("key" in k for k in keys_raw)
        if len(targets) > 1 or not (targets or keyframes_only):
            raise self.error(where, "give exactly one of 'body' (a [[bodies]] name), 'joint' "
                                    "(a joint of the mjcf model) and 'file' (a CSV file of "
                                    "samples), or keys that all name keyframes of the mjcf "
                                    "model ({ t = ..., key = \"home\" })")
        interpolation = self.string(t.get("interpolation", INTERPOLATIONS[0]),
                                    f"{where}.interpolation", INTERPOLATIONS)
        time_scale = self.number(t.get("time_scale", 1.0), f"{where}.time_scale", positive=True)
        if "angles" in t and "body" in t:
            raise self.error(f"{where}.angles", "not used by a body's motion (its euler "
                                                "angles are degrees, as in [[bodies]])")
        angles = self.string(t.get("angles", "deg"), f"{where}.angles", tuple(ANGLES))
        body = joint = file = None
        keys: tuple = ()
        if "body" in t:
            body = self.motion_body(t["body"], f"{where}.body", bodies)
            home = bodies[body]
            keys = tuple(self.body_key(k, f"{where}.keys[{i}]", home)
                         for i, k in enumerate(keys_raw))
        elif "joint" in t:
            joint = self.motion_joint(t["joint"], f"{where}.joint")
            keys = tuple(self.joint_key(k, f"{where}.keys[{i}]") for i, k in enumerate(keys_raw))
        elif keyframes_only:
            if self.mjcf is None:
                raise self.error(f"{where}.keys[0].key", "no mjcf model in [scene]; "
                                                         "keyframes come from it")
            keys = tuple(self.joint_key(k, f"{where}.keys[{i}]") for i, k in enumerate(keys_raw))
        for i in range(1, len(keys)):
            if keys[i].t <= keys[i - 1].t:
                raise self.error(f"{where}.keys[{i}].t",
                                 f"times must increase strictly: {_g(keys[i].t)} after "
                                 f"{_g(keys[i - 1].t)}")
        if "file" in t:
            file = self.file_path(t["file"], f"{where}.file")
            trajectory = self.file_trajectory(file, t["file"], where, bodies, angles,
                                              interpolation, time_scale)
        else:
            trajectory = self.keys_trajectory(keys, body, joint, where, angles, interpolation,
                                              time_scale)
        return MotionDef(body=body, joint=joint, keys=keys, file=file, angles=angles,
                         interpolation=interpolation, time_scale=time_scale,
                         trajectory=trajectory)

    def motion_body(self, value: Any, where: str, bodies: dict[str, BodyDef]) -> str:
        """A body a motion may drive: a [[bodies]] body."""
        body = self.name(value, where)
        if body not in bodies:
            if body == "world":
                problem = "the world frame cannot move"
            elif self.mjcf and body in self.mjcf.bodies:
                problem = (f"{body!r} is a body of the mjcf model, which cannot be "
                           "keyframed by pose; drive its joints (joint = ...)")
            else:
                problem = f"no [[bodies]] entry named {body!r}"
            raise self.error(where, problem)
        return body

    def motion_joint(self, value: Any, where: str) -> str:
        """A joint a motion may drive: a hinge or slide joint of the mjcf model."""
        joint = self.name(value, where)
        if self.mjcf is None:
            raise self.error(where, "no mjcf model in [scene]; joints come from it")
        if joint not in self.mjcf.joints:
            close = difflib.get_close_matches(joint, list(self.mjcf.joints), n=1)
            hint = f" (did you mean {close[0]!r}?)" if close else ""
            raise self.error(where, f"no joint named {joint!r} in the mjcf model{hint}")
        kind = int(self.mjcf.model.jnt_type[self.mjcf.joints[joint]])
        if kind not in _DRIVEN:
            raise self.error(where, f"{joint!r} is a {mujoco.mjtJoint(kind).name[6:].lower()} "
                                    "joint; only hinge and slide joints are driven by a value")
        return joint

    def body_key(self, value: dict, where: str, home: BodyDef) -> BodyKey:
        t = self.table(value, where, _BODY_KEY_KEYS, ("t",))
        return BodyKey(t=self.number(t["t"], f"{where}.t", nonnegative=True),
                       pos=self.position(t["pos"], f"{where}.pos") if "pos" in t else home.pos,
                       euler=(self.vector(t["euler"], f"{where}.euler") if "euler" in t
                              else home.euler))

    def joint_key(self, value: dict, where: str) -> JointKey | KeyframeKey:
        t = self.table(value, where, _JOINT_KEY_KEYS, ("t",))
        time = self.number(t["t"], f"{where}.t", nonnegative=True)
        if ("value" in t) == ("key" in t):
            raise self.error(f"{where}.value" if "value" not in t else where,
                             "missing (required unless 'key' names a keyframe of the mjcf "
                             "model)" if "value" not in t else "give 'value' or 'key', not both")
        if "value" in t:
            return JointKey(t=time, value=self.number(t["value"], f"{where}.value"))
        name = self.name(t["key"], f"{where}.key")
        if self.mjcf is None:
            raise self.error(f"{where}.key", "no mjcf model in [scene]; keyframes come from it")
        if name not in self.mjcf.keyframes:
            known = sorted(self.mjcf.keyframes)
            raise self.error(f"{where}.key", f"no keyframe named {name!r} in the mjcf model "
                                             f"(known: {', '.join(known) or 'none'})")
        return KeyframeKey(t=time, key=name)

    # -- trajectories -------------------------------------------------------

    def driven_joints(self) -> list[str]:
        """Named hinge and slide joints of the mjcf model, in model order."""
        model = self.mjcf.model
        return [name for name, j in sorted(self.mjcf.joints.items(), key=lambda item: item[1])
                if int(model.jnt_type[j]) in _DRIVEN]

    def keyframe_qpos(self, name: str, where: str) -> np.ndarray:
        """The qpos of keyframe `name`; it may move only named hinge and slide joints."""
        model = self.mjcf.model
        qpos = model.key_qpos[self.mjcf.keyframes[name]]
        driven = {self.mjcf.joints[j] for j in self.driven_joints()}
        sizes = {int(mujoco.mjtJoint.mjJNT_FREE): 7, int(mujoco.mjtJoint.mjJNT_BALL): 4}
        for j in range(model.njnt):
            if j in driven:
                continue
            a = int(model.jnt_qposadr[j])
            n = sizes.get(int(model.jnt_type[j]), 1)
            if not np.allclose(qpos[a:a + n], model.qpos0[a:a + n], rtol=0.0, atol=1e-12):
                body = model.body(int(model.jnt_bodyid[j])).name
                label = model.joint(j).name or f"#{j} (unnamed, on body {body!r})"
                raise self.error(where, f"keyframe {name!r} moves joint {label}; only named hinge "
                                        "and slide joints are driven")
        return qpos

    def joint_scale(self, joint: str, angles: str) -> float:
        """Multiplies a written value of `joint` into MuJoCo units."""
        hinge = int(self.mjcf.model.jnt_type[self.mjcf.joints[joint]]) == _HINGE
        return ANGLES[angles] if hinge else self.scale

    def keys_trajectory(self, keys: tuple, body: str | None, joint: str | None, where: str,
                        angles: str, interpolation: str, time_scale: float) -> Trajectory:
        times = np.array([k.t for k in keys], float) / time_scale
        none = np.zeros((len(keys), 0))
        if body is not None:
            pos = np.array([k.pos for k in keys], float)[:, None, :]
            euler = np.array([k.euler for k in keys], float)[:, None, :]
            return _trajectory(times, (), none, (body,), pos, euler, interpolation)
        joints = (joint,) if joint is not None else tuple(self.driven_joints())
        adr = self.mjcf.model.jnt_qposadr[[self.mjcf.joints[j] for j in joints]]
        values = np.zeros((len(keys), len(joints)))
        for i, k in enumerate(keys):
            if isinstance(k, KeyframeKey):
                values[i] = self.keyframe_qpos(k.key, f"{where}.keys[{i}].key")[adr]
            else:
                values[i] = k.value * self.joint_scale(joint, angles)
        no_bodies = np.zeros((len(keys), 0, 3))
        trajectory = _trajectory(times, joints, values, (), no_bodies, no_bodies, interpolation)
        self.check_ranges(trajectory, angles, lambda i: (
            f"{where}.keys[{i}].{'key' if isinstance(keys[i], KeyframeKey) else 'value'}",
            f"t = {_g(keys[i].t)} s"))
        return trajectory

    def file_trajectory(self, path: Path, written: str, where: str, bodies: dict[str, BodyDef],
                        angles: str, interpolation: str, time_scale: float) -> Trajectory:
        """The samples of a CSV motion file (see `read_samples`)."""
        where = f"{where}.file"
        header, table, lines = self.read_samples(path, written, where)
        joints: list[str] = []
        body_axes: dict[str, dict[str, int]] = {}
        for c, name in enumerate(header[1:], start=1):
            body, _, axis = name.rpartition(".")
            try:
                if self.mjcf is not None and name in self.mjcf.joints:
                    joints.append(self.motion_joint(name, where))
                    continue
                if body and axis in BODY_AXES:
                    self.motion_body(body, where, bodies)
                    body_axes.setdefault(body, {})[axis] = c
                    continue
            except SceneError as e:
                raise self.error(where, f"{written} column {name!r}: {e.problem}") from None
            known = sorted(self.mjcf.joints if self.mjcf else []) + [
                f"{b}.{a}" for b in bodies for a in BODY_AXES]
            close = difflib.get_close_matches(name, known, n=1, cutoff=0.6)
            hint = f" (did you mean {close[0]!r}?)" if close else ""
            raise self.error(where, f"{written} column {name!r}: neither a joint of the mjcf "
                                    f"model nor <body>.x/.y/.z/.rx/.ry/.rz of a [[bodies]] "
                                    f"body{hint}")
        n = len(table)
        columns = [header.index(j) for j in joints]
        values = table[:, columns] * np.array([self.joint_scale(j, angles) for j in joints])
        names = tuple(body_axes)
        pos = np.zeros((n, len(names), 3))
        euler = np.zeros((n, len(names), 3))
        for b, (name, axes) in enumerate(body_axes.items()):
            home = bodies[name]
            for k, axis in enumerate(BODY_AXES):
                target, index = (pos, k) if k < 3 else (euler, k - 3)
                default = home.pos[k] if k < 3 else home.euler[k - 3]
                target[:, b, index] = (table[:, axes[axis]] * (self.scale if k < 3 else 1.0)
                                       if axis in axes else default)
        times = table[:, 0] / time_scale
        trajectory = _trajectory(times, tuple(joints), values, names, pos, euler, interpolation)
        self.check_ranges(trajectory, angles, lambda i: (
            where, f"{written} line {lines[i]}, t = {_g(table[i, 0])} s"))
        return trajectory

    def read_samples(self, path: Path, written: str, where: str
                     ) -> tuple[list[str], np.ndarray, list[int]]:
        """A CSV motion file: its header (``t`` first), its (n, columns) numbers
        and each row's line number. Blank lines are skipped; every cell must be
        a finite number, t not negative and strictly increasing."""
        def fail(problem: str) -> SceneError:
            return self.error(where, f"{written}: {problem}")

        try:
            text = path.read_bytes().decode("utf-8-sig")
        except OSError as e:
            raise fail(f"cannot read: {e.strerror or e}") from None
        except UnicodeDecodeError as e:
            raise fail(f"not UTF-8 text (byte {e.start}: {e.reason})") from None
        reader = csv.reader(io.StringIO(text))
        rows, lines = [], []
        try:
            for row in reader:
                if any(cell.strip() for cell in row):
                    rows.append([cell.strip() for cell in row])
                    lines.append(reader.line_num)
        except csv.Error as e:
            raise fail(f"line {reader.line_num}: not CSV: {e}") from None
        if not rows:
            raise fail("empty: expected a header 't,<joint or body.axis>,...' and rows")
        header = rows[0]
        if header[0] != "t":
            raise fail(f"line {lines[0]}: the header's first column must be 't' (time, s), "
                       f"got {header[0]!r}")
        if len(header) < 2:
            raise fail(f"line {lines[0]}: the header names no joint or body column")
        for c, name in enumerate(header):
            if not name:
                raise fail(f"line {lines[0]}: column {c + 1} of the header is empty")
            if name in header[:c]:
                raise fail(f"line {lines[0]}: column {name!r} appears twice")
        body = rows[1:]
        if not body:
            raise fail("no samples: the header is the only row")
        for row, line in zip(body, lines[1:]):
            if len(row) != len(header):
                raise fail(f"line {line}: {len(row)} cell{'s' * (len(row) != 1)}, the header "
                           f"has {len(header)}")
        try:
            table = np.array(body, dtype=float)
        except ValueError:   # find the cell numpy could not read
            for r, row in enumerate(body):
                for c, cell in enumerate(row):
                    try:
                        float(cell)
                    except ValueError:
                        raise fail(f"line {lines[r + 1]}, column {header[c]!r}: not a number: "
                                   f"{cell!r}") from None
            raise
        finite = np.isfinite(table) & (np.abs(table) <= LARGEST)
        if not finite.all():
            r, c = np.argwhere(~finite)[0]
            raise fail(f"line {lines[r + 1]}, column {header[c]!r}: not a finite number of "
                       f"magnitude at most {LARGEST:g}: {body[r][c]!r}")
        t = table[:, 0]
        if t[0] < 0:
            raise fail(f"line {lines[1]}, column 't': must not be negative, got {_g(t[0])}")
        steps = np.flatnonzero(np.diff(t) <= 0)
        if len(steps):
            r = steps[0] + 1
            raise fail(f"line {lines[r + 1]}, column 't': times must increase strictly: "
                       f"{_g(t[r])} after {_g(t[r - 1])} (line {lines[r]})")
        return header, table, lines[1:]

    def check_ranges(self, trajectory: Trajectory, angles: str, sample) -> None:
        """Every joint sample inside its joint's range, when the joint is
        limited. `sample(i)` gives (key path, "where in the source") of sample i.
        The interpolants stay between neighbouring samples (`sim.curves`), so
        the samples bound the whole motion."""
        model = self.mjcf.model if self.mjcf else None
        for j, name in enumerate(trajectory.joints):
            jid = self.mjcf.joints[name]
            if not model.jnt_limited[jid]:
                continue
            lo, hi = (float(v) for v in model.jnt_range[jid])
            tol = 1e-9 * max(1.0, abs(lo), abs(hi))
            values = trajectory.joint_values[:, j]
            out = np.flatnonzero((values < lo - tol) | (values > hi + tol))
            if not len(out):
                continue
            i = out[0]
            hinge = int(model.jnt_type[jid]) == _HINGE
            unit = angles if hinge else self._units()
            per = ANGLES[angles] if hinge else self.scale
            key, source = sample(i)
            raise self.error(key, f"{source}: joint {name!r} at {_g(values[i] / per)} {unit} is "
                                  f"outside its range {_g(lo / per)}..{_g(hi / per)} {unit}")

    def unique(self, records: tuple, where: str, kind: str) -> None:
        seen: dict[str, int] = {}
        for i, record in enumerate(records):
            if record.name in seen:
                raise self.error(f"{where}[{i}].name", f"duplicate {kind} name "
                                 f"{record.name!r} (also {where}[{seen[record.name]}])")
            seen[record.name] = i

    def _units(self) -> str:
        return "m" if self.scale == 1.0 else "mm"


_SIZE_HELP = {"box": "half-extents x, y, z", "sphere": "radius",
              "cylinder": "radius, half-length", "capsule": "radius, half-length",
              "ellipsoid": "semi-axes x, y, z"}


_HINGE = int(mujoco.mjtJoint.mjJNT_HINGE)
_DRIVEN = (_HINGE, int(mujoco.mjtJoint.mjJNT_SLIDE))


def _trajectory(times, joints, values, bodies, pos, euler, interpolation) -> Trajectory:
    """A read-only Trajectory; euler angles unwrapped (short way between samples)."""
    euler = np.unwrap(np.asarray(euler, float), period=360.0, axis=0)
    arrays = [np.array(a, float) for a in (times, values, pos, euler)]
    for a in arrays:
        a.setflags(write=False)
    times, values, pos, euler = arrays
    return Trajectory(times=times, joints=tuple(joints), joint_values=values,
                      bodies=tuple(bodies), body_pos=pos, body_euler=euler,
                      interpolation=interpolation)


def covers(pattern: str, names) -> bool:
    """True when `pattern` is one of `names` or an assembly path prefix of one."""
    prefix = pattern + "/"
    return any(n == pattern or n.startswith(prefix) for n in names)


def unknown_name(name: str, names) -> str:
    """The problem text for an `[[allow]]` name that covers nothing, with the
    closest part, assembly path or cable name as a hint."""
    known = sorted({"/".join(n.split("/")[:k]) for n in names for k in range(1, n.count("/") + 2)})
    close = difflib.get_close_matches(name, known, n=1, cutoff=0.6)
    hint = f"did you mean {close[0]!r}?" if close else f"{len(known)} names known, e.g. " + \
        ", ".join(repr(k) for k in known[:5])
    return f"no part, assembly path or cable named {name!r} ({hint})"


def check_allow_names(scene: Scene, names) -> None:
    """Raise SceneError when an `[[allow]]` name covers none of `names` (the
    built parts' and the cables' names): a name taken at load time for a
    body of the mjcf model whose geoms the builder named otherwise."""
    names = list(names)
    for i, rule in enumerate(scene.allow):
        for key, name in (("a", rule.a), ("b", rule.b)):
            if not covers(name, names):
                raise SceneError(scene.path, f"allow[{i}].{key}", unknown_name(name, names))


def _frame(origin, rotation) -> tuple[np.ndarray, np.ndarray]:
    """A read-only (origin (3,), rotation (3, 3)) pair."""
    origin, rotation = np.array(origin, float), np.array(rotation, float)
    origin.setflags(write=False)
    rotation.setflags(write=False)
    return origin, rotation


def _join(where: str, key: str) -> str:
    return key if where == "(top level)" else f"{where}.{key}"


def _g(value: float) -> str:
    return f"{value:.6g}"
