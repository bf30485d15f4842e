"""The checker's view of a built scene: shapes, rigid groups, selections, and who imports it."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import trimesh

from cablecheck.build.checkview import (
    DEFAULT_PRECISION_M,
    OptionError,
    part_set,
    part_shapes,
    rigid_groups,
    selection,
)
from cablecheck.build.stages import build
from cablecheck.checker.shapes import ShapeType
from cablecheck.run.runner import RunOptions, run_scene
from cablecheck.scene.load import parse_scene

ROOT = Path(__file__).resolve().parents[1]


def _scene(tmp_path: Path) -> dict:
    mesh = trimesh.creation.box(extents=[0.02, 0.04, 0.06])
    mesh.apply_translation([0.3, 0.2, 0.1])     # off-centre: MuJoCo recentres it
    mesh.export(tmp_path / "block.stl")
    return {
        "scene": {"name": "view", "units": "m", "duration": 0.0, "settle": 0.0},
        "effects": {"dynamics": False, "contact": []},
        "bodies": [{"name": "slider", "pos": [0.0, 0.0, 0.3]}],
        "parts": [{"name": "frame/post", "shape": "box", "size": [0.01, 0.02, 0.03], "pos": [0.3, 0, 0]},
                  {"name": "frame/ball", "shape": "sphere", "size": [0.02], "pos": [0.5, 0, 0]},
                  {"name": "frame/block", "shape": "mesh", "file": "block.stl"},
                  {"name": "slider/pin", "body": "slider", "shape": "cylinder", "size": [0.005, 0.02]}],
        "cables": [{"name": "c", "radius": 0.004, "start": {"pos": [0, 0, 0.2]},
                    "end": {"pos": [0.6, 0, 0.2]}, "segments": 10}],
    }


def test_shapes_are_the_built_geoms(tmp_path):
    built = build(parse_scene(_scene(tmp_path), tmp_path / "s.toml"), detect=False)
    shapes = part_shapes(built)
    assert [s.type for s in shapes] == [ShapeType.BOX, ShapeType.SPHERE, ShapeType.MESH, ShapeType.CYLINDER]
    assert np.array_equal(shapes[0].size, built.parts[0].size)
    block = built.parts[2]
    # the mesh in MuJoCo's geom frame (recentred), not the file's
    assert np.allclose(shapes[2].vertices, block.vertices)
    assert np.allclose(shapes[2].vertices.mean(axis=0), 0.0, atol=1e-6)
    assert len(shapes[2].faces) == len(block.faces) == 12


def test_rigid_groups_follow_the_bodies(tmp_path):
    built = build(parse_scene(_scene(tmp_path), tmp_path / "s.toml"), detect=False)
    assert rigid_groups(built) == ["world", "world", "world", "slider"]
    parts = part_set(built, tolerance=DEFAULT_PRECISION_M)
    assert list(parts.names) == [p.name for p in built.parts]


def test_selection_by_name_and_assembly_prefix(tmp_path):
    built = build(parse_scene(_scene(tmp_path), tmp_path / "s.toml"), detect=False)
    parts = part_set(built, tolerance=DEFAULT_PRECISION_M)
    assert selection(parts, "frame", "--only").tolist() == [True, True, True, False]
    assert selection(parts, "slider/pin", "--only").tolist() == [False, False, False, True]
    with pytest.raises(OptionError) as e:
        selection(parts, "frame/bal", "--only")
    assert e.value.option == "--only"
    assert "'frame/ball'" in e.value.problem        # the close name is offered


def test_run_only_unknown_is_the_runs_own_error(tmp_path):
    """A run's --only naming nothing is an OptionError, not the sweep command's error."""
    scene = parse_scene(_scene(tmp_path), tmp_path / "s.toml")
    with pytest.raises(OptionError) as e:
        run_scene(scene, RunOptions(report=tmp_path / "r.json", record=None, only="nothing"))
    assert type(e.value) is OptionError and e.value.option == "--only"


def test_the_run_does_not_import_the_sweep_command():
    """No module of a run imports the sweep command's module."""
    code = "import sys, cablecheck.run.runner, cablecheck.run.stepcheck, cablecheck.record; print('cablecheck.run.sweep' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True,
                         env={"PYTHONPATH": str(ROOT), "PATH": "/usr/bin:/bin"}, check=True)
    assert out.stdout.strip() == "False"
