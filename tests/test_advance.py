"""Conservative advancement (checker.advance) changes no answer.

Every example scene is run with the skip rule and checking every step in
full; events and pairs must be identical, and validation compares exactly
the fully checked steps. Unit tests of the bound itself follow.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from checker.advance import Advancement
from sim.run import RunOptions, run_scene
from sim.scene import load_scene

SCENES = sorted((Path(__file__).resolve().parents[1] / "scenes").glob("*.toml"))


def _strip(rows):
    return [{k: (np.asarray(v).tolist() if isinstance(v, np.ndarray) else v) for k, v in r.items()} for r in rows]


@pytest.mark.parametrize("path", SCENES, ids=lambda p: p.stem)
def test_skipping_changes_no_answer(path: Path, tmp_path):
    scene = load_scene(path)
    fast = run_scene(scene, RunOptions(report=tmp_path / "a.json", record=None))
    full = run_scene(scene, RunOptions(report=tmp_path / "b.json", record=None, advance=False))
    assert _strip(fast["events"]) == _strip(full["events"])
    assert _strip(fast["pairs"]) == _strip(full["pairs"])
    assert fast["summary"] == full["summary"]
    for a, b in zip(fast["cables"], full["cables"]):
        assert a["max_strain"] == b["max_strain"] and a["min_bend_radius"] == b["min_bend_radius"]
    adv = fast["settings"]["advance"]
    assert full["settings"]["advance"] is None
    if adv is not None:
        assert adv["full_checks"] + adv["proven_clear_steps"] == fast["settings"]["checked_steps"]
        if "validation" in fast:
            assert fast["validation"]["compared_steps"] == adv["full_checks"]


def test_drawer_skips_steps(tmp_path):
    scene = load_scene(SCENES[[p.stem for p in SCENES].index("drawer")])
    rep = run_scene(scene, RunOptions(report=tmp_path / "a.json", record=None))
    assert rep["settings"]["advance"]["proven_clear_steps"] > 0


def _adv(gap_cable=1.0, gap_part=1.0, bound=10.0):
    pts = np.array([[0.0, 0, 0], [1, 0, 0], [2, 0, 0]])
    poses = np.tile(np.eye(4), (2, 1, 1))
    a = Advancement(np.array([0, 3]), np.array([5.0]), np.array([1.0, 1.0]), 0.5, 0.1)
    a.start(pts, poses, gap_cable, np.array([gap_part, gap_part]), (np.array([0]), np.array([1])),
            np.array([bound]))
    return a, pts, poses


def test_bound_cable_and_parts():
    a, pts, poses = _adv()
    assert a.proven_clear(pts, poses)
    moved = pts + [0.0, 0.49, 0.0]
    assert a.proven_clear(moved, poses)
    assert not a.proven_clear(pts + [0.0, 1.01, 0.0], poses)   # past the part gap 1
    # the cable's own pairs: the spread of the displacements (0 here), not
    # twice the largest (1.2 > gap_cable 1)
    assert a.proven_clear(pts + [0.0, 0.6, 0.0], poses)
    p2 = poses.copy()
    p2[0, :3, 3] = [0.3, 0, 0]
    assert a.proven_clear(moved, p2)          # |(-0.3, 0.49)| < 1 in part 0's frame
    assert not a.proven_clear(moved + [0, 0.5, 0], p2)   # |(-0.3, 0.99)| > 1
    # a part and the cable moving together: nothing moved in the part's frame
    p4 = poses.copy()
    p4[:, :3, 3] = [0.0, 5.0, 0.0]
    a2, _, _ = _adv(bound=100.0)
    assert a2.proven_clear(pts + [0.0, 5.0, 0.0], p4)
    assert not a2.proven_clear(pts, p4)
    c, s = np.cos(0.2), np.sin(0.2)
    p3 = poses.copy()
    p3[1, :3, :3] = [[c, -s, 0], [s, c, 0], [0, 0, 1]]   # ||dR||_F ~ 0.28 per unit radius
    assert a.proven_clear(pts, p3)
    p3[1, :3, 3] = [0.8, 0.4, 0]
    assert not a.proven_clear(pts, p3)


def test_gaps_per_centre():
    """Candidates give each body centre its own gap: a centre far from the
    part may move further than the part's (smallest) gap."""
    pts = np.array([[0.0, 0, 0], [1, 0, 0], [2, 0, 0], [3, 0, 0]])
    poses = np.tile(np.eye(4), (1, 1, 1))
    a = Advancement(np.array([0, 4]), np.array([5.0]), np.array([1.0]), 0.5, 1.0)
    # one candidate at s = 0.25 (element 0: centres 0 and 1), 0.2 past the clearance
    a.start(pts, poses, 1.0, np.array([0.2]), (np.zeros(0, int), np.zeros(0, int)), np.zeros(0),
            (np.array([0]), np.array([0.25]), np.array([0]), np.array([0.2])), 3.0)
    far = pts.copy()
    far[3] += [0.0, 0.0, 0.9]                 # centre 3: horizon 3; spread 0.9 < 1
    assert a.proven_clear(far, poses)
    near = pts.copy()
    near[1] += [0.0, 0.0, 0.21]               # centre 1 borders the candidate's element
    assert not a.proven_clear(near, poses)
    far[3] += [0.0, 0.0, 0.2]                 # spread 1.1 > gap_cable 1
    assert not a.proven_clear(far, poses)
    far[3] -= [0.0, 0.0, 0.2]
    far[0] -= [0.0, 0.0, 0.2]                 # spread 1.1 again, and centre 0 past 0.2
    assert not a.proven_clear(far, poses)


def test_bound_stretch_and_gaps_at_or_below_zero():
    a, pts, poses = _adv()
    stretched = pts.copy()
    stretched[2, 0] += 0.11                  # element lengths change by 0.11 > 0.1
    assert not a.proven_clear(stretched, poses)
    a, pts, poses = _adv(gap_cable=0.0)
    assert not a.proven_clear(pts, poses)
    a, pts, poses = _adv(bound=0.5)          # part pair at the clearance
    assert not a.proven_clear(pts, poses)


def test_attached_part_moves_while_far_part_approaches(tmp_path):
    """The drawer (carrying the cable's end) moves out while a probe on its
    own body comes down onto the cable's middle: per-centre gaps in each
    part's own frame must still catch the probe."""
    text = (SCENES[[p.stem for p in SCENES].index("drawer")]).read_text()
    text = text.replace("duration = 4.0", "duration = 1.5") + '''
[[bodies]]
name = "probe"
pos = [0, 0, 0]

[[parts]]
name = "probe/block"
body = "probe"
shape = "box"
size = [20, 20, 20]
pos = [130, 0, 200]

[[motion]]
body = "probe"
keys = [ { t = 0.0, pos = [0, 0, 0] },
         { t = 1.5, pos = [0, 0, -125] } ]
'''
    path = tmp_path / "probe.toml"
    path.write_text(text)
    scene = load_scene(path)
    fast = run_scene(scene, RunOptions(report=tmp_path / "a.json", record=None))
    full = run_scene(scene, RunOptions(report=tmp_path / "b.json", record=None, advance=False))
    assert any(e["b"] == "probe/block" for e in _strip(full["events"]))
    assert _strip(fast["events"]) == _strip(full["events"])
    assert _strip(fast["pairs"]) == _strip(full["pairs"])
    assert fast["settings"]["advance"]["proven_clear_steps"] > 0
