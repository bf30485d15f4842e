"""Attachment windows excuse only what an end is fastened to, and say what they excused
(cablecheck.run.stepcheck.attachment_exclusions, cablecheck.checker.interference.excused, the report's `excused`).

A straight cable along x (no dynamics: it stays as routed) starts clamped on
the world inside a clamp box; a second box lies beside its first elements,
inside the start's window but farther from the held point than the cable
radius plus the clearance. Every distance below is a box's face distance
to the straight centreline, less the radius, worked out by hand:

- clamp: half-size 5 along x, centred on the start: the centreline's
  deepest point is the start itself, 5 inside the x faces, so -5 - r;
  the window (30 of rest arc length: 5 radii past the clamp's short edge,
  to the next vertex) holds every element within the clearance of it;
- beside: its face at y = BESIDE_Y over x in [12, 20]: BESIDE_Y - r;
  from the held points (x = 0 and the clamp's short edge, x < 1.2) it is
  at least sqrt(10.8^2 + BESIDE_Y^2) > r + clearance.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from cablecheck.build.stages import build
from cablecheck.run.runner import RunOptions, run_scene
from cablecheck.run.stepcheck import attachment_exclusions
from cablecheck.scene.errors import SceneError
from cablecheck.scene.load import load_scene

R, CLEARANCE, BESIDE_Y = 4.0, 20.0, 23.0

SCENE = """
[scene]
name = "windows"
units = "{units}"
duration = 0.0

[effects]
dynamics = false

[check]
method = "{method}"
clearance = {clearance}
validate = false

[[parts]]
name = "jig/clamp"
shape = "box"
size = [{c5}, {c10}, {c10}]
pos = [{ox}, {oy}, {oz}]

[[parts]]
name = "jig/beside"
shape = "box"
size = [{c4}, {c4}, {c4}]
pos = [{bx}, {by}, {oz}]

[[cables]]
name = "lead"
radius = {r}
start = {{ pos = [{ox}, {oy}, {oz}]{start_extra} }}
end = {{ pos = [{ex}, {oy}, {oz}] }}
segments = 20
"""


def _scene(tmp_path: Path, units: str = "mm", method: str = "exact", origin=(0.0, 0.0, 0.0),
           start_extra: str = "") -> Path:
    k = 1.0 if units == "mm" else 1e-3        # the same scene in m: every number scaled
    ox, oy, oz = (c * k for c in origin)
    text = SCENE.format(units=units, method=method, clearance=CLEARANCE * k, r=R * k, c5=5 * k, c10=10 * k,
                        c4=4 * k, ox=ox, oy=oy, oz=oz, bx=ox + 16 * k, by=oy + (BESIDE_Y + 4) * k,
                        ex=ox + 200 * k, start_extra=start_extra)
    path = tmp_path / f"windows-{units}-{method}.toml"
    path.write_text(text)
    return path


def _run(tmp_path: Path, path: Path) -> dict:
    return run_scene(load_scene(path), RunOptions(report=tmp_path / "r.json", record=None))


@pytest.mark.parametrize("units,origin", [("mm", (0, 0, 0)), ("m", (0, 0, 0)), ("mm", (4.0e5, -3.0e5, 2.0e5))])
@pytest.mark.parametrize("method", ["exact", "points"])
def test_an_end_on_world_excuses_its_clamp_and_checks_the_part_beside_it(tmp_path, units, origin, method):
    scale = 1.0 if units == "mm" else 1e-3
    report = _run(tmp_path, _scene(tmp_path, units, method, origin))
    (excused,) = report["excused"]
    assert (excused["a"], excused["b"], excused["window"], excused["type"]) == ("lead", "jig/clamp", "start",
                                                                                  "cable-structure")
    assert excused["min_distance"] == pytest.approx((-5 - R) * scale, abs=1e-9 * scale)
    assert report["summary"]["excused"] == 1
    # the part beside the end is no longer excused by the world's window: reported at its distance
    pairs = {(p["a"], p["b"]): p["min_distance"] for p in report["pairs"] if p["a"] == "lead"}
    assert set(pairs) == {("lead", "jig/beside")}
    assert pairs["lead", "jig/beside"] == pytest.approx((BESIDE_Y - R) * scale, abs=1e-9 * scale)
    (event,) = [e for e in report["events"] if e["a"] == "lead"]
    assert (event["b"], event["severity"]) == ("jig/beside", "soft")


def test_a_named_part_is_excused_and_nothing_else(tmp_path):
    report = _run(tmp_path, _scene(tmp_path, start_extra=', part = "jig/beside"'))
    (excused,) = report["excused"]
    assert (excused["b"], excused["window"]) == ("jig/beside", "start")
    assert excused["min_distance"] == pytest.approx(BESIDE_Y - R, abs=1e-9)
    # the clamp is not what the scene says the end is fastened to: a hard clash, at its depth
    pairs = {(p["a"], p["b"]): p["min_distance"] for p in report["pairs"] if p["a"] == "lead"}
    assert set(pairs) == {("lead", "jig/clamp")}
    assert pairs["lead", "jig/clamp"] == pytest.approx(-5 - R, abs=1e-9)


def test_windows_name_the_fastened_parts(tmp_path):
    plain = build(load_scene(_scene(tmp_path)), detect=False)
    assert {(e.cable, e.part, e.window) for e in attachment_exclusions(plain)} == {("lead", "jig/clamp", "start")}
    named = build(load_scene(_scene(tmp_path, start_extra=', part = ["jig"]')), detect=False)
    # an assembly path covers its parts
    assert {e.part for e in attachment_exclusions(named)} == {"jig/clamp", "jig/beside"}
    (window,) = {(e.s_min, e.s_max) for e in attachment_exclusions(named)}
    assert window[0] == 0.0 and window[1] >= 5 * R * 1e-3      # attach_zone radii of rest arc length


@pytest.mark.parametrize("extra,key,problem", [
    (', part = "jig/clmap"', "cables[0].start.part", "did you mean 'jig/clamp'"),
    (', part = ["jig/clamp", "nope"]', "cables[0].start.part[1]", "no part or assembly path named 'nope'"),
    (', part = []', "cables[0].start.part", "non-empty list"),
    (', hold = "free", part = "jig/clamp"', "cables[0].start.part", "free end"),
])
def test_bad_part_names_are_scene_errors(tmp_path, extra, key, problem):
    with pytest.raises(SceneError) as err:
        load_scene(_scene(tmp_path, start_extra=extra))
    assert err.value.key == key and problem in err.value.problem


def test_excused_worst_is_the_least_over_states(tmp_path):
    """A clamp box on a body sliding onto the start and back, the start held
    by that body (no dynamics: the cable stays as routed, straight along +x):
    with the box's centre at x = c <= 0 the cable's deepest point is the
    start, min(5 - |c|, 10) inside, so the excused distance is
    -(5 - |c|) - r, least at c = 0, t = 0.1 s."""
    text = _scene(tmp_path).read_text()
    text = text.replace('name = "jig/clamp"', 'name = "jig/clamp"\nbody = "slide"').replace(
        "duration = 0.0", "duration = 0.2\ntimestep = 0.01").replace(
        "start = { pos = [0.0, 0.0, 0.0] }", 'start = { body = "slide", pos = [3.0, 0.0, 0.0] }') + """
[[bodies]]
name = "slide"

[[motion]]
body = "slide"
interpolation = "linear"
keys = [ { t = 0.0, pos = [-3, 0, 0] }, { t = 0.1, pos = [0, 0, 0] }, { t = 0.2, pos = [-3, 0, 0] } ]
"""
    path = tmp_path / "slide.toml"
    path.write_text(text)
    # fastened as placed at t = 0: the box 3 off centre, still holding the start
    report = _run(tmp_path, path)
    (excused,) = report["excused"]
    assert excused["b"] == "jig/clamp"
    assert excused["min_distance"] == pytest.approx(-5 - R, abs=1e-9)
    assert excused["t_worst"] == pytest.approx(0.1)
    assert np.allclose(excused["where"], [0, 0, 0], atol=1e-9)
