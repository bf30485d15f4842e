"""Checking states a batch at a time (cablecheck.run.stepcheck) gives the answers of
checking them one at a time."""

from __future__ import annotations

import dataclasses

from pathlib import Path

import numpy as np
import pytest

import cablecheck.run.runner
from cablecheck.run.runner import RunOptions, run_scene
from cablecheck.scene.load import load_scene

SCENES = Path(__file__).resolve().parents[1] / "scenes"


def _comparable(rep: dict) -> dict:
    out = {k: rep[k] for k in ("events", "pairs", "summary")}
    out["cables"] = [(c["max_strain"], c["min_bend_radius"], np.asarray(c["final_points"]).tolist())
                     for c in rep["cables"]]
    out["advance"] = rep["settings"]["advance"]
    out["validation"] = {k: v for k, v in rep.get("validation", {}).items()}
    out["steps"] = (rep["settings"]["steps"], rep["settings"]["checked_steps"])
    return {k: (np.asarray(v).tolist() if isinstance(v, np.ndarray) else v) for k, v in out.items()}


def _strip(x):
    if isinstance(x, dict):
        return {k: _strip(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_strip(v) for v in x]
    return x.tolist() if isinstance(x, np.ndarray) else x


@pytest.mark.parametrize("name", ["drawer_pinch", "keepout_bolt"])
def test_batch_size_changes_no_answer(name: str, tmp_path, monkeypatch):
    """Any batch size, the same answers; with the promotion budget of these
    small scenes' own size (no floor) the batches hold full checks too."""
    import cablecheck.run.stepcheck
    monkeypatch.setattr(cablecheck.run.stepcheck, "PROMOTE_MIN", 0)
    scene = load_scene(SCENES / f"{name}.toml")
    reports = []
    # fixed batches of 1 and 7 states, then the run's own (BATCH, growing to BATCH_MAX)
    for size, most in ((1, 1), (7, 7), (cablecheck.run.runner.BATCH, cablecheck.run.runner.BATCH_MAX)):
        monkeypatch.setattr(cablecheck.run.runner, "BATCH", size)
        monkeypatch.setattr(cablecheck.run.runner, "BATCH_MAX", most)
        rep = run_scene(scene, RunOptions(report=tmp_path / f"{size}-{most}.json", record=None))
        reports.append(_strip(_comparable(rep)))
    adv = reports[0]["advance"]
    assert adv["full_checks"] > 1 and adv["proven_clear_steps"] > 0   # both kinds in the batches
    assert reports[0] == reports[1] == reports[2]


def test_active_part_pairs_batch_size_changes_no_answer(tmp_path, monkeypatch):
    """The door's hinge pin pair is checked on its own for whole batches of
    states at once (PartChecker.check_pairs_many): any batch size, the same
    answers, allowed pairs included."""
    scene = dataclasses.replace(load_scene(Path(__file__).resolve().parent / "scenes" / "door.toml"),
                                duration=0.5)          # half its swing: CI's time
    reports = []
    for size, most in ((1, 1), (7, 7), (cablecheck.run.runner.BATCH, cablecheck.run.runner.BATCH_MAX)):
        monkeypatch.setattr(cablecheck.run.runner, "BATCH", size)
        monkeypatch.setattr(cablecheck.run.runner, "BATCH_MAX", most)
        rep = run_scene(scene, RunOptions(report=tmp_path / f"{size}-{most}.json", record=None))
        reports.append(_strip({**_comparable(rep), "allowed": rep["allowed"]}))
    assert reports[0]["advance"]["proven_clear_steps"] > reports[0]["advance"]["full_checks"]
    assert reports[0]["allowed"] and reports[0] == reports[1] == reports[2]


def test_neighbour_links_in_the_kinematic_tree():
    """arm.xml: pedestal -(base_yaw)- shoulder -(shoulder_pitch)- upper_arm
    -(elbow)- forearm = tool (welded). Never through the world body."""
    import mujoco

    from cablecheck.run.stepcheck import neighbour_bodies
    m = mujoco.MjModel.from_xml_path(str(SCENES / "arm.xml"))
    name = lambda ids: {m.body(i).name for i in ids}      # noqa: E731
    upper = m.body("upper_arm").id
    assert name(neighbour_bodies(m, upper, 0)) == {"upper_arm"}
    assert name(neighbour_bodies(m, upper, 1)) == {"shoulder", "upper_arm", "forearm", "tool"}
    assert name(neighbour_bodies(m, upper, 2)) == {"pedestal", "shoulder", "upper_arm", "forearm", "tool"}
    assert name(neighbour_bodies(m, m.body("pedestal").id, 5)) == {"pedestal", "shoulder", "upper_arm",
                                                                     "forearm", "tool"}
    assert neighbour_bodies(m, 0, 3) == [0]


def test_attach_links_excuse_the_clamp_links_neighbours(tmp_path):
    """With attach_links = 1 the clip on the upper arm may also excuse the
    forearm's (and the tool flange welded to it) and the shoulder's parts
    over its window, never the floor (on the world body); with 0 only the
    upper arm's. (A clearance of 2 m puts every part within reach of the
    held point: the links decide here, not the distance.)"""
    from cablecheck.build.stages import build
    from cablecheck.run.stepcheck import attachment_exclusions
    text = (SCENES / "arm.toml").read_text()
    (tmp_path / "arm.xml").write_text((SCENES / "arm.xml").read_text())
    windows = []
    for links in (0, 1):
        f = tmp_path / f"arm{links}.toml"
        f.write_text(text.replace("[check]\n", f"[check]\nattach_links = {links}\n")
                     .replace("clearance = 0.005", "clearance = 2.0"))
        built = build(load_scene(f), detect=False)
        body = {p.name: p.body for p in built.parts}
        clip = next(a for a in built.cables[0].attachments if a.body == "upper_arm")
        s = built.cables[0].rest_s[clip.vertex]
        windows.append({body[e.part] for e in attachment_exclusions(built) if e.s_min <= s <= e.s_max})
    assert windows[0] == {"upper_arm"}
    assert windows[1] == {"upper_arm", "forearm", "tool", "shoulder"}


def test_a_long_cable_on_a_floor_is_checked_in_passes_of_bounded_points(tmp_path, monkeypatch):
    """A 15 m wire of 0.5 mm radius lying on a floor keeps its every discrete
    point (15,000 a state) active: the states proven clear are evaluated in
    passes of at most CHUNK_POINTS points, the same records however small
    the passes (here 1, 2 and the default 66 states a pass)."""
    import cablecheck.run.stepcheck

    path = tmp_path / "wire.toml"
    path.write_text("""
[scene]
name = "wire"
units = "m"
duration = 0.1
settle = 0.2

[effects]
contact = ["cable-structure"]

[[parts]]
name = "floor"
shape = "plane"

[[cables]]
name = "wire"
radius = 0.0005
start = { pos = [0, 0, 0.002] }
end = { pos = [15, 0, 0.002] }
""")
    scene = load_scene(path)
    reports = []
    for chunk in (15_000, 30_000, cablecheck.run.stepcheck.CHUNK_POINTS):
        monkeypatch.setattr(cablecheck.run.stepcheck, "CHUNK_POINTS", chunk)
        rep = run_scene(scene, RunOptions(report=tmp_path / f"{chunk}.json", record=None))
        reports.append(_strip(_comparable(rep)))
    assert reports[0]["advance"]["proven_clear_steps"] > 0 and reports[0]["events"]
    assert reports[0] == reports[1] == reports[2]


def test_batches_shrink_towards_the_runs_end():
    """Twice the last up to the most, never more than half of what is
    still to come, never under the least: the run's last batch is short."""
    from cablecheck.run.stepcheck import next_batch
    assert next_batch(32, 10_000) == 64 and next_batch(256, 10_000) == 256
    assert next_batch(256, 300) == 150 and next_batch(150, 150) == 75 and next_batch(75, 75) == 38
    assert next_batch(38, 37) == 32 and next_batch(32, 0) == 32
    assert next_batch(256, 300, every=3) == 50      # 100 states still to come
    assert next_batch(7, 10_000, least=7, most=7) == 7
    # the run's own sizes, state by state: the last batch after 2,200 steps is at most a quarter of the one before
    size, left, sizes = 32, 2200, []
    while left > 0:
        take = min(size, left)
        sizes.append(take)
        left -= take
        size = next_batch(size, left)
    assert sum(sizes) == 2200 and max(sizes) == 256 and sizes[-1] <= 32


def _turntable(tmp_path: Path, allow: bool) -> dict:
    """A ring (a mesh) turning +270 degrees and back on a cylinder it sits 3 mm
    into, a cable clamped clear of both; the pair allowed or not."""
    import trimesh

    trimesh.creation.annulus(r_min=0.03, r_max=0.08, height=0.02, sections=24).export(tmp_path / "ring.stl")
    data = {
        "scene": {"name": "turntable", "units": "m", "duration": 0.6},
        "effects": {"dynamics": False, "contact": ["cable-structure"]},
        "check": {"clearance": 0.003},
        "bodies": [{"name": "table", "pos": [0.0, 0.0, 0.057]}],
        "parts": [{"name": "machine/base", "shape": "cylinder", "size": [0.1, 0.05]},
                  {"name": "table/ring", "body": "table", "shape": "mesh", "file": "ring.stl"}],
        "cables": [{"name": "c", "radius": 0.004, "start": {"pos": [0.3, 0.0, 0.2]},
                    "end": {"pos": [0.3, 0.3, 0.2]}}],
        "motion": [{"body": "table", "keys": [{"t": 0.0, "euler": [0, 0, 0]}, {"t": 0.3, "euler": [0, 0, 270]},
                                             {"t": 0.6, "euler": [0, 0, 0]}]}],
    }
    if allow:
        data["allow"] = [{"a": "table", "b": "machine", "reason": "the table turns on its bearing"}]
    return data


def test_an_allowed_pair_turning_in_its_bearing_is_measured_at_the_sampled_states(tmp_path, monkeypatch):
    """An allowed part-part pair is measured at the first checked state of
    each ALLOWED_INTERVAL alone, in full checks and proven-clear states
    alike: the same answers with the skip rule or without it, its worst
    the ring's 3 mm in the cylinder (the depth at every angle), the report
    saying how often it was measured. Not allowed, the same pair is an
    event measured at every state (its worst the same)."""
    from cablecheck.checker.parts import PartChecker
    from cablecheck.run.stepcheck import ALLOWED_INTERVAL
    from cablecheck.scene.load import parse_scene

    asked = []
    many = PartChecker.check_pairs_many

    def counted(self, poses, i, j):
        if any("table/ring" in (self.parts.names[a], self.parts.names[b]) for a, b in zip(i, j)):
            asked.append(len(poses))
        return many(self, poses, i, j)

    monkeypatch.setattr(PartChecker, "check_pairs_many", counted)
    scene = parse_scene(_turntable(tmp_path, allow=True), tmp_path / "t.toml")
    reports = [run_scene(scene, RunOptions(report=tmp_path / f"{adv}.json", record=None, advance=adv))
               for adv in (True, False)]
    skip, full = reports
    for key in ("events", "pairs", "allowed", "summary"):
        assert _strip(skip[key]) == _strip(full[key]), key
    (pair,) = skip["allowed"]
    assert (pair["type"], {pair["a"], pair["b"]}) == ("part-part", {"table/ring", "machine/base"})
    assert pair["min_distance"] == pytest.approx(-0.003, abs=1e-7) and pair["sampled_every_s"] == ALLOWED_INTERVAL
    samples = int(np.floor(0.6 / ALLOWED_INTERVAL)) + 1
    assert skip["settings"]["advance"]["proven_clear_steps"] > 0
    assert 0 < sum(asked) <= samples          # the proven-clear states measured it at the samples alone
    not_allowed = run_scene(parse_scene(_turntable(tmp_path, allow=False), tmp_path / "t.toml"),
                            RunOptions(report=tmp_path / "event.json", record=None))
    (event,) = [e for e in not_allowed["events"] if e["type"] == "part-part"]
    assert event["t_start"] == 0.0 and event["t_end"] == pytest.approx(0.6)
    assert event["min_distance"] == pytest.approx(pair["min_distance"], abs=1e-9)
