"""The mjcf model's visual geoms, for the recording only: read from the file compiled whole.

The simulation and detection models leave out what MuJoCo only draws
(`cablecheck.scene.mjcf.lean_spec`): a robot's visual meshes are most of
what compiling it costs, and nothing but the recording uses them. A run
that records compiles the file whole on a thread of its own as it starts
(`DrawnLoad`; MuJoCo's compiler releases Python's interpreter lock, so on
a second core this costs the run nothing) and takes from it each geom
MuJoCo never collides (contype = conaffinity = 0 as written): its name as
the builder names a body's visual geoms, its shape, its colour as MuJoCo
draws it and its pose in its body. The recording draws each by its body's
pose in the simulation model, whose mjcf bodies are the file's, in the
file's order (`cablecheck.build.mjspec` adds the scene's after them).

Not here: drawing them (`cablecheck.record.scene`).
"""

from __future__ import annotations

import threading
from dataclasses import dataclass
from pathlib import Path

import mujoco
import numpy as np

from cablecheck.build.modelread import mesh_arrays
from cablecheck.scene.errors import SceneError
from cablecheck.scene.mjcf import SHAPES, body_name, geom_names
from cablecheck.scene.records import Scene


@dataclass(frozen=True)
class DrawnGeom:
    """One visual geom of the mjcf model, as the recording draws it."""

    name: str                   # `<body>/<geom>`, as `cablecheck.scene.mjcf.geom_names` names a body's visual geoms
    geom_id: int                # its id in the file's model compiled whole (not in the simulation's)
    body: str                   # its body's name (`body_name`)
    body_id: int                # its body's id, the same in the file's model and the simulation's
    shape: str                  # a `SHAPES` value
    size: np.ndarray            # MuJoCo's three size numbers
    vertices: np.ndarray | None  # a mesh's vertices in the geom's frame (MuJoCo's), else None
    faces: np.ndarray | None
    local: np.ndarray           # (4, 4) the geom's pose in its body's frame
    rgba: tuple[int, int, int, int]   # its colour as MuJoCo draws it (its material's, else its own), 0-255


def drawn_geoms(m: mujoco.MjModel) -> tuple[DrawnGeom, ...]:
    """The visual geoms (contype = conaffinity = 0) of a model compiled whole, in model order."""
    per_body: dict[int, list[int]] = {}
    for g in range(m.ngeom):
        if int(m.geom_type[g]) in SHAPES and m.geom_contype[g] == 0 and m.geom_conaffinity[g] == 0:
            per_body.setdefault(int(m.geom_bodyid[g]), []).append(g)
    named = {g: n for geoms in per_body.values() for g, n in zip(geoms, geom_names(m, geoms))}
    out = []
    for g in sorted(named):
        verts, faces = mesh_arrays(m, g)
        local = np.eye(4)
        mat = np.zeros(9)
        mujoco.mju_quat2Mat(mat, m.geom_quat[g])
        local[:3, :3], local[:3, 3] = mat.reshape(3, 3), m.geom_pos[g]
        mat_id = int(m.geom_matid[g])
        rgba = m.mat_rgba[mat_id] if mat_id >= 0 else m.geom_rgba[g]
        bid = int(m.geom_bodyid[g])
        out.append(DrawnGeom(named[g], g, body_name(m, bid), bid, SHAPES[int(m.geom_type[g])], m.geom_size[g].copy(),
                             verts, faces, local,
                             tuple(round(255 * float(c)) for c in np.clip(rgba, 0.0, 1.0))))
    return tuple(out)


class DrawnLoad:
    """The scene's visual geoms (`drawn_geoms` of its mjcf file compiled
    whole), compiled on a thread started here; `result()` waits for them.
    None of them without an mjcf file."""

    def __init__(self, scene: Scene):
        self._scene = scene
        self._out: tuple[DrawnGeom, ...] = ()
        self._error: BaseException | None = None
        self._thread = None
        if scene.mjcf is not None:
            self._thread = threading.Thread(target=self._work, name="cablecheck-drawn", daemon=True)
            self._thread.start()

    def _work(self) -> None:
        try:
            self._out = drawn_geoms(mujoco.MjModel.from_xml_path(str(self._scene.mjcf)))
        except BaseException as exc:   # handed to result()
            self._error = exc

    def result(self) -> tuple[DrawnGeom, ...]:
        """The visual geoms; a file MuJoCo cannot compile whole (a visual
        mesh's file missing, which the checks never read) is the scene's
        error (`scene.mjcf`)."""
        if self._thread is not None:
            self._thread.join()
        if self._error is not None:
            message = " ".join(str(self._error).split())
            raise SceneError(self._scene.path, "scene.mjcf",
                             f"MuJoCo cannot compile {Path(self._scene.mjcf).name} with its visual geoms, "
                             f"which the recording draws: {message} (--no-record runs without them)")
        return self._out

