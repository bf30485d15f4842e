"""Static checks without MuJoCo: which scenes need a model, and the built scene without one
equals a MuJoCo build's (parts, cables, bodies' tree, pair filters) and runs to the same report."""

from __future__ import annotations

import json
from pathlib import Path

import mujoco
import numpy as np
import pytest
import trimesh

import cablecheck.run.runner
from cablecheck.build.built import BodyTree
from cablecheck.build.stages import build
from cablecheck.build.static import build_static, needs_model
from cablecheck.run.runner import RunOptions, run_scene
from cablecheck.run.stepcheck import attachment_exclusions, part_pairs_skipped
from cablecheck.scene.load import parse_scene

SHAPES = {"box": 3, "sphere": 1, "cylinder": 2, "capsule": 2, "ellipsoid": 3}


def static_scene(seed: int, far: float = 0.0, parts: int = 12) -> dict:
    """World parts and parts on two scripted bodies (interleaved in the file),
    rotated every way, `far` metres from the origin; a cable held by a clamp,
    a clip and a pin, with slack; the bodies move and turn."""
    rng = np.random.default_rng(seed)
    off = np.array([far, -far, 0.5 * far])
    rows = []
    for k in range(parts):
        shape = list(SHAPES)[k % len(SHAPES)]
        body = ["world", "arm", "world", "carriage"][k % 4]
        pos = rng.uniform(-0.3, 0.3, 3) + (off if body == "world" else 0.0)
        rows.append({"name": f"cell/p{k}", "shape": shape, "body": body,
                     "size": rng.uniform(0.01, 0.04, SHAPES[shape]).tolist(), "pos": pos.tolist(),
                     "euler": rng.uniform(-180.0, 180.0, 3).tolist(), "keepout": bool(k == 5)})
    return {
        "scene": {"name": f"static{seed}", "units": "m", "duration": 0.06, "timestep": 0.01, "settle": 0.0},
        "effects": {"dynamics": False, "contact": []},
        "check": {"validate": False, "clearance": 0.005},
        "bodies": [{"name": "arm", "pos": (off + [0.1, 0.0, 0.2]).tolist(), "euler": [10.0, 20.0, 30.0]},
                   {"name": "carriage", "pos": (off + [0.6, 0.0, 0.0]).tolist()}],
        "parts": rows,
        "cables": [{"name": "lead", "radius": 0.004, "length": 0.8, "segments": 16,
                    "start": {"pos": (off + [0.0, 0.0, 0.1]).tolist()},
                    "clips": [{"body": "arm", "pos": [0.2, 0.0, -0.1], "hold": "pin"}],
                    "end": {"body": "carriage", "pos": [0.0, 0.0, 0.1]}}],
        "motion": [{"body": "arm", "keys": [{"t": 0.0, "pos": (off + [0.1, 0.0, 0.2]).tolist(), "euler": [10, 20, 30]},
                                            {"t": 0.06, "pos": (off + [0.15, 0.05, 0.2]).tolist(),
                                             "euler": [40, -20, 90]}]},
                   {"body": "carriage", "keys": [{"t": 0.0, "pos": (off + [0.6, 0.0, 0.0]).tolist()},
                                                 {"t": 0.06, "pos": (off + [0.6, 0.0, 0.05]).tolist()}]}],
    }


def test_needs_model_for_dynamics_validation_or_an_mjcf_model(tmp_path):
    data = static_scene(0)
    assert not needs_model(parse_scene(data, tmp_path / "s.toml"))
    for key, table, value in (("dynamics", "effects", True), ("validate", "check", True)):
        changed = json.loads(json.dumps(data))
        changed[table][key] = value
        assert needs_model(parse_scene(changed, tmp_path / "s.toml"))
    arm = Path(__file__).resolve().parents[1] / "scenes" / "arm.xml"
    changed = dict(data, scene=dict(data["scene"], mjcf=str(arm)), bodies=[], motion=[],
                   parts=[p for p in data["parts"] if p["body"] == "world"])
    changed["cables"] = [dict(data["cables"][0], clips=[], end={"pos": [0.6, 0.0, 0.1]})]
    assert needs_model(parse_scene(changed, tmp_path / "s.toml"))
    with pytest.raises(ValueError):
        build_static(parse_scene(changed, tmp_path / "s.toml"))


@pytest.mark.parametrize("seed, far", [(0, 0.0), (1, 2.2e4), (2, 3.0)])
def test_static_build_is_the_mujoco_builds_view(tmp_path, seed, far):
    """Parts (order, geom ids, MuJoCo's sizes), cables, bodies and the pair filters
    read from the tree equal a MuJoCo build's, far from the origin too."""
    scene = parse_scene(static_scene(seed, far), tmp_path / "s.toml")
    mj, st = build(scene, detect=False), build_static(scene)
    assert isinstance(st.model, BodyTree) and st.detect is None
    for a, b in zip(mj.parts, st.parts, strict=True):
        assert (a.name, a.geom_id, a.body, a.shape, a.keepout) == (b.name, b.geom_id, b.body, b.shape, b.keepout)
        assert np.array_equal(a.size, b.size)
    for a, b in zip(mj.cables, st.cables, strict=True):
        assert (a.name, a.radius, a.flex_id, a.vert_adr, a.count, a.length, a.element_length, a.attachments,
                a.min_bend_radius, a.elements) == \
               (b.name, b.radius, b.flex_id, b.vert_adr, b.count, b.length, b.element_length, b.attachments,
                b.min_bend_radius, b.elements)
        assert np.array_equal(a.routed, b.routed) and np.array_equal(a.rest_s, b.rest_s)
    assert mj.body_ids == st.body_ids and np.array_equal(mj.origin, st.origin)
    assert mj.substeps == st.substeps and mj.warnings == st.warnings == ()
    m, tree = mj.model, st.model
    bodies = [mj.body_ids[n] for n in tree.body_names]
    assert np.array_equal(m.body_parentid[bodies], tree.body_parentid)
    assert np.array_equal(m.body_weldid[bodies], tree.body_weldid)
    assert np.array_equal(m.body_jntnum[bodies], tree.body_jntnum)
    assert np.array_equal(m.geom_bodyid[[p.geom_id for p in mj.parts]], tree.geom_bodyid)
    for name, (qa, da) in st.free.items():
        j = int(m.body_jntadr[mj.body_ids[name]])
        assert (int(m.jnt_qposadr[j]), int(m.jnt_dofadr[j])) == (qa, da)
        assert m.joint(j).name == tree.joint(tree.body_names.index(name) - 1).name
    assert np.array_equal(part_pairs_skipped(mj), part_pairs_skipped(st))
    assert attachment_exclusions(mj) == attachment_exclusions(st)


def _report(path: Path) -> dict:
    report = json.loads(path.read_text())
    report.pop("timing")
    return report


def _forbid_models(monkeypatch) -> None:
    """Every way into a MuJoCo model raises."""
    def refuse(*args, **kwargs):
        raise AssertionError("a MuJoCo model was built for a static check")
    for owner, name in ((mujoco.MjSpec, "compile"), (mujoco.MjSpec, "from_string"), (mujoco.MjSpec, "from_file"),
                        (mujoco.MjModel, "from_xml_string"), (mujoco.MjModel, "from_xml_path")):
        monkeypatch.setattr(owner, name, refuse)


@pytest.mark.parametrize("seed", [0, 1])
def test_static_run_compiles_nothing_and_reports_as_before(tmp_path, monkeypatch, seed):
    """The same report (apart from timing), byte for byte, as the run that builds MuJoCo's model."""
    data = static_scene(seed, far=3.0)
    scene = parse_scene(data, tmp_path / "s.toml")
    with monkeypatch.context() as patch:
        patch.setattr(cablecheck.run.runner, "needs_model", lambda s: True)       # the run as it was: a MuJoCo build
        run_scene(scene, RunOptions(report=tmp_path / "mujoco.json", record=None))
    with monkeypatch.context() as patch:
        _forbid_models(patch)
        run_scene(scene, RunOptions(report=tmp_path / "static.json", record=tmp_path / "static.rrd"))
    before, after = _report(tmp_path / "mujoco.json"), _report(tmp_path / "static.json")
    assert before["events"] or before["pairs"]         # the scene has something to report
    after["recording"] = before["recording"]
    assert json.dumps(after, sort_keys=True) == json.dumps(before, sort_keys=True)
    assert (tmp_path / "static.rrd").stat().st_size > 0


def test_static_mesh_part_is_the_files_mesh_in_double_precision(tmp_path, monkeypatch):
    """A mesh part keeps its file's vertices in its own frame; distances to it
    agree with a MuJoCo build's (float32, recentred vertices) to its rounding."""
    mesh = trimesh.creation.box(extents=[0.04, 0.3, 0.3])
    mesh.apply_translation([0.011, 0.02, 0.003])
    mesh.export(tmp_path / "plate.stl")
    data = {
        "scene": {"name": "plate", "units": "m", "duration": 0.0, "settle": 0.0},
        "effects": {"dynamics": False, "contact": []},
        "check": {"validate": False, "clearance": 0.004},
        "parts": [{"name": "plate", "shape": "mesh", "file": "plate.stl", "pos": [0.3, 0.0, 0.0],
                   "euler": [0.0, 0.0, 15.0]}],
        "cables": [{"name": "lead", "radius": 0.004, "segments": 20,
                    "start": {"pos": [0.0, 0.0, 0.0]}, "end": {"pos": [0.6, 0.0, 0.0]}}],
    }
    scene = parse_scene(data, tmp_path / "s.toml")
    st = build_static(scene)
    rows = lambda v: np.unique(np.round(np.asarray(v, float), 6), axis=0)   # STL: its own order, float32
    assert np.array_equal(rows(st.parts[0].vertices), rows(mesh.vertices))
    with monkeypatch.context() as patch:
        patch.setattr(cablecheck.run.runner, "needs_model", lambda s: True)
        run_scene(scene, RunOptions(report=tmp_path / "mujoco.json", record=None))
    with monkeypatch.context() as patch:
        _forbid_models(patch)
        run_scene(scene, RunOptions(report=tmp_path / "static.json", record=None))
    before, after = _report(tmp_path / "mujoco.json"), _report(tmp_path / "static.json")
    key = lambda r: [(e["type"], e["a"], e["b"], e["severity"]) for e in r["events"]]
    assert key(before) == key(after) == [("cable-structure", "lead", "plate", "hard")]
    assert after["events"][0]["min_distance"] == pytest.approx(before["events"][0]["min_distance"], abs=1e-7)
