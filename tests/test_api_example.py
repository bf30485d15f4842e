"""docs/api.md's example, run as it stands from the repository's root: the public API works as documented."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def test_the_api_pages_example_runs_and_prints_what_it_says():
    text = (ROOT / "docs" / "api.md").read_text()
    blocks = re.findall(r"```python\n(.*?)```", text, flags=re.S)
    assert len(blocks) == 1
    out = subprocess.run([sys.executable, "-c", blocks[0]], cwd=ROOT, capture_output=True, text=True, timeout=600)
    assert out.returncode == 0, out.stderr
    lines = out.stdout.splitlines()
    assert lines[0] == "drawer-pinch ['loop'] mm"
    assert lines[1].startswith("complete: True summary: {'hard': 1")
    assert any(line.startswith("worst: loop drawer/") and " hard " in line for line in lines)
    rows = [line for line in lines if line.startswith("(4")]
    assert len(rows) == 2 and all(" done hard events: " in r for r in rows)
    assert lines[-1] == "outputs: ['results.csv', 'study.json', 'study.png']"


def test_every_public_name_is_in_the_api_page():
    import cablecheck

    text = (ROOT / "docs" / "api.md").read_text()
    assert all(f"`{name}" in text for name in cablecheck.__all__)
