"""Start-up pays only for what runs: a plain `check` or `run --no-record`
imports no recording library (rerun), no cluster (Dask), no plotting
(matplotlib), and a scene of primitive parts no mesh library (trimesh).

Each command runs in a fresh interpreter (`python -c`), which then lists
the heavy packages it holds in `sys.modules`.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from cablecheck.bench.harness import harness_scene, write_scene

ROOT = Path(__file__).resolve().parents[1]

HEAVY = ("rerun", "dask", "distributed", "matplotlib", "trimesh")
"""Packages a plain check or a run without a recording must not load."""

_PROBE = """
import json, sys
from cablecheck.cli.main import main
code = main(sys.argv[1:])
heavy = sorted({{m.split(".")[0] for m in sys.modules}} & set({heavy!r}))
print(json.dumps({{"code": code, "heavy": heavy}}))
"""


def _loaded(*args: str) -> tuple[int, list[str]]:
    """Run `cablecheck ARGS` in a fresh interpreter: its exit status and the heavy packages it loaded."""
    out = subprocess.run([sys.executable, "-c", _PROBE.format(heavy=HEAVY), *args], cwd=ROOT,
                         capture_output=True, text=True, timeout=300)
    found = json.loads(out.stdout.strip().splitlines()[-1])
    return found["code"], found["heavy"]


@pytest.fixture(scope="module")
def static_scene(tmp_path_factory) -> Path:
    """A small static harness: primitive parts, no motion, no dynamics."""
    data = harness_scene(4, 20, segments=12, duration=0.0, dynamics=False)
    data["check"]["validate"] = False
    return write_scene(data, tmp_path_factory.mktemp("startup") / "static.toml")


def test_check_loads_nothing_heavy():
    code, heavy = _loaded("check", "scenes/drawer.toml")
    assert code == 0 and heavy == []


def test_run_without_a_recording_loads_nothing_heavy(tmp_path):
    code, heavy = _loaded("run", "scenes/drawer.toml", "--no-record", "--quiet",
                          "--report", str(tmp_path / "drawer.json"))
    assert code in (0, 1) and heavy == []


def test_static_run_loads_nothing_heavy(static_scene, tmp_path):
    code, heavy = _loaded("run", str(static_scene), "--no-record", "--quiet",
                          "--report", str(tmp_path / "static.json"))
    assert code in (0, 1) and heavy == []
