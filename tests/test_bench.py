"""`cablecheck bench --quick`: the tables are produced and sane.

Runs the quick benchmark once (module fixture, into a temporary folder) and
checks the files, columns and the accuracy relations the tables must show.
Nothing here asserts a time: timings only have to be positive and finite.
"""

from __future__ import annotations

import csv
import math
from pathlib import Path

import pytest

from sim.cli import main

TABLES = {
    "discretisation": ["config", "spacing_r", "ms_per_check", "ms_large", "pairs", "ref_pairs", "ref_hard",
                       "missed_hard", "missed", "false_alarms", "worst_error_mm"],
    "physics": ["reference", "elements", "elements_per_m", "timestep_ms", "error_pct", "ms_per_sim_s",
                "warnings"],
    "scale": ["axis", "cables", "points", "parts", "ms_points", "ms_exact", "us_per_point_points",
              "us_per_point_exact"],
    "side_by_side": ["scene", "method", "points", "parts", "checker_ms", "other", "other_ms", "ratio"],
    "paper": ["case", "cables", "points", "parts", "cable_cable_s", "cable_structure_s", "full_check_s",
              "paper_cable_cable_s", "paper_cable_structure_s"],
    "example_scenes": ["scene", "steps", "mj_step_ms", "sim_ms", "check_ms", "validate_ms",
                       "check_plus_validate_ms", "record_ms", "cost_over_mj_step", "realtime_factor",
                       "realtime_factor_total", "full_checks", "proven_clear"],
    "targets": ["target", "measured", "met"],
}


@pytest.fixture(scope="module")
def bench(tmp_path_factory):
    out = tmp_path_factory.mktemp("bench")
    assert main(["bench", "--quick", "--out", str(out)]) == 0
    tables = {}
    for name in TABLES:
        with open(out / f"{name}.csv", newline="") as f:
            rows = list(csv.reader(f))
        tables[name] = (rows[0], [dict(zip(rows[0], r)) for r in rows[1:]])
    return out, tables


def _positive(text: str) -> bool:
    v = float(text)
    return math.isfinite(v) and v > 0


def test_files_and_columns(bench):
    out, tables = bench
    for name, columns in TABLES.items():
        header, rows = tables[name]
        assert header == columns, name
        assert rows, f"{name}.csv has no rows"
    png = out / "bench.png"
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert png.stat().st_size < 200_000


def test_discretisation_errors_shrink_and_exact_is_the_reference(bench):
    _, rows = bench[1]["discretisation"]
    by = {r["config"]: r for r in rows}
    assert set(by) == {"points 4r", "points 2r", "points r", "points r/2", "face-plane 2r", "exact"}
    err = [float(by[k]["worst_error_mm"]) for k in ("points 4r", "points 2r", "points r", "points r/2")]
    assert err == sorted(err, reverse=True) and err[-1] < err[0]
    missed = [int(by[k]["missed"]) for k in ("points 4r", "points 2r", "points r", "points r/2")]
    assert missed == sorted(missed, reverse=True)
    exact = by["exact"]
    assert int(exact["missed_hard"]) == 0 and int(exact["missed"]) == 0 and int(exact["false_alarms"]) == 0
    assert float(exact["worst_error_mm"]) == 0.0
    assert int(exact["ref_hard"]) > 0 and int(exact["ref_pairs"]) > int(exact["ref_hard"])
    # Discrete points sample the centreline: they never report a pair the exact geometry does not.
    for k in ("points 4r", "points 2r", "points r", "points r/2"):
        assert int(by[k]["false_alarms"]) == 0, k
    # The paper's face-plane distance raises false alarms near edges.
    assert int(by["face-plane 2r"]["false_alarms"]) > 0
    for r in rows:
        assert _positive(r["ms_per_check"]) and _positive(r["ms_large"])


def test_physics_errors_against_references(bench):
    _, rows = bench[1]["physics"]
    for ref in ("catenary", "cantilever"):
        at_2ms = {int(r["elements"]): abs(float(r["error_pct"])) for r in rows
                  if r["reference"] == ref and float(r["timestep_ms"]) == 2.0}
        assert len(at_2ms) >= 2
        counts = sorted(at_2ms)
        assert at_2ms[counts[-1]] < at_2ms[counts[0]], ref  # more elements, smaller error
        assert at_2ms[counts[-1]] < 10.0
    for r in rows:
        assert r["warnings"] == ""
        assert _positive(r["ms_per_sim_s"])


def test_scale_side_by_side_paper_and_examples(bench):
    tables = bench[1]
    _, scale = tables["scale"]
    cables = [int(r["cables"]) for r in scale if r["axis"] == "cables"]
    parts = [int(r["parts"]) for r in scale if r["axis"] == "parts"]
    assert min(cables) == 1 and max(cables) == 200
    assert min(parts) == 10 and max(parts) == 2000
    assert all(_positive(r["ms_points"]) and _positive(r["ms_exact"]) for r in scale)

    _, side = tables["side_by_side"]
    others = {r["other"] for r in side}
    assert "mj_collision" in others
    assert "fcl update+query" in others or any("not installed" in o for o in others)
    assert {r["scene"] for r in side} >= {"drawer", "arm"}
    for r in side:
        if r["other_ms"]:
            assert _positive(r["ratio"]) and _positive(r["other_ms"])

    _, paper = tables["paper"]
    assert {r["case"] for r in paper} == {"simple", "complex"}
    complex_ = [r for r in paper if r["case"] == "complex"]
    assert all(int(r["cables"]) > 100 and int(r["parts"]) > 200 for r in complex_)
    assert all(int(r["cables"]) < 100 for r in paper if r["case"] == "simple")

    _, examples = tables["example_scenes"]
    scenes = sorted(p.stem for p in (Path(__file__).resolve().parents[1] / "scenes").glob("*.toml"))
    assert [r["scene"] for r in examples][:2] == ["drawer", "arm"]
    assert sorted(r["scene"] for r in examples) == scenes
    for r in examples:
        assert int(r["steps"]) > 0
        assert int(r["full_checks"]) >= 1 and int(r["full_checks"]) + int(r["proven_clear"]) <= int(r["steps"]) + 1
        assert _positive(r["mj_step_ms"]) and _positive(r["check_ms"]) and _positive(r["realtime_factor"])

    _, targets = tables["targets"]
    assert len(targets) == 6
    assert all(r["met"] in ("True", "False", "") for r in targets)
