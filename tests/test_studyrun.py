"""One study task (cablecheck.study.execute.run_variant) in this process, without a
cluster: a variant's report is the report of running its scene directly
(timing and file names aside), and its recording comes back as bytes.
Running variants on clusters is tested in test_study."""

from __future__ import annotations

import json

from buildscenes import slider_scene

from cablecheck.run.runner import RunOptions, run_scene
from cablecheck.scene.load import parse_scene
from cablecheck.study.bundle import make_bundle
from cablecheck.study.execute import VariantTask, run_variant

_WHERE = ("timing", "scene_file", "recording", "report")


def _comparable(report: dict) -> dict:
    """The report less its timing and where its files were."""
    out = {k: v for k, v in report.items() if k not in _WHERE}
    out["settings"] = {k: v for k, v in report["settings"].items() if k != "scene_file"}
    return out


def test_a_variant_reports_as_its_scene_run_directly(tmp_path):
    data = slider_scene(tmp_path)
    data["scene"]["duration"] = 0.05
    data["scene"]["settle"] = 0.05
    (tmp_path / "s.toml").write_text("")
    bundle, (moved,) = make_bundle(tmp_path / "s.toml", [data])
    out = run_variant(VariantTask(id="007", data=moved, record=True), bundle)
    run_scene(parse_scene(data, tmp_path / "s.toml"), RunOptions(report=tmp_path / "r.json", record=None))
    direct = json.loads((tmp_path / "r.json").read_text())
    got = json.loads(out.report)
    assert _comparable(got) == _comparable(direct)
    assert got["complete"] is True
    assert out.recording is not None and len(out.recording) > 0
    assert run_variant(VariantTask(id="008", data=moved, record=False), bundle).recording is None
