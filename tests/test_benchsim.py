"""The simulation side of the benchmark (cablecheck.bench.sim_tables): the example scenes it
times. Its tables run in test_bench on the tiny sizes."""

from __future__ import annotations

from pathlib import Path

from cablecheck.bench.sim_tables import example_names

ROOT = Path(__file__).resolve().parents[1]


def test_example_names_are_every_scene_drawer_and_arm_first():
    names = example_names()
    assert names[:2] == ["drawer", "arm"]
    assert sorted(names) == sorted(p.stem for p in (ROOT / "scenes").glob("*.toml"))
