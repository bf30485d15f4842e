"""cablecheck.report.review: a reviewer's notes matched to a run's events by pair, carried into the report and the summary."""

from __future__ import annotations

import json
from pathlib import Path
from types import SimpleNamespace

import pytest
from helpers import write_text

from cablecheck.cli.main import main
from cablecheck.report.review import ReviewError, ReviewStatus, load_review, match

ROOT = Path(__file__).resolve().parents[1]


def _event(a, b, type="cable-structure"):
    return SimpleNamespace(type=type, a=a, b=b)


def test_a_note_covers_its_pair_in_either_order_and_under_an_assembly_path(tmp_path):
    notes = load_review(write_text(tmp_path / "n.toml", '''
[[review]]
a = "drawer"
b = "loop"
status = "approved"
comment = "sleeve fitted"
[[review]]
a = "loop"
b = "cabinet"
status = "reviewed"
comment = ""
type = "keepout"
[[review]]
a = "hose"
b = "frame"
status = "reviewed"
'''))
    events = [_event("loop", "drawer/back"), _event("loop", "cabinet/floor"), _event("loop", "drawers/x")]
    m = match(tmp_path / "n.toml", notes, events)
    assert [None if n is None else n.index for n in m.per_event] == [0, None, None]   # type differs; 'drawers' is not under 'drawer'
    assert [n.index for n in m.unmatched] == [1, 2]
    assert notes[0].status is ReviewStatus.APPROVED and notes[2].comment == ""
    keep = match(tmp_path / "n.toml", notes, [_event("loop", "cabinet/floor", "keepout")])
    assert keep.per_event[0].index == 1


@pytest.mark.parametrize("text, key, words", [
    ('[[review]]\nb = "x"\nstatus = "approved"', "review[0].a", "missing"),
    ('[[review]]\na = "x"\nb = "y"\nstatus = "ok"', "review[0].status", "'reviewed' or 'approved'"),
    ('[[review]]\na = "x"\nb = "y"\nstatus = "approved"\nwho = 1', "review[0].who", "unknown key"),
    ('[[review]]\na = ""\nb = "y"\nstatus = "approved"', "review[0].a", "non-empty"),
    ('[[review]]\na = "x"\nb = "y"\nstatus = "approved"\ntype = "rub"', "review[0].type", "one of"),
    ('[notes]\na = 1', "notes", "unknown table"),
    ('[[review]\n', "(file)", "not TOML"),
])
def test_a_bad_notes_file_names_file_key_and_problem(tmp_path, text, key, words):
    path = write_text(tmp_path / "n.toml", text)
    with pytest.raises(ReviewError) as e:
        load_review(path)
    assert e.value.key == key and words in e.value.problem and str(path) in str(e.value)


def test_run_carries_the_notes_into_the_report_and_exits_2_on_a_bad_file(tmp_path, capsys):
    notes = write_text(tmp_path / "n.toml", '[[review]]\na = "loop"\nb = "drawer"\nstatus = "approved"\n'
                       'comment = "sleeve fitted"\n[[review]]\na = "loop"\nb = "cabinet/floor"\n'
                       'status = "reviewed"\ncomment = "was pinched in rev A"\n')
    report = tmp_path / "r.json"
    assert main(["run", str(ROOT / "scenes" / "drawer_pinch.toml"), "--no-record", "--report", str(report),
                 "--review", str(notes), "--fail-on", "never"]) == 0
    out = capsys.readouterr().out
    r = json.loads(report.read_text())
    assert [e["review"] for e in r["events"]] == [{"status": "approved", "comment": "sleeve fitted"}]
    assert r["review"]["on_events"] == 1 and [n["b"] for n in r["review"]["unmatched"]] == ["cabinet/floor"]
    assert "approved: sleeve fitted" in out and "review[1] loop / cabinet/floor (reviewed)" in out
    bad = write_text(tmp_path / "bad.toml", '[[review]]\na = "loop"\n')
    assert main(["run", str(ROOT / "scenes" / "drawer_pinch.toml"), "--no-record", "--report",
                 str(tmp_path / "r2.json"), "--review", str(bad)]) == 2
    err = capsys.readouterr().err
    assert "review[0].b" in err and "Traceback" not in err and not (tmp_path / "r2.json").exists()
