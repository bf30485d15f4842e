"""`cablecheck bench`: the tables are produced and sane.

Runs the bench once at tiny sizes (`TINY`, module fixture, into a temporary
folder: seconds, where the quick bench takes a minute) and checks the
files, columns and the accuracy relations the tables must show; the
command line's wiring to the quick and full sizes is checked without
running them. Nothing here asserts a time: timings only have to be
positive and finite.

The tables of cablecheck.bench.checker_tables and cablecheck.bench.sim_tables and the figure of
cablecheck.bench.plot are tested here, through that one tiny run; their small
pieces have their own files (test_benchtable, test_benchscene,
test_benchcheck, test_benchsim, test_benchfcl, test_benchplot).
"""

from __future__ import annotations

import csv
import dataclasses
import math
from pathlib import Path

import pytest

import cablecheck.bench.command
from cablecheck.bench.command import FULL, QUICK, BenchSizes, run_bench
from cablecheck.cli.main import main

ROOT = Path(__file__).resolve().parents[1]

TINY = BenchSizes(
    name="tiny", repeat=1, disc_scenes=2, large_cables=4,
    catenary=((20, 0.002), (40, 0.002)), cantilever=((20, 0.002), (40, 0.002)),
    scale_cables=(1, 2, 4), scale_parts=(10, 20, 40), scale_held_parts=20, scale_held_cables=4,
    side_scene=(6, 50, 20, 1), side_repeat=1, fcl_repeat=1,
    synthetic=((3, 10, 10),), side_examples=("drawer",),
    paper_cases=(("simple", 2, 10), ("complex", 4, 40)),
    examples=("drawer",), example_seconds=0.2)
"""Every table at a few seconds' worth of sizes."""

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
    printed = []
    run_bench(TINY, out, echo=printed.append)
    assert printed[0].startswith("cablecheck bench (tiny sizes)")
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
    assert [int(r["cables"]) for r in scale if r["axis"] == "cables"] == list(TINY.scale_cables)
    assert [int(r["parts"]) for r in scale if r["axis"] == "parts"] == list(TINY.scale_parts)
    assert all(int(r["parts"]) == TINY.scale_held_parts for r in scale if r["axis"] == "cables")
    assert all(int(r["cables"]) == TINY.scale_held_cables for r in scale if r["axis"] == "parts")
    assert all(int(r["points"]) == 200 * int(r["cables"]) for r in scale)
    assert all(_positive(r["ms_points"]) and _positive(r["ms_exact"]) for r in scale)

    _, side = tables["side_by_side"]
    others = {r["other"] for r in side}
    assert "mj_collision" in others
    assert "fcl update+query" in others or any("not installed" in o for o in others)
    n_cables, n_points, n_prims, n_meshes = TINY.side_scene
    assert {r["scene"] for r in side} == {f"random {n_cables}x{n_points}/{n_prims + n_meshes}",
                                          "synthetic 3 cables/10 parts", "drawer"}
    for r in side:
        if r["other_ms"]:
            assert _positive(r["ratio"]) and _positive(r["other_ms"])

    _, paper = tables["paper"]
    assert [(r["case"], int(r["cables"]), int(r["parts"])) for r in paper] == list(TINY.paper_cases)

    _, examples = tables["example_scenes"]
    assert [r["scene"] for r in examples] == list(TINY.examples)
    for r in examples:
        assert 0 < int(r["steps"]) <= round(TINY.example_seconds / 0.002) + 1
        assert int(r["full_checks"]) >= 1 and int(r["full_checks"]) + int(r["proven_clear"]) <= int(r["steps"]) + 1
        assert _positive(r["mj_step_ms"]) and _positive(r["check_ms"]) and _positive(r["realtime_factor"])

    _, targets = tables["targets"]
    assert len(targets) == 6
    assert all(r["met"] in ("True", "False", "") for r in targets)
    # the check-time targets are stated for 20,000 points x 310 parts: not judged at tiny sizes
    assert [r["met"] for r in targets[:2]] == ["", ""]
    assert all("measured on" in r["measured"] for r in targets[:2])


def test_quick_and_full_sizes_measure_what_the_tables_state():
    for sizes in (QUICK, FULL):
        assert len(sizes.scale_cables) >= 3 and len(sizes.scale_parts) >= 3
        assert sizes.side_scene == cablecheck.bench.command.TARGET_SCENE
        assert sizes.examples == () and "drawer" in sizes.side_examples
        assert {case for case, _, _ in sizes.paper_cases} == {"simple", "complex"}
        assert all(n > 100 and p > 200 for case, n, p in sizes.paper_cases if case == "complex")
        assert all(n < 100 for case, n, _ in sizes.paper_cases if case == "simple")
    assert QUICK.example_seconds == 1.0 and FULL.example_seconds is None


@pytest.mark.parametrize("args, sizes", [(["--quick"], QUICK), ([], FULL)])
def test_the_command_runs_the_quick_or_full_sizes(tmp_path: Path, monkeypatch, args, sizes):
    calls = []
    monkeypatch.setattr(cablecheck.bench.command, "run_bench", lambda s, out: calls.append((s, out)))
    assert main(["bench", *args, "--out", str(tmp_path / "b")]) == 0
    assert calls == [(sizes, tmp_path / "b")]


def test_the_command_refuses_an_output_folder_that_is_a_file(tmp_path: Path, monkeypatch, capsys):
    monkeypatch.setattr(cablecheck.bench.command, "run_bench", lambda s, out: pytest.fail("ran"))
    (tmp_path / "f").write_text("")
    assert main(["bench", "--quick", "--out", str(tmp_path / "f")]) == 2
    assert "--out" in capsys.readouterr().err


def test_sizes_are_frozen():
    with pytest.raises(dataclasses.FrozenInstanceError):
        QUICK.repeat = 1  # type: ignore[misc]


