"""End to end: `cablecheck sweep` (table, JSON, exit codes) and part-part events in `cablecheck run`."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from cablecheck.cli.main import main

SCENE = """
[scene]
name = "rack"
units = "mm"
duration = 0.3

[effects]
dynamics = false

[check]
clearance = 2.0
validate = false

[[bodies]]
name = "carriage"

[[parts]]
name = "tool/body"
shape = "box"
size = [50, 50, 50]

[[parts]]
name = "frame/post"
shape = "box"
size = [20, 20, 200]
pos = [300, 0, 0]

[[parts]]
name = "frame/plate"
shape = "box"
size = [0.5, 40, 100]
pos = [150, 0, 0]

[[parts]]
name = "frame/ball"
shape = "sphere"
size = [40]
pos = [600, 0, 0]

[[parts]]
name = "frame/side"
shape = "box"
size = [200, 10, 50]
pos = [250, 60, 0]

[[parts]]
name = "carriage/block"
body = "carriage"
shape = "box"
size = [20, 20, 20]
pos = [0, 0, 300]

[[parts]]
name = "zone"
shape = "box"
size = [30, 30, 30]
pos = [100, 0, 400]
keepout = true

[[motion]]
body = "carriage"
keys = [ { t = 0.0, pos = [0, 0, 0] }, { t = 0.3, pos = [150, 0, 0] } ]
"""


@pytest.fixture
def scene(tmp_path: Path) -> Path:
    path = tmp_path / "rack.toml"
    path.write_text(SCENE)
    return path


def test_sweep_table_json_and_exit_status(scene: Path, tmp_path: Path, capsys):
    out = tmp_path / "sweep.json"
    code = main(["sweep", str(scene), "--part", "tool", "--direction", "2,0,0", "--distance", "1000",
                 "--report", str(out)])
    assert code == 1
    r = json.loads(out.read_text())
    assert r["schema"] == "cablecheck.sweep/1" and r["scene"] == "rack" and r["units"] == "mm"
    assert r["part"] == "tool" and r["direction"] == [1.0, 0.0, 0.0] and r["distance"] == 1000
    got = {h["part"]: h["distance"] for h in r["hits"]}
    # the 1 mm plate at x = 150 (face at 149.5), the post (face at 280), the ball (face at 560)
    assert got["frame/plate"] == pytest.approx(99.5, abs=1e-9)
    assert got["frame/post"] == pytest.approx(230.0, abs=1e-9)
    assert got["frame/ball"] == pytest.approx(510.0, abs=r["precision"])
    # frame/side (y 50..70) is flush with tool's +y face (y = 50): it slides past
    assert "frame/side" not in got
    assert [h["part"] for h in r["hits"]] == ["frame/plate", "frame/post", "frame/ball"]
    assert r["overlapping"] == [] and r["precision"] == pytest.approx(0.5)
    assert all(len(h["where"]) == 3 for h in r["hits"])
    text = capsys.readouterr().out
    assert "frame/post" in text and "230" in text


def test_sweep_only_and_start_overlap(scene: Path, tmp_path: Path):
    out = tmp_path / "s.json"
    assert main(["sweep", str(scene), "--part", "tool/body", "--direction", "1,0,0", "--distance", "1000",
                 "--only", "frame/ball", "--report", str(out), "--quiet"]) == 1
    assert [h["part"] for h in json.loads(out.read_text())["hits"]] == ["frame/ball"]
    assert main(["sweep", str(scene), "--part", "tool", "--direction=-1,0,0", "--distance", "10",
                 "--report", str(out), "--quiet"]) == 0
    assert json.loads(out.read_text())["hits"] == []


@pytest.mark.parametrize("args, option", [
    (["--part", "nope", "--direction", "1,0,0", "--distance", "5"], "--part"),
    (["--part", "tool", "--direction", "0,0,0", "--distance", "5"], "--direction"),
    (["--part", "tool", "--direction", "1,0", "--distance", "5"], "--direction"),
    (["--part", "tool", "--direction", "1,0,0", "--distance", "-5"], "--distance"),
    (["--part", "tool", "--direction", "1,0,0", "--distance", "5", "--only", "nope"], "--only"),
])
def test_sweep_bad_input_exits_2_naming_the_option(scene: Path, tmp_path: Path, capsys, args, option):
    with pytest.raises(SystemExit) as e:
        code = main(["sweep", str(scene), *args, "--report", str(tmp_path / "x.json")])
        raise SystemExit(code)
    assert e.value.code == 2
    err = capsys.readouterr().err
    assert option in err and "Traceback" not in err


def test_run_reports_part_part_and_keepout_events(scene: Path, tmp_path: Path):
    report = tmp_path / "run.json"
    # the carriage block (z = 280..320) passes under the zone (370..430): clear;
    # tool/body and frame/side touch flush: contact, not interference
    code = main(["run", str(scene), "--no-record", "--report", str(report), "--quiet"])
    r = json.loads(report.read_text())
    kinds = {(e["type"], e["a"], e["b"]) for e in r["events"]}
    assert kinds == set() and code == 0
    # move the zone down into the block's path: a dynamic keepout event
    text = scene.read_text().replace("pos = [100, 0, 400]", "pos = [100, 0, 340]")
    scene.write_text(text)
    code = main(["run", str(scene), "--no-record", "--report", str(report), "--quiet"])
    r = json.loads(report.read_text())
    ev = [e for e in r["events"] if e["type"] == "keepout"]
    assert code == 1 and len(ev) == 1
    assert (ev[0]["a"], ev[0]["b"], ev[0]["severity"], ev[0]["phase"]) == \
        ("carriage/block", "zone", "hard", "dynamic")
    # only the carriage's assembly against the rest: same answer; another assembly: none
    code = main(["run", str(scene), "--no-record", "--report", str(report), "--quiet", "--only", "tool"])
    assert code == 0 and json.loads(report.read_text())["events"] == []
