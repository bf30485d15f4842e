"""The run's outcome record to the JSON report, and the atomic write (cablecheck.report.document)."""

from __future__ import annotations

import json
import math
import os
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from cablecheck.checker.events import AllowedWorst, Event, PairWorst, Phase
from cablecheck.checker.interference.excused import ExcusedWorst
from cablecheck.checker.records import PairType, Severity, severity_of
from cablecheck.checker.scene_state import CheckConfig
from cablecheck.checker.validation import Disagreement, Reason, ValidationSummary
from cablecheck.checker.wear import CableWear
from cablecheck.report import document as report_mod
from cablecheck.report.document import (
    SCHEMA,
    AdvanceOutcome,
    CableOutcome,
    RunOutcome,
    Timing,
    plain,
    report_of,
    write_report,
)
from cablecheck.scene.load import parse_scene

CLEARANCE_MM = 5.0


def _scene(units: str = "mm"):
    k = 1.0 if units == "mm" else 1e-3
    data = {"scene": {"name": "tiny", "units": units, "duration": 0.1, "settle": 0.0},
            "check": {"clearance": CLEARANCE_MM * k},
            "cables": [{"name": "lead", "radius": 3.0 * k, "start": {"pos": [0, 0, 100 * k]},
                        "end": {"pos": [200 * k, 0, 100 * k]}, "length": 260.0 * k, "segments": 12}]}
    return parse_scene(data, Path(f"/virtual/tiny-{units}.toml"))


def _wear(n: int = 4) -> CableWear:
    return CableWear("lead", np.linspace(0.0, 0.26, n, endpoint=False), 0.26, np.array([0.0, 0.02, 0.0, 0.0]),
                     np.array([0.0, 0.001, 0.0, 0.0]), np.zeros(n), (None, "frame/floor", None, None))


def _cable(checked: bool = True) -> CableOutcome:
    pts = np.stack([np.linspace(0.0, 0.2, 15), np.zeros(15), np.full(15, 0.1)], axis=1)
    return CableOutcome(name="lead", length=0.26, radius=0.003, segments=14,
                        max_strain=-0.002 if checked else None, taut=False,
                        min_bend_radius=0.05 if checked else None, bend_violation=False,
                        rest_points=pts if checked else None, final_points=pts + 0.01 if checked else None,
                        wear=_wear(), max_twist=math.radians(30.0) if checked else None,
                        max_twist_moment=1e-4 if checked else None)


def _event(kind=PairType.CABLE_STRUCTURE, d=-0.001, t0=0.0, where=(0.1, 0.0, 0.004)) -> Event:
    sev = severity_of(d, CLEARANCE_MM * 1e-3)
    return Event(kind, "lead", "frame/floor", sev, Phase.STATIC if t0 <= 0.0 else Phase.DYNAMIC,
                 t0, t0 + 0.02, t0 + 0.01, d, np.asarray(where, float), 0.1)


def _validation() -> ValidationSummary:
    d = Disagreement(PairType.CABLE_STRUCTURE, "lead", "frame/floor", 0.02, 0.03, 0.025, None, 0.004,
                     Reason.BETWEEN_POINTS, 0.004, 6)
    return ValidationSummary(compared_steps=50, pair_steps=60, agree=54, checker_only=0, mujoco_only=6,
                             severity_differs=0, agreement=0.9, max_distance_error=1e-4, unexplained=0,
                             allowed_pair_steps=2, reasons=((Reason.BETWEEN_POINTS, 6),), disagreements=(d,))


def _outcome(**changes) -> RunOutcome:
    scene = _scene(changes.pop("units", "mm"))
    events = (_event(), _event(PairType.SELF, 0.002, 0.04))
    base = dict(
        scene=scene, config=CheckConfig(method="points", spacing=2.0, clearance=scene.check.clearance),
        scene_file=str(scene.path), version="0.1.0", mujoco="4.0.1", complete=True, interrupted=None,
        steps=50, checked=50, t_end=0.1, cables=(_cable(),), events=events, event_joints=None, joint_units=None,
        pairs=(PairWorst(PairType.SELF, "lead", "lead", 0.002, 0.05, np.zeros(3)),
               PairWorst(PairType.CABLE_STRUCTURE, "lead", "frame/floor", -0.001, 0.01, np.zeros(3))),
        allowed=(AllowedWorst(PairType.CABLE_STRUCTURE, "lead", "frame/wall", -0.002, 0.0, np.zeros(3),
                              "held by a clip"),),
        excused=(ExcusedWorst(PairType.CABLE_STRUCTURE, "lead", "frame/clamp", "start", -0.003, 0.02,
                              np.array([0.0, 0.0, 0.001]), 0.001),),
        event_hold=0.006, validation=_validation(),
        advance=AdvanceOutcome(horizon=0.01, stretch=0.002, full_checks=10, proven_clear_steps=40),
        warnings={}, part_warnings=(), physics_warnings=(), substeps=1,
        timing=Timing(1.5, {"sim": 0.5, "check": 0.6, "validate": 0.2, "record": 0.1, "wear": 0.1}),
        recording=None)
    base.update(changes)
    return RunOutcome(**base)


def _json(report: dict) -> str:
    return json.dumps(plain(report), indent=1, allow_nan=False)


# The SPEC's keys in the report's order (the golden reports are compared as text).
TOP = ["schema", "scene", "units", "complete", "mujoco", "settings", "summary", "events", "pairs", "allowed",
       "excused", "closest", "validation", "cables", "warnings", "timing", "recording", "joint_units", "part_warnings", "interrupted",
       "physics_warnings", "physics_error", "error"]
SETTINGS = ["method", "spacing", "spacing_radii", "clearance", "attach_zone_radii", "event_hold_s", "timestep",
            "settle", "duration", "dynamics", "gravity", "contact", "steps", "checked_steps", "t_end", "units",
            "scene_file", "version", "advance", "substeps"]
EVENT = ["type", "a", "b", "severity", "phase", "t_start", "t_end", "t_worst", "min_distance", "where", "s"]
CABLE = ["name", "length", "segments", "max_strain", "taut", "min_bend_radius", "bend_violation", "rest_points",
         "final_points", "wear", "max_twist", "max_twist_moment", "twist_from", "twist"]
VALIDATION = ["compared_steps", "pair_steps", "agree", "checker_only", "mujoco_only", "severity_differs",
              "agreement", "max_distance_error", "unexplained", "allowed_pair_steps", "reasons", "disagreements"]


def test_keys_in_the_report_order():
    joints = ({"joints": {"j1": 10.0}, "link": None, "joint_ranges": {"j1": [0.0, 10.0]}},) * 2
    r = json.loads(_json(report_of(_outcome(event_joints=joints, joint_units={"j1": "deg"}))))
    assert list(r) == TOP and list(r["settings"]) == SETTINGS and list(r["validation"]) == VALIDATION
    assert list(r["events"][0]) == EVENT + ["joints", "link", "joint_ranges"]
    assert list(r["cables"][0]) == CABLE
    assert r["schema"] == SCHEMA == "cablecheck.report/1"
    # without moving joints, validation or the skip rule: no joint keys, no validation, advance null
    plain_run = json.loads(_json(report_of(_outcome(validation=None, advance=None))))
    assert list(plain_run) == [k for k in TOP if k not in ("validation", "joint_units")]
    assert list(plain_run["events"][0]) == EVENT and plain_run["settings"]["advance"] is None


def test_enums_are_the_reports_strings():
    r = json.loads(_json(report_of(_outcome())))
    assert [(e["type"], e["severity"], e["phase"]) for e in r["events"]] == [
        ("cable-structure", "hard", "static"), ("self", "soft", "dynamic")]
    assert r["summary"] == {"hard": 1, "soft": 1, "static": 1, "dynamic": 1, "excused": 1}
    assert r["validation"]["reasons"] == {"between points": 6}
    assert r["validation"]["disagreements"][0]["reason"] == "between points"
    assert r["validation"]["disagreements"][0]["type"] == "cable-structure"
    # pairs and allowed pairs worst first
    assert [p["type"] for p in r["pairs"]] == ["cable-structure", "self"]
    assert r["allowed"][0]["reason"] == "held by a clip"
    # what an attachment window excused: the pair, the window, its worst distance and time, in scene units
    assert r["excused"] == [{"type": "cable-structure", "a": "lead", "b": "frame/clamp", "window": "start",
                             "min_distance": -3.0, "t_worst": 0.02, "where": [0.0, 0.0, 1.0], "s": 1.0}]


def test_lengths_in_scene_units_and_twist_in_degrees():
    mm, m = (json.loads(_json(report_of(_outcome(units=u)))) for u in ("mm", "m"))
    assert mm["units"] == "mm" and m["units"] == "m"
    assert mm["settings"]["clearance"] == pytest.approx(CLEARANCE_MM) and m["settings"]["clearance"] == 0.005
    assert mm["settings"]["spacing"] == pytest.approx(6.0)     # 2 radii of a 3 mm cable
    assert mm["events"][0]["min_distance"] == pytest.approx(-1.0) and m["events"][0]["min_distance"] == -0.001
    assert mm["settings"]["advance"]["horizon"] == pytest.approx(10.0)
    c = mm["cables"][0]
    assert c["length"] == pytest.approx(260.0) and c["min_bend_radius"] == pytest.approx(50.0)
    assert c["rest_points"][-1] == pytest.approx([200.0, 0.0, 100.0])
    assert c["wear"]["most_worn"] == {"s": pytest.approx(65.0), "touches": "frame/floor",
                                      "contact_time": 0.02, "sliding": pytest.approx(1.0)}
    assert c["max_twist"] == pytest.approx(30.0) and c["max_twist_moment"] == 1e-4
    assert mm["validation"]["disagreements"][0]["checker"] is None
    assert mm["validation"]["disagreements"][0]["mujoco"] == pytest.approx(4.0)


def test_a_run_that_checked_nothing_reports_nulls():
    r = json.loads(_json(report_of(_outcome(cables=(_cable(checked=False),), checked=0, steps=0, events=(),
                                            pairs=(), excused=(), complete=False, interrupted="SIGINT"))))
    c = r["cables"][0]
    assert c["max_strain"] is None and c["min_bend_radius"] is None and c["max_twist"] is None
    assert c["rest_points"] == [] and c["final_points"] == []
    assert r["complete"] is False and r["interrupted"] == "SIGINT"
    assert r["summary"] == {"hard": 0, "soft": 0, "static": 0, "dynamic": 0, "excused": 0}
    assert r["timing"]["check_ms_per_step"] == pytest.approx(600.0)   # per step: at least one


def test_same_outcome_same_report():
    o = _outcome()
    assert _json(report_of(o)) == _json(report_of(o)) == _json(report_of(replace(o)))


coordinate = st.floats(-1e4, 1e4, allow_nan=False)
point = st.tuples(coordinate, coordinate, coordinate)
distance = st.floats(-0.05, 0.0049, allow_nan=False)


@settings(max_examples=60, deadline=None)
@given(st.lists(st.tuples(point, distance, st.floats(0.0, 10.0)), min_size=1, max_size=6),
       st.sampled_from(["m", "mm"]))
def test_written_events_keep_their_places_and_distances(tmp_path_factory, rows, units):
    """Events drawn anywhere (up to 10 km from the origin), any distance below
    the clearance: the written report gives every worst place and distance back
    in scene units to the report's 1e-12 rounding, with the severity
    `severity_of` gives, in the outcome's order."""
    events = tuple(_event(d=d, t0=t0, where=where) for where, d, t0 in rows)
    o = _outcome(units=units, events=events)
    path = tmp_path_factory.mktemp("r") / "r.json"
    write_report(report_of(o), path)
    written = json.loads(path.read_text())["events"]
    u = o.scene.scale
    assert len(written) == len(events)
    for row, e in zip(written, events):
        assert np.allclose(np.array(row["where"]) * u, e.where, rtol=1e-12, atol=1e-12 * u)
        assert abs(row["min_distance"] * u - e.min_distance) <= 1e-12 * u
        assert row["severity"] == ("hard" if e.min_distance < 0 else "soft")


def test_plain_makes_json_ready_values():
    value = {PairType.SELF: (np.float32(0.5), np.int64(3), np.bool_(True), Path("/a/b")),
             "x": np.array([[1.0, np.nan], [np.inf, -np.inf]]), "r": Reason.AT_BOUNDARY,
             "s": Severity.HARD, 2: 1 / 3}
    out = plain(value)
    assert out == {"self": [0.5, 3, True, "/a/b"], "x": [[1.0, None], [None, None]],
                   "r": "at a boundary", "s": "hard", "2": round(1 / 3, 12)}
    assert type(out["r"]) is str and type(out["self"][2]) is bool and type(out["self"][1]) is int
    json.dumps(out, allow_nan=False)


def test_write_report_replaces_atomically(tmp_path: Path):
    path = tmp_path / "deeper" / "r.json"
    write_report({"a": np.float64(1.0)}, path)
    assert path.read_text() == '{\n "a": 1.0\n}\n'
    write_report({"a": 2}, path)
    assert json.loads(path.read_text()) == {"a": 2}
    assert sorted(p.name for p in path.parent.iterdir()) == ["r.json"]
    umask = os.umask(0)
    os.umask(umask)
    assert path.stat().st_mode & 0o777 == 0o666 & ~umask


def test_failed_write_keeps_the_earlier_report_and_no_temp(tmp_path: Path, monkeypatch):
    path = tmp_path / "r.json"
    path.write_text('{"old": true}')

    def fail(src, dst):
        raise KeyboardInterrupt     # a second Ctrl-C just before the rename

    monkeypatch.setattr(report_mod.os, "replace", fail)
    with pytest.raises(KeyboardInterrupt):
        write_report({"new": True}, path)
    assert path.read_text() == '{"old": true}'
    assert [p.name for p in tmp_path.iterdir()] == ["r.json"]
    with pytest.raises(TypeError):      # not JSON: nothing is written at all
        write_report({"x": object()}, path)
    assert [p.name for p in tmp_path.iterdir()] == ["r.json"]


def test_the_detection_models_collision_time_is_reported_with_validation_only():
    r = report_of(_outcome(timing=Timing(1.5, {"sim": 0.5, "check": 0.6, "validate": 0.2, "record": 0.1,
                                               "wear": 0.1}, collision=0.125)))["timing"]
    assert r["validate_collision_s"] == 0.125
    assert r["validate_collision_ms_per_step"] == pytest.approx(1e3 * 0.125 / 50)
    assert "validate_collision_s" not in report_of(_outcome())["timing"]


def test_physics_error_and_error_in_scene_units():
    """A divergence's place, cause and measure (a distance in scene units, a
    stretch as a ratio) and a run's error, as the report holds them."""
    from cablecheck.report.document import RunError
    from cablecheck.run.divergence import Cause, PhysicsError, Sign

    far = PhysicsError(0.5, 250, False, Sign.FAR, "lead", 4, "cables/lead_4", None, 12.5, Cause.UNITS,
                       "motion[0] moves 'slider' ...")
    r = json.loads(_json(report_of(_outcome(complete=False, physics_error=far))))
    e = r["physics_error"]
    assert e["value"] == pytest.approx(12500.0) and e["sign"] == "runaway-far" and e["cause"] == "units"
    assert (e["t"], e["step"], e["settling"], e["cable"], e["vertex"]) == (0.5, 250, False, "lead", 4)
    assert e["message"] == far.message() and "12.5 m from the scene" in e["message"] and r["error"] is None
    stretched = replace(far, sign=Sign.STRETCHED, value=4.0, cause=Cause.STIFFNESS)
    e = json.loads(_json(report_of(_outcome(complete=False, physics_error=stretched))))["physics_error"]
    assert e["value"] == 4.0 and e["cause"] == "stiffness-timestep"
    err = RunError("IndexError", "index 7 is out of bounds", "Traceback (most recent call last): ...", 0.04)
    r = json.loads(_json(report_of(_outcome(complete=False, error=err))))
    assert r["error"] == {"type": "IndexError", "message": "index 7 is out of bounds", "t": 0.04,
                          "traceback": "Traceback (most recent call last): ..."} and r["physics_error"] is None
    assert report_of(_outcome())["physics_error"] is None


def test_plain_rounds_float_arrays_as_each_float():
    from cablecheck.report.document import plain
    rng = np.random.default_rng(3)
    values = [rng.normal(size=(50, 3)) * 10.0 ** rng.integers(-9, 9, (50, 1)),
              np.array([np.nan, np.inf, -np.inf, -0.0, 5e-13, 1.5e-12]), np.array(2.5),
              rng.normal(size=(2, 3, 2)).astype(np.float32)]
    for v in values:
        flat = [round(float(f), 12) if np.isfinite(f) else None for f in np.ravel(v)]
        got = plain(v)
        assert json.dumps(got) == json.dumps(np.array(flat, dtype=object).reshape(np.shape(v)).tolist())
