"""benchmarks/bench_startup.py on a tiny static scene: its table, and the figures written between the markers."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def test_times_both_commands_and_writes_the_doc_section(tmp_path):
    doc = tmp_path / "performance.md"
    doc.write_text("# Performance\n\n<!-- bench_startup -->\nold figures\n<!-- /bench_startup -->\n\nafter\n")
    out = subprocess.run([sys.executable, str(ROOT / "benchmarks" / "bench_startup.py"), "--repeat", "1",
                          "--static", "2,10", "--doc", str(doc)],
                         cwd=ROOT, capture_output=True, text=True, timeout=600)
    assert out.returncode == 0, out.stderr[-2000:]
    assert "`cablecheck check scenes/drawer.toml`" in out.stdout
    assert "`cablecheck run STATIC --no-record --quiet --report REPORT`" in out.stdout
    assert "load average" in out.stdout
    text = doc.read_text()
    assert "old figures" not in text and text.startswith("# Performance\n") and text.endswith("\nafter\n")
    assert text.count("<!-- bench_startup -->") == 1 and "| this checkout |" in text
