"""Mesh formats: STL, OBJ, PLY and glTF/GLB node trees become parts (names, scale, keep-out closure)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import trimesh

from cablecheck.cli.main import main
from cablecheck.scene.errors import SceneError
from cablecheck.scene.load import load_scene
from cablecheck.scene.meshfile import MeshFileError, mesh_nodes

SCENE = """
[scene]
name = "meshes"
units = "m"
duration = 0.0

[effects]
dynamics = false

[check]
validate = false

[[parts]]
name = "mover"
shape = "box"
size = [0.05, 0.05, 0.05]

[[parts]]
name = "asm"
shape = "mesh"
file = "{file}"
scale = 0.001
pos = [1.0, 0, 0]
{extra}
"""


def _tree(path: Path) -> Path:
    """A GLB in mm: node 'base' (100 mm cube at the origin) with a child 'lid'
    (40 mm cube 300 mm above), and a separate root 'post' 500 mm along x."""
    scene = trimesh.Scene()
    scene.add_geometry(trimesh.creation.box(extents=[100, 100, 100]), node_name="base", geom_name="g_base")
    scene.add_geometry(trimesh.creation.box(extents=[40, 40, 40]), node_name="lid", geom_name="g_lid",
                       parent_node_name="base",
                       transform=trimesh.transformations.translation_matrix([0, 0, 300]))
    scene.add_geometry(trimesh.creation.box(extents=[100, 100, 100]), node_name="post", geom_name="g_post",
                       transform=trimesh.transformations.translation_matrix([500, 0, 0]))
    scene.export(path)
    return path


def test_gltf_nodes_have_tree_paths_and_transforms(tmp_path: Path):
    nodes = {n.path: n for n in mesh_nodes(_tree(tmp_path / "a.glb"))}
    assert set(nodes) == {"base", "base/lid", "post"}
    assert nodes["base/lid"].vertices[:, 2].min() == pytest.approx(280.0)
    assert nodes["post"].vertices[:, 0].min() == pytest.approx(450.0)


def test_gltf_part_expands_into_assembly_paths_and_sweeps(tmp_path: Path):
    scene = tmp_path / "s.toml"
    scene.write_text(SCENE.format(file=_tree(tmp_path / "a.glb").name, extra=""))
    names = [p.name for p in load_scene(scene).parts]
    assert names == ["mover", "asm/base", "asm/base/lid", "asm/post"]
    out = tmp_path / "r.json"
    assert main(["sweep", str(scene), "--part", "mover", "--direction", "1,0,0", "--distance", "2",
                 "--report", str(out), "--quiet"]) == 1
    got = {h["part"]: h["distance"] for h in json.loads(out.read_text())["hits"]}
    # base spans x 0.95..1.05, post 1.45..1.55; mover's front at 0.05; lid is above the path
    assert got == {"asm/base": pytest.approx(0.9, abs=1e-6), "asm/post": pytest.approx(1.4, abs=1e-6)}
    assert main(["sweep", str(scene), "--part", "asm/base", "--direction", "0,0,1", "--distance", "1",
                 "--report", str(out), "--quiet"]) == 0
    r = json.loads(out.read_text())
    assert r["moving"] == ["asm/base", "asm/base/lid"] and r["hits"] == []


@pytest.mark.parametrize("suffix", [".stl", ".obj", ".ply"])
def test_single_mesh_formats_in_mm(tmp_path: Path, suffix: str):
    mesh = tmp_path / f"cube{suffix}"
    trimesh.creation.box(extents=[100, 100, 100]).export(mesh)
    scene = tmp_path / "s.toml"
    scene.write_text(SCENE.format(file=mesh.name, extra=""))
    out = tmp_path / "r.json"
    assert main(["sweep", str(scene), "--part", "mover", "--direction", "1,0,0", "--distance", "2",
                 "--report", str(out), "--quiet"]) == 1
    assert json.loads(out.read_text())["hits"][0]["distance"] == pytest.approx(0.9, abs=1e-6)


def test_open_keepout_mesh_is_refused_and_open_part_warns(tmp_path: Path):
    tm = trimesh.creation.box(extents=[100, 100, 100])
    tm.update_faces(np.arange(len(tm.faces)) != 0)
    tm.export(tmp_path / "open.stl")
    scene = tmp_path / "s.toml"
    scene.write_text(SCENE.format(file="open.stl", extra="keepout = true"))
    with pytest.raises(SceneError, match="not a closed surface"):
        load_scene(scene)
    scene.write_text(SCENE.format(file="open.stl", extra=""))
    out = tmp_path / "r.json"
    main(["sweep", str(scene), "--part", "mover", "--direction", "1,0,0", "--distance", "2",
          "--report", str(out), "--quiet"])
    r = json.loads(out.read_text())
    assert any("inside and outside cannot be decided" in w for w in r["warnings"])
    assert [h["part"] for h in r["hits"]] == ["asm"]


def test_unreadable_mesh_exits_2(tmp_path: Path, capsys):
    (tmp_path / "bad.glb").write_bytes(b"not a glb")
    scene = tmp_path / "s.toml"
    scene.write_text(SCENE.format(file="bad.glb", extra=""))
    assert main(["sweep", str(scene), "--part", "mover", "--direction", "1,0,0", "--distance", "1"]) == 2
    err = capsys.readouterr().err
    assert "parts[1].file" in err and "Traceback" not in err


def test_corrupt_stl_says_what_is_wrong(tmp_path):
    """Random bytes, a truncated binary STL and a tiny file: the message names the
    layout that does not fit, not an error of trimesh's text fallback."""
    good = tmp_path / "good.stl"
    trimesh.creation.box().export(good)
    assert len(mesh_nodes(good)[0].faces) == 12
    rng = np.random.default_rng(0)
    cases = {"random.stl": rng.bytes(3000), "truncated.stl": good.read_bytes()[:500], "tiny.stl": b"hello\n"}
    for name, data in cases.items():
        (tmp_path / name).write_bytes(data)
        with pytest.raises(MeshFileError) as e:
            mesh_nodes(tmp_path / name)
        assert name in str(e.value) and "charset" not in str(e.value)
    with pytest.raises(MeshFileError, match="declares 12 triangles, which take 684 bytes, but the file has 500"):
        mesh_nodes(tmp_path / "truncated.stl")
    with pytest.raises(MeshFileError, match="6 bytes, too short"):
        mesh_nodes(tmp_path / "tiny.stl")
