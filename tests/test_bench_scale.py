"""benchmarks/bench_scale.py's static table on a tiny scene: both runs, the same events, fcl beside the checker."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def test_static_table_runs_without_a_model_and_beside_one(tmp_path):
    pytest.importorskip("fcl")
    out = subprocess.run([sys.executable, str(ROOT / "benchmarks" / "bench_scale.py"), "--tables", "static",
                          "--static", "2,10", "--segments", "8", "--out", str(tmp_path)],
                         cwd=ROOT, capture_output=True, text=True, timeout=600)
    assert out.returncode == 0, out.stderr[-2000:]
    (row,) = json.loads((tmp_path / "bench_scale.json").read_text())["static"]
    static, mujoco = row["no_model"], row["MuJoCo_model"]
    assert static["events"] == mujoco["events"] and static["pairs"] == mujoco["pairs"]
    assert static["checker_points"] > 0 and static["fcl_points"] > 0 and static["n_points"] > 0
    assert "fcl/checker" in out.stdout


def test_a_runs_memory_counts_its_processes_together():
    """bench_scale's peak_pss_mb sums a process and its children (a run whose
    simulation steps in a process of its own is two): a parent and a forked
    child each holding 100 MB of their own read about 200 MB together (the
    parent alone, about 100). ru_maxrss is not compared: a process forked
    from a large one (this test's worker) keeps that one's size as its
    high-water mark through exec."""
    sys.path.insert(0, str(ROOT / "benchmarks"))
    try:
        from bench_scale import _child
    finally:
        sys.path.remove(str(ROOT / "benchmarks"))
    code = ("import os, time; pid = os.fork(); a = (b'2' if pid == 0 else b'1') * (100 * 2 ** 20); "
            "time.sleep(0.8); os._exit(0) if pid == 0 else os.waitpid(pid, 0)")
    status, _, _, _, err, pss = _child(["-c", code], ROOT, 4.0, 60)
    assert status == 0, err
    assert 190 <= pss < 280          # 200 MiB and the interpreters, their shared pages split
