"""The scale benchmark's second harness layout (cablecheck.bench.crossing): cables of
two families crossing, parts scattered clear of the routes and of each other, a
third hugging a route, and a small one run: cables on cables at and inside the
clearance, as MuJoCo finds them too."""

import numpy as np
import pytest

from cablecheck.bench.crossing import HUG_EVERY, RADIUS, crossing_scene
from cablecheck.bench.harness import bounding_radius, write_scene
from cablecheck.checker.parts import check_parts
from cablecheck.checker.partset import PartSet
from cablecheck.checker.shapes import Shape, ShapeType, segment_signed_distance
from cablecheck.scene.frames import euler_matrix
from cablecheck.scene.load import load_scene


@pytest.mark.parametrize("cables, parts", [(2, 10), (7, 90), (16, 160)])
def test_sizes_parse_parts_keep_clear_and_some_hug_a_route(tmp_path, cables, parts):
    data = crossing_scene(cables, parts, segments=12, duration=0.5)
    scene = load_scene(write_scene(data, tmp_path / "c.toml"))
    assert len(scene.cables) == cables and len(scene.parts) == parts + 1              # + the slider's plate
    trunk = [c for c in data["cables"] if c["name"].startswith("trunk/")]
    branch = [c for c in data["cables"] if c["name"].startswith("branch/")]
    assert len(trunk) == cables // 2 and len(branch) == cables - cables // 2
    # every branch crosses every trunk cable, above it
    for t in trunk:
        for b in branch:
            assert 0 < b["start"]["pos"][0] < t["end"]["pos"][0] and 0 < t["start"]["pos"][1] < b["end"]["pos"][1]
            assert b["start"]["pos"][2] > t["start"]["pos"][2]
    # on the parts' true shapes: every cable's straight route at least a millimetre beyond its
    # radius from every part, a third of the parts drawn with their bounding spheres within 6 mm
    # of one (so their surfaces within 6 mm plus their size), and no two parts meeting
    world = [p for p in data["parts"] if p.get("body", "world") == "world"]
    shapes = [Shape(ShapeType(p["shape"]), p["size"]) for p in world]
    poses = np.tile(np.eye(4), (len(world), 1, 1))
    for pose, p in zip(poses, world):
        pose[:3, :3], pose[:3, 3] = euler_matrix(p["euler"]), p["pos"]
    a = np.array([c["start"]["pos"] for c in data["cables"]], float)
    b = np.array([c["end"]["pos"] for c in data["cables"]], float)
    gap = np.array([segment_signed_distance(sh, (a - pose[:3, 3]) @ pose[:3, :3], (b - pose[:3, 3]) @ pose[:3, :3])[0]
                    .min() for sh, pose in zip(shapes, poses)]) - RADIUS
    assert gap.min() >= 1.0 - 1e-9
    size = np.array([bounding_radius(p["shape"], np.array(p["size"], float)) for p in world])
    assert (gap <= 6.0 + size).sum() >= parts // HUG_EVERY
    ps = PartSet.build([p["name"] for p in world], shapes, tolerance=0.05)
    assert check_parts(ps, ps.place(poses), 0.0) == []


def test_bad_sizes_are_refused():
    with pytest.raises(ValueError):
        crossing_scene(1, 10)


def test_a_small_crossing_harness_runs_with_cables_on_cables(tmp_path):
    """Four cables, the branches sagging onto the trunk: cable-cable records the
    checker and MuJoCo's contacts both see, and the run complete."""
    from cablecheck.run.runner import RunOptions, run_scene

    data = crossing_scene(4, 30, segments=16, duration=0.05, settle=0.3)
    scene = load_scene(write_scene(data, tmp_path / "c.toml"))
    report = run_scene(scene, RunOptions(report=tmp_path / "r.json", record=None))
    assert report["complete"]
    pairs = {(e["a"], e["b"]) for e in report["events"] if e["type"] == "cable-cable"}
    assert pairs and all(a.split("/")[0] != b.split("/")[0] for a, b in pairs)
    assert report["validation"]["agreement"] >= 0.9
