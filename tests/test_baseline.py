"""cablecheck.report.baseline and `cablecheck run --baseline`: clashes new, still present or resolved against an earlier run.

A straight cable along x (no dynamics: it stays as routed) crosses blocks
whose places along it are known: the first scene has blocks at x = 100 and
x = 300, the changed scene moves the first away (resolved), keeps the second
(present, a little deeper) and adds one at x = 200 (new). A second changed
scene moves the kept block along the cable by more than the matching reach:
then it is another clash (the old one resolved, this one new).
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from cablecheck.checker.events import Event
from cablecheck.checker.records import PairType, Severity
from cablecheck.cli.main import main
from cablecheck.report.baseline import (
    PLACE_RADII,
    Baseline,
    BaselineError,
    BaselineEvent,
    ClashStatus,
    compare,
    load_baseline,
)

BLOCK = """
[[parts]]
name = "{name}"
shape = "box"
size = [10, 10, 10]
pos = [{x}, 0, {z}]
"""

SCENE = """
[scene]
name = "{name}"
units = "{units}"
duration = 0.0

[effects]
dynamics = false

[check]
clearance = 5.0
validate = false

[[cables]]
name = "lead"
radius = 4
start = {{ pos = [0, 0, 0] }}
end = {{ pos = [400, 0, 0] }}
"""


def _scene(folder: Path, name: str, blocks: dict[str, tuple[float, float]], units: str = "mm") -> Path:
    text = SCENE.format(name=name, units="mm") + "".join(BLOCK.format(name=n, x=x, z=z) for n, (x, z) in blocks.items())
    if units == "m":        # the same scene in metres
        text = (text.replace('units = "mm"', 'units = "m"').replace("[10, 10, 10]", "[0.01, 0.01, 0.01]")
                .replace("radius = 4", "radius = 0.004").replace("clearance = 5.0", "clearance = 0.005")
                .replace("[400, 0, 0]", "[0.4, 0, 0]"))
        for n, (x, z) in blocks.items():
            text = text.replace(f"pos = [{x}, 0, {z}]", f"pos = [{x / 1000}, 0, {z / 1000}]")
    path = folder / f"{name}.toml"
    path.write_text(text)
    return path


def _run(path: Path, report: Path, *extra: str) -> dict:
    assert main(["run", str(path), "--no-record", "--quiet", "--fail-on", "never", "--report", str(report),
                 *extra]) == 0
    return json.loads(report.read_text())


@pytest.mark.parametrize("units", ["mm", "m"])
def test_a_fixed_clash_is_resolved_a_kept_one_present_and_an_added_one_new(tmp_path, units, capsys):
    before = _run(_scene(tmp_path, "before", {"jig/a": (100, 12), "jig/b": (300, 10)}), tmp_path / "before.json")
    assert {e["b"] for e in before["events"]} == {"jig/a", "jig/b"} and "baseline" not in before
    after = _run(_scene(tmp_path, "after", {"jig/a": (100, 60), "jig/b": (300, 8), "jig/c": (200, 12)}, units),
                 tmp_path / "after.json", "--baseline", str(tmp_path / "before.json"))
    status = {e["b"]: e["status"] for e in after["events"]}
    assert status == {"jig/b": "present", "jig/c": "new"}
    b = after["baseline"]
    assert (b["new"], b["present"], b["resolved"]) == (1, 1, 1) and b["report"] == str(tmp_path / "before.json")
    (gone,) = b["resolved_events"]
    assert (gone["b"], gone["status"]) == ("jig/a", "resolved")
    scale = 1.0 if units == "mm" else 1e-3          # the earlier (mm) report read in this report's units
    assert gone["min_distance"] == pytest.approx((12 - 10 - 4) * scale)     # the block's bottom 2 above the axis
    assert 90 * scale - 1e-9 <= gone["s"] <= 110 * scale + 1e-9     # a worst place under the block
    out = _run(_scene(tmp_path, "after", {"jig/a": (100, 60), "jig/b": (300, 8), "jig/c": (200, 12)}, units),
               tmp_path / "again.json", "--baseline", str(tmp_path / "before.json"))
    assert out["baseline"] == b


def test_a_clash_that_moved_along_the_cable_is_another_clash(tmp_path):
    _run(_scene(tmp_path, "before", {"jig/b": (300, 10)}), tmp_path / "before.json")
    far = 300 - PLACE_RADII * 4 - 30       # beyond the reach along the cable
    after = _run(_scene(tmp_path, "after", {"jig/b": (far, 10)}), tmp_path / "after.json",
                 "--baseline", str(tmp_path / "before.json"))
    assert [e["status"] for e in after["events"]] == ["new"] and after["baseline"]["resolved"] == 1
    near = 300 - PLACE_RADII * 4 + 30      # within it
    after = _run(_scene(tmp_path, "after", {"jig/b": (near, 10)}), tmp_path / "near.json",
                 "--baseline", str(tmp_path / "before.json"))
    assert [e["status"] for e in after["events"]] == ["present"] and after["baseline"]["resolved"] == 0


def test_each_earlier_clash_matches_one_clash_nearest_first():
    def event(s):
        return Event(PairType.CABLE_STRUCTURE, "c", "p", Severity.SOFT, "dynamic", 0.0, 1.0, 0.5, 0.001, None, s)

    base = Baseline(Path("b.json"), tuple(BaselineEvent("cable-structure", "c", "p", "soft", "dynamic", 0.001, 0.5, s)
                                          for s in (0.10, 0.30)))
    got = compare([event(0.29), event(0.31), event(0.12)], {"c": 0.004}, base)
    # 0.31 and 0.29 both reach 0.30: the nearer (0.31 by 0.01 = 0.29 by 0.01: the first listed) takes it
    assert got.status == (ClashStatus.PRESENT, ClashStatus.NEW, ClashStatus.PRESENT)
    assert got.resolved == () and got.counts() == {"new": 1, "present": 2, "resolved": 0}
    # another pair never matches
    other = compare([Event(PairType.KEEPOUT, "c", "p", Severity.SOFT, "dynamic", 0, 1, 0.5, 0.001, None, 0.1)],
                    {"c": 0.004}, base)
    assert other.status == (ClashStatus.NEW,) and len(other.resolved) == 2


@pytest.mark.parametrize("text,problem", [
    (None, "cannot be read"),
    ("not json", "is not a JSON report"),
    ('{"schema": "other"}', "is not a cablecheck report"),
    ('{"schema": "cablecheck.report/1", "units": "mm", "events": [{"type": "self"}]}', "has an event without"),
])
def test_a_file_that_is_no_report_is_bad_input(tmp_path, capsys, text, problem):
    bad = tmp_path / "bad.json"
    if text is not None:
        bad.write_text(text)
    with pytest.raises(BaselineError) as err:
        load_baseline(bad)
    assert problem in err.value.problem and err.value.path == bad
    scene = _scene(tmp_path, "s", {"jig/b": (300, 10)})
    assert main(["run", str(scene), "--no-record", "--quiet", "--report", str(tmp_path / "r.json"),
                 "--baseline", str(bad)]) == 2
    assert problem in capsys.readouterr().err and not (tmp_path / "r.json").exists()


def test_the_recording_says_each_clashs_status(tmp_path):
    from tests.test_record import _clash_rows, _rows

    _run(_scene(tmp_path, "before", {"jig/a": (100, 12), "jig/b": (300, 10)}), tmp_path / "before.json")
    after = _scene(tmp_path, "after", {"jig/a": (100, 60), "jig/b": (300, 8), "jig/c": (200, 12)})
    record = tmp_path / "after.rrd"
    assert main(["run", str(after), "--record", str(record), "--quiet", "--fail-on", "never",
                 "--report", str(tmp_path / "after.json"), "--baseline", str(tmp_path / "before.json")]) == 0
    rows = _clash_rows(record)
    assert sorted((r["a"], r["b"], r["status"]) for r in rows) == [("lead", "jig/b", "present"),
                                                                   ("lead", "jig/c", "new")]
    summary = " ".join(str(v) for r in _rows(record, "/summary") for v in r.values())
    assert "1 new, 1 still present, 1 resolved" in summary and "jig/a" in summary
