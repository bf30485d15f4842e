"""Checking states a batch at a time (sim.stepcheck) gives the answers of
checking them one at a time."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import sim.run
from sim.run import RunOptions, run_scene
from sim.scene import load_scene

SCENES = Path(__file__).resolve().parents[1] / "scenes"


def _comparable(rep: dict) -> dict:
    out = {k: rep[k] for k in ("events", "pairs", "summary")}
    out["cables"] = [(c["max_strain"], c["min_bend_radius"], np.asarray(c["final_points"]).tolist())
                     for c in rep["cables"]]
    out["advance"] = rep["settings"]["advance"]
    out["validation"] = {k: v for k, v in rep.get("validation", {}).items()}
    out["steps"] = (rep["settings"]["steps"], rep["settings"]["checked_steps"])
    return {k: (np.asarray(v).tolist() if isinstance(v, np.ndarray) else v) for k, v in out.items()}


def _strip(x):
    if isinstance(x, dict):
        return {k: _strip(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_strip(v) for v in x]
    return x.tolist() if isinstance(x, np.ndarray) else x


@pytest.mark.parametrize("name", ["drawer_pinch", "keepout_bolt"])
def test_batch_size_changes_no_answer(name: str, tmp_path, monkeypatch):
    scene = load_scene(SCENES / f"{name}.toml")
    reports = []
    for size in (1, 7, sim.run.BATCH):
        monkeypatch.setattr(sim.run, "BATCH", size)
        rep = run_scene(scene, RunOptions(report=tmp_path / f"{size}.json", record=None))
        reports.append(_strip(_comparable(rep)))
    adv = reports[0]["advance"]
    assert adv["full_checks"] > 1 and adv["proven_clear_steps"] > 0   # both kinds in the batches
    assert reports[0] == reports[1] == reports[2]
