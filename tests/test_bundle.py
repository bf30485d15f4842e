"""The files that travel with a study's task (cablecheck.study.bundle): meshes, MJCF
models with includes and meshdirs, example scenes; unpacked elsewhere they
load as the originals."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest
from helpers import write_text

from cablecheck.scene.load import load_scene, parse_scene
from cablecheck.study.bundle import make_bundle, materialise

SCENES = Path(__file__).resolve().parents[1] / "scenes"


def test_bundle_carries_meshes_and_mjcf_files(tmp_path):
    """A scene's files, unpacked elsewhere, load as the original: a mesh part,
    an mjcf model with an <include> and a mesh under the compiler's meshdir."""
    src = tmp_path / "src"
    shutil.copy(SCENES / "meshes" / "l_bracket.stl", write_text(src / "robot" / "assets" / "x", "").parent
                / "bracket.stl")
    write_text(src / "robot" / "arm.xml",
           '<mujoco><compiler meshdir="assets"/><include file="parts.xml"/>'
           '<worldbody><body name="b"><geom type="mesh" mesh="m"/></body></worldbody></mujoco>')
    write_text(src / "robot" / "parts.xml", '<mujoco><asset><mesh name="m" file="bracket.stl"'
                                        ' scale="0.001 0.001 0.001"/></asset></mujoco>')
    write_text(src / "unrelated.bin", "not needed")
    shutil.copy(SCENES / "meshes" / "l_bracket.stl", src / "l_bracket.stl")
    scene = write_text(src / "cell" / "scene.toml", """
[scene]
name = "cell"
units = "m"
duration = 0.0
mjcf = "../robot/arm.xml"
[[parts]]
name = "bracket"
shape = "mesh"
file = "%s"
scale = 0.001
""" % (src / "l_bracket.stl"))   # an absolute name: rewritten relative
    base = load_scene(scene)
    import tomllib
    bundle, (data,) = make_bundle(scene, [tomllib.loads(scene.read_text())])
    names = {rel for rel, _ in bundle.files}
    assert names == {"robot/arm.xml", "robot/parts.xml", "robot/assets/bracket.stl", "l_bracket.stl"}
    assert bundle.scene == "cell/scene.toml" and data["parts"][0]["file"] == "../l_bracket.stl"
    shutil.rmtree(src)
    moved = parse_scene(data, materialise(bundle, tmp_path / "elsewhere"))
    assert moved.mjcf == (tmp_path / "elsewhere" / "robot" / "arm.xml").resolve()
    assert moved.parts[0].file == (tmp_path / "elsewhere" / "l_bracket.stl").resolve()
    assert [p.name for p in moved.parts] == [p.name for p in base.parts]


@pytest.mark.parametrize("name", ["arm.toml", "robot_cell.toml", "bracket_static.toml"])
def test_example_scenes_travel(name, tmp_path):
    """The example scenes with files (an mjcf model and its meshes, a motion
    CSV, a mesh part), unpacked elsewhere, load with the same parts and
    motions; nothing else of their folders travels."""
    import tomllib

    path = SCENES / name
    bundle, (data,) = make_bundle(path, [tomllib.loads(path.read_text())])
    moved = parse_scene(data, materialise(bundle, tmp_path))
    base = load_scene(path)
    assert [p.name for p in moved.parts] == [p.name for p in base.parts]
    assert len(moved.motions) == len(base.motions)
    assert all(str(p.file).startswith(str(tmp_path)) for p in moved.parts if p.file is not None)
    assert moved.mjcf is None or str(moved.mjcf).startswith(str(tmp_path))
    assert all(m.file is None or str(m.file).startswith(str(tmp_path)) for m in moved.motions)
    assert not any(n.endswith((".md", "LICENSE")) or n.endswith("_study.toml") for n, _ in bundle.files)
