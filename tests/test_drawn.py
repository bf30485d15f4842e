"""The mjcf model's visual geoms (cablecheck.build.drawn, cablecheck.scene.mjcf.lean_spec):
left out of the models the run simulates and checks, drawn from the file
compiled whole, and a visual mesh MuJoCo cannot read an error of the
recording only."""

from __future__ import annotations

from pathlib import Path

import mujoco
import numpy as np
import pytest
import trimesh

from cablecheck.build.drawn import DrawnLoad, drawn_geoms
from cablecheck.build.stages import build
from cablecheck.cli.main import main
from cablecheck.scene.load import load_scene
from cablecheck.scene.mjcf import lean_spec

_XML = """<mujoco>
  <compiler {compiler}/>
  <asset><mesh name="shell" file="shell.stl"/></asset>
  <worldbody>
    <body name="link" pos="0 0 0.3">
      <joint name="j" type="hinge" axis="0 0 1"/>
      {inertial}
      <geom name="bar" type="box" size="0.15 0.02 0.02" pos="0.15 0 0"/>
      <geom name="cover" type="mesh" mesh="shell" contype="0" conaffinity="0" rgba="0.2 0.4 0.6 1"/>
    </body>
  </worldbody>
</mujoco>"""

_SCENE = """[scene]
name = "visual-mesh"
units = "m"
duration = 0.1
settle = 0.02
mjcf = "arm.xml"

[effects]
contact = ["cable-structure"]

[[motion]]
joint = "j"
keys = [{{ t = 0.0, value = 0.0 }}, {{ t = 0.1, value = 5.0 }}]

[[cables]]
name = "hose"
radius = 0.005
start = {{ pos = [0.0, 0.2, 0.25] }}
end = {{ body = "link", pos = [0.25, 0.0, -0.03] }}
length = 0.45
"""


def _scene(tmp_path: Path, inertial: bool = True, compiler: str = "") -> Path:
    box = trimesh.creation.box(extents=[0.32, 0.06, 0.06])
    box.apply_translation([0.15, 0.0, 0.0])
    box.export(tmp_path / "shell.stl")
    (tmp_path / "arm.xml").write_text(_XML.format(
        compiler=compiler,
        inertial='<inertial pos="0.15 0 0" mass="2" diaginertia="0.01 0.01 0.01"/>' if inertial else ""))
    path = tmp_path / "scene.toml"
    path.write_text(_SCENE.format())
    return path


def test_the_visual_mesh_is_left_out_and_drawn_from_the_whole_file(tmp_path):
    path = _scene(tmp_path)
    scene = load_scene(path)
    built = build(scene)
    names = [built.model.geom(g).name for g in range(built.model.ngeom)]
    assert "cover" not in names and "bar" in names and built.model.nmesh == 0
    drawn = DrawnLoad(scene).result()
    assert [d.name for d in drawn] == ["link/cover"] and drawn[0].shape == "mesh"
    assert drawn[0].rgba == (51, 102, 153, 255)
    whole = mujoco.MjModel.from_xml_path(str(tmp_path / "arm.xml"))
    assert built.model.body("link").mass[0] == whole.body("link").mass[0] == 2.0
    # the mesh as MuJoCo holds it, placed in its body as MuJoCo places it
    g = whole.geom("cover").id
    assert np.array_equal(drawn[0].local[:3, 3], whole.geom_pos[g])
    world = drawn[0].vertices @ drawn[0].local[:3, :3].T + drawn[0].local[:3, 3] + [0, 0, 0.3]
    assert np.allclose(world.min(axis=0), [-0.01, -0.03, 0.27], atol=1e-6)
    assert np.allclose(world.max(axis=0), [0.31, 0.03, 0.33], atol=1e-6)


def test_a_visual_geom_whose_mass_counts_keeps_it(tmp_path):
    """No <inertial>: the body's mass and inertia come from its geoms, the
    visual one's too; MuJoCo gives the body that mass when it leaves the
    geom out. Under inertiafromgeom="true" it cannot, and keeps the geom:
    it is still no part."""
    _scene(tmp_path, inertial=False)
    whole = mujoco.MjModel.from_xml_path(str(tmp_path / "arm.xml"))
    lean = lean_spec(tmp_path / "arm.xml").compile()
    assert lean.ngeom == whole.ngeom - 1
    assert np.allclose(lean.body("link").mass, whole.body("link").mass, rtol=1e-12)
    assert np.allclose(lean.body("link").inertia, whole.body("link").inertia, rtol=1e-9)
    path = _scene(tmp_path, inertial=False, compiler='inertiafromgeom="true"')
    built = build(load_scene(path))
    assert built.model.geom("cover").id >= 0 and [p.name for p in built.parts] == ["link/bar"]
    assert [d.name for d in drawn_geoms(mujoco.MjModel.from_xml_path(str(tmp_path / "arm.xml")))] == ["link/cover"]


def test_a_missing_visual_mesh_stops_only_the_recording(tmp_path, capsys):
    """The checks never read a visual mesh: without its file a run that does
    not record runs; one that records is told so, exit status 2, before
    anything is written."""
    path = _scene(tmp_path)
    (tmp_path / "shell.stl").unlink()
    report = tmp_path / "r.json"
    assert main(["run", str(path), "--no-record", "--quiet", "--fail-on", "never", "--report", str(report)]) == 0
    assert report.exists()
    rrd = tmp_path / "r.rrd"
    assert main(["run", str(path), "--record", str(rrd), "--quiet", "--fail-on", "never",
                 "--report", str(tmp_path / "r2.json")]) == 2
    err = capsys.readouterr().err
    assert "scene.mjcf" in err and "shell.stl" in err and "visual" in err and "Traceback" not in err
    assert not rrd.exists() and not (tmp_path / "r2.json").exists()
    assert not list(tmp_path.glob(".r.rrd*"))


@pytest.mark.parametrize("record", [False, True])
def test_the_run_records_the_visual_geom_where_mujoco_has_it(tmp_path, record):
    path = _scene(tmp_path)
    rrd = tmp_path / "v.rrd"
    args = ["--record", str(rrd)] if record else ["--no-record"]
    assert main(["run", str(path), *args, "--quiet", "--fail-on", "never", "--report", str(tmp_path / "r.json")]) == 0
    assert rrd.exists() == record
    if record:
        from test_cli import _assert_rrd_has
        _assert_rrd_has(rrd, ["/world/visual/link/cover", "/world/visual/link"])
