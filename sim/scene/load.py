"""`load_scene` and `parse_scene`: a scene file (or the dict `tomllib` gives
for it) to a validated `Scene`, reading the tables in the order they
depend on one another.

`[scene]` first (units, the mjcf model), then `[effects]`, `[check]`,
`[[bodies]]`, `[[parts]]`, `[[motion]]` (which fix every body's frame at
t = 0), `[[cables]]` (routed in those frames), `[limits]` and `[[allow]]`.
Each table has its own module; this one only orders them and checks what
spans tables (names unique across parts and cables, one motion per target).
"""

from __future__ import annotations

import re
import tomllib
from dataclasses import replace
from pathlib import Path
from types import MappingProxyType

import numpy as np

from cablecheck.scene.allow import read_allow
from cablecheck.scene.cables import check_fastened_names, read_cable
from cablecheck.scene.errors import SceneError
from cablecheck.scene.format import SCENE_KEYS, TOP_KEYS, UNITS
from cablecheck.scene.frames import euler_matrix, frame, mjcf_frames
from cablecheck.scene.mjcf import compile_mjcf
from cablecheck.scene.motion import read_motion
from cablecheck.scene.parts import expand_nodes, read_body, read_part
from cablecheck.scene.reader import Reader
from cablecheck.scene.records import Scene
from cablecheck.scene.settings import read_check, read_effects, read_limits, within_limits
from cablecheck.scene.units import check_units


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
    return read_scene(Reader(Path(path)), data)


def read_scene(r: Reader, data: dict) -> Scene:
    """The whole scene dict, the tables in the order they depend on one another."""
    data = r.table(data, "(top level)", TOP_KEYS, ("scene",))
    head = r.table(data["scene"], "scene", SCENE_KEYS, ("name", "units", "duration"))
    name = r.name(head["name"], "scene.name")
    if "/" in name or "\\" in name or name in (".", ".."):
        raise r.error("scene.name", f"is used as a file name; it may not contain "
                                    f"'/' or '\\' or be '.' or '..', got {name!r}")
    units = r.string(head["units"], "scene.units", tuple(UNITS))
    r.scale = UNITS[units]
    duration = r.number(head["duration"], "scene.duration", nonnegative=True)
    timestep = r.number(head.get("timestep", 0.002), "scene.timestep", positive=True)
    settle = r.number(head.get("settle", 0.0), "scene.settle", nonnegative=True)
    mjcf = None
    if "mjcf" in head:
        mjcf = r.file_path(head["mjcf"], "scene.mjcf")
        r.mjcf = compile_mjcf(r.file, mjcf)
        r.frames.update(dict.fromkeys(r.mjcf.bodies))   # names now, frames below
    r.frames["world"] = frame(np.zeros(3), np.eye(3))

    effects = read_effects(r, data.get("effects", {}))
    r.effects_read = effects
    check = read_check(r, data.get("check", {}))
    bodies = tuple(read_body(r, b, f"bodies[{i}]")
                   for i, b in enumerate(r.tables(data.get("bodies", []), "bodies")))
    parts = tuple(node for i, p in enumerate(r.tables(data.get("parts", []), "parts"))
                  for node in expand_nodes(r, read_part(r, p, f"parts[{i}]"), f"parts[{i}]"))
    r.unique(parts, "parts", "part")
    motions = tuple(read_motion(r, m, f"motion[{i}]", {b.name: b for b in bodies})
                    for i, m in enumerate(r.tables(data.get("motion", []), "motion")))
    driven: dict[str, int] = {}
    for i, m in enumerate(motions):
        traj = m.trajectory
        for target in ([f"body {b!r}" for b in traj.bodies]
                       + [f"joint {j!r}" for j in traj.joints]):
            if target in driven:
                raise r.error(f"motion[{i}]", f"{target} is already driven by "
                                              f"motion[{driven[target]}]")
            driven[target] = i
        for k, b in enumerate(traj.bodies):
            r.frames[b] = frame(traj.body_pos[0, k], euler_matrix(traj.body_euler[0, k]))
    if r.mjcf is not None:
        r.frames.update(mjcf_frames(r.mjcf, motions))
    cables = tuple(read_cable(r, c, f"cables[{i}]", effects.dynamics)
                   for i, c in enumerate(r.tables(data.get("cables", []), "cables")))
    r.unique(cables, "cables", "cable")
    part_index = {p.name: i for i, p in enumerate(parts)}
    for i, cable in enumerate(cables):
        if cable.name in part_index:
            raise r.error(f"cables[{i}].name", f"{cable.name!r} is also the name of "
                          f"parts[{part_index[cable.name]}]; names must differ")
    limits = read_limits(r, data.get("limits", {}))
    names = [p.name for p in parts] + [c.name for c in cables]
    allow = tuple(read_allow(r, a, f"allow[{i}]", names)
                  for i, a in enumerate(r.tables(data.get("allow", []), "allow")))
    scene = Scene(path=r.file, name=name, units=units, scale=r.scale,
                  duration=duration, timestep=timestep, settle=settle, mjcf=mjcf,
                  effects=effects, check=check, bodies=bodies, parts=parts,
                  cables=cables, motions=motions, allow=allow,
                  start_frames=MappingProxyType(dict(r.frames)), limits=limits)
    warnings = check_units(scene)          # a size no unit makes sense of first: it says which unit
    within_limits(r, limits, duration + settle, timestep, check, cables)
    check_fastened_names(scene, [p.name for p in parts],
                         (set(r.mjcf.bodies) | {"world"}) if r.mjcf is not None else ())
    return replace(scene, warnings=warnings) if warnings else scene
