"""benchmarks/bench_near.py --quick: the rows say what its scenes are (a hose resting on the near parts, never on the far ones)."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def test_quick_rows_touch_the_near_parts_alone(tmp_path):
    out = subprocess.run([sys.executable, str(ROOT / "benchmarks" / "bench_near.py"), "--quick",
                          "--json", str(tmp_path / "rows.json")],
                         cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr[-2000:]
    assert "| near parts | far parts |" in out.stdout and "load average" in out.stdout
    rows = json.loads((tmp_path / "rows.json").read_text())
    assert [(w["near"], w["far"]) for w in rows] == [(2, 0), (2, 4)]
    for w in rows:
        # the hose rests on every near part and comes within the clearance of no far one
        assert w["complete"] and w["touched"] == w["near"] and w["far_touched"] == 0, w
        assert w["steps"] == 101 and w["check_ms"] > 0 and w["agreement"] >= 0.98
