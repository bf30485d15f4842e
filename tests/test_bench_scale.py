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
