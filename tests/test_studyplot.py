"""A study's outputs (cablecheck.study.plot) for rows made here: results.csv reads
back cell for cell, study.json carries the settings, rows and answer and
is strict JSON, study.png is a PNG, and no temporary file is left."""

from __future__ import annotations

import csv
import json
from pathlib import Path

from cablecheck.study.definition import load_study
from cablecheck.study.plot import SCHEMA, write_outputs
from cablecheck.study.result import CABLE_COLUMNS, COLUMNS, CableRow, Row, Status, length_window

EXAMPLE = Path(__file__).resolve().parents[1] / "scenes" / "studies" / "drawer_length_study.toml"


def test_outputs_read_back(tmp_path):
    study = load_study(EXAMPLE)
    power = CableRow("power", hard=2, soft=0, closest=-1.25, closest_to="cabinet/floor", max_strain=0.031,
                     taut=True, min_bend_radius=None, bend_violation=False, max_twist=None, wear=3.5)
    rows = [Row("000", (540.0,), Status.DONE, exit_status=1, hard=2, soft=0, worst_distance=-1.25,
                max_strain=0.031, taut=True, bend_violation=False, run_time_s=0.5, cables=(power,)),
            Row("001", (600.0,), Status.DONE, exit_status=0, hard=0, soft=1, worst_distance=0.1,
                max_strain=0.001, min_bend_radius=40.0, taut=False, bend_violation=False, agreement=1.0),
            Row("002", (660.0,), Status.FAILED, error="boom")]
    window = length_window(rows)
    paths = write_outputs(tmp_path / "out", study, rows, complete=False, units="mm", window=window,
                          settings={"workers": 2})
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == ["results.csv", "study.json", "study.png"]
    with open(paths["csv"], newline="") as f:
        table = list(csv.reader(f))
    assert table[0] == ["id", "cables.power.length", *COLUMNS, *(f"power: {c}" for c in CABLE_COLUMNS)]
    got = [dict(zip(table[0], line)) for line in table[1:]]
    assert [g["id"] for g in got] == ["000", "001", "002"]
    assert [g["cables.power.length"] for g in got] == ["540", "600", "660"]
    first = (got[0]["status"], got[0]["hard"], got[0]["worst_distance"], got[0]["taut"])
    assert first == ("done", "2", "-1.25", "true")
    assert (got[1]["min_bend_radius"], got[0]["min_bend_radius"], got[2]["status"]) == ("40.0", "", "failed")
    # the varied cable's own columns (empty where a row has no cable rows)
    assert (got[0]["power: closest_to"], got[0]["power: wear"], got[0]["power: taut"]) == ("cabinet/floor", "3.5", "true")
    assert got[1]["power: hard"] == ""
    doc = json.loads(paths["json"].read_text(), parse_constant=lambda c: (_ for _ in ()).throw(ValueError(c)))
    assert doc["schema"] == SCHEMA and doc["study"] == "drawer-power-length" and doc["units"] == "mm"
    assert doc["complete"] is False and doc["settings"] == {"workers": 2}
    assert doc["vary"] == [{"key": "cables.power.length", "scene_key": study.vary[0].path,
                            "values": list(study.vary[0].values)}]
    assert [r["values"] for r in doc["rows"]] == [{"cables.power.length": v} for v in (540.0, 600.0, 660.0)]
    assert doc["rows"][2]["status"] == "failed" and doc["rows"][2]["error"] == "boom"
    assert doc["free_of_hard"] == ["001"]
    assert doc["window"]["key"] == "cables.power.length" and doc["window"]["shortest"] == window.shortest
    assert paths["png"].read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_two_keys_are_also_drawn_as_a_map(tmp_path):
    from helpers import write_text

    scene = Path(__file__).resolve().parents[1] / "scenes" / "drawer.toml"
    path = write_text(tmp_path / "s.toml", f'[study]\nname = "two"\nscene = "{scene}"\n'
                      '[[vary]]\nkey = "cables.power.length"\nfrom = 600\nto = 700\n'
                      '[[vary]]\nkey = "check.clearance"\nfrom = 2\nto = 6\n'
                      '[[require]]\ntaut = false\n[search]\nmethod = "optimise"\nbudget = 4\n')
    study = load_study(path)
    rows = [Row("000", (600.0, 2.0), Status.DONE, hard=0, soft=0, satisfied=False, margin=-1.0),
            Row("001", (700.0, 6.0), Status.DONE, hard=0, soft=1, satisfied=True, margin=2.0),
            Row("002", (650.0, 4.0), Status.FAILED, error="boom")]
    paths = write_outputs(tmp_path / "out", study, rows, complete=True, units="mm", window=None, settings={})
    assert paths["map"].read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    doc = json.loads(paths["json"].read_text())
    assert doc["best"]["id"] == "001" and doc["best"]["satisfied"] is True and doc["runs"] == 3
