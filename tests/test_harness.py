"""The scale benchmark's harness scene: a valid scene of the asked size, parts apart, a few
pairs within the clearance, and a run of a small one."""

import numpy as np
import pytest

from cablecheck.bench.harness import CLEARANCE, RADIUS, harness_scene, write_scene
from cablecheck.checker.parts import check_parts
from cablecheck.checker.partset import PartSet
from cablecheck.checker.shapes import Shape, ShapeType
from cablecheck.scene.load import load_scene


@pytest.mark.parametrize("cables, parts", [(1, 10), (5, 60), (9, 150)])
def test_sizes_parse_and_parts_keep_apart(tmp_path, cables, parts):
    data = harness_scene(cables, parts, segments=12, duration=0.5)
    scene = load_scene(write_scene(data, tmp_path / "h.toml"))
    assert len(scene.cables) == cables and len(scene.parts) == parts + 1          # + the carriage plate
    assert all(c.segments == 12 for c in scene.cables)
    # on their true shapes, the parts never overlap; the near pairs are placed at half the clearance
    names = [p["name"] for p in data["parts"]]
    shapes = [Shape(ShapeType(p["shape"]), p["size"]) for p in data["parts"]]
    poses = []
    for p in data["parts"]:
        t = np.eye(4)
        a, b, c = np.radians(p.get("euler", [0, 0, 0]))
        ca, sa, cb, sb, cc, sc = np.cos(a), np.sin(a), np.cos(b), np.sin(b), np.cos(c), np.sin(c)
        t[:3, :3] = (np.array([[1, 0, 0], [0, ca, -sa], [0, sa, ca]]) @ np.array([[cb, 0, sb], [0, 1, 0], [-sb, 0, cb]])
                     @ np.array([[cc, -sc, 0], [sc, cc, 0], [0, 0, 1]]))
        t[:3, 3] = p.get("pos", [0, 0, 0])
        poses.append(t)
    ps = PartSet.build(names, shapes, tolerance=0.05)
    recs = check_parts(ps, ps.place(np.array(poses)), CLEARANCE)
    assert all(r.severity.value == "soft" for r in recs)
    for r in recs:
        assert r.min_distance == pytest.approx(0.5 * CLEARANCE, abs=1e-9)


def test_cables_have_room_and_some_parts_come_near():
    data = harness_scene(16, 400)
    spheres = [p for p in data["parts"] if p["shape"] == "sphere" and p["euler"] == [0.0, 0.0, 0.0]]
    assert len(spheres) >= 400 // 50
    for c in data["cables"]:
        assert c["radius"] == RADIUS and c["end"]["body"] == "carriage"


def test_bad_sizes_are_refused():
    with pytest.raises(ValueError):
        harness_scene(0, 10)


def test_a_small_harness_runs(tmp_path):
    from cablecheck.run.runner import RunOptions, run_scene

    data = harness_scene(2, 10, segments=10, duration=0.02)
    scene = load_scene(write_scene(data, tmp_path / "h.toml"))
    report = run_scene(scene, RunOptions(report=tmp_path / "r.json", record=None))
    assert report["complete"] and report["timing"]["sim_s"] > 0 and report["settings"]["steps"] > 0


def test_settling_brings_the_cables_to_rest(tmp_path):
    """The routes droop between via points that hold nothing: unsettled,
    the cables fall into their sag at t = 0; after SETTLE seconds of
    settling they are at rest (the carriage held still meanwhile)."""
    from cablecheck.bench.harness import SETTLE
    from cablecheck.build.stages import build
    from cablecheck.run.loop import Simulation

    def moved(settle: float) -> float:
        data = harness_scene(4, 40, segments=16, duration=0.2, settle=settle)
        data["motion"] = []                                     # the carriage still: the cables' own motion
        built = build(load_scene(write_scene(data, tmp_path / f"h{settle}.toml")), detect=False)
        sim = Simulation(built)
        sim.reset()
        sim.settle()
        states = sim.steps(contacts=False)
        first = np.concatenate(next(states).cables)
        for _ in range(10):                                     # 20 ms
            last = next(states)
        return float(np.linalg.norm(np.concatenate(last.cables) - first, axis=1).max())

    assert moved(0.0) > 5e-3 and moved(SETTLE) < 1e-4           # m: falling, then still (under 0.1 mm)
