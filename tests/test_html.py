"""The HTML report (`cablecheck run --html`, issue 28 item 5): one self-contained file whose clash
table, read back from headless Chromium's DOM, equals the JSON report, with a non-blank picture per
clash; a missing OpenGL context is said, never silent; the path is checked before the run."""

from __future__ import annotations

import base64
import io
import json
import re
import shutil
import subprocess
from html.parser import HTMLParser
from pathlib import Path

import numpy as np
import pytest
from matplotlib.image import imread

from cablecheck.cli.main import main
from cablecheck.report import render
from cablecheck.report.html import distance_decimals
from cablecheck.run.runner import RunOptions, run_outcome, run_scene
from cablecheck.scene.load import load_scene

ROOT = Path(__file__).resolve().parents[1]
SCENE = ROOT / "scenes" / "drawer_pinch.toml"
CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    out = tmp_path_factory.mktemp("html")
    report, page = out / "drawer.json", out / "drawer.html"
    status = main(["run", str(SCENE), "--no-record", "--report", str(report), "--html", str(page), "--quiet"])
    assert status == 1            # one hard clash
    return json.loads(report.read_text()), page


class _Page(HTMLParser):
    """The clash table's rows (cells' text and the row's attributes) and every image's src."""

    def __init__(self):
        super().__init__()
        self.rows: list[tuple[dict, list[str]]] = []
        self.images: list[str] = []
        self.links: list[str] = []
        self.tags: set[str] = set()
        self._in_table = False
        self._cell: list[str] | None = None

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        self.tags.add(tag)
        if tag == "table" and a.get("id") == "clashes":
            self._in_table = True
        elif tag == "tr" and self._in_table and "clash-row" in (a.get("class") or ""):
            self.rows.append((a, []))
        elif tag == "td" and self._in_table and self.rows:
            self._cell = []
        elif tag == "img":
            self.images.append(a.get("src") or "")
        if tag in ("a", "link", "script", "iframe") and (a.get("href") or a.get("src")):
            self.links.append(a.get("href") or a.get("src"))

    def handle_endtag(self, tag):
        if tag == "table":
            self._in_table = False
        elif tag == "td" and self._cell is not None:
            self.rows[-1][1].append("".join(self._cell).strip())
            self._cell = None

    def handle_data(self, data):
        if self._cell is not None:
            self._cell.append(data)


def _dom(page: Path) -> str:
    """The page as headless Chromium builds it (offline: a file URL, no network needed)."""
    done = subprocess.run([CHROMIUM, "--headless", "--disable-gpu", "--no-sandbox", "--dump-dom",
                           page.resolve().as_uri()], capture_output=True, text=True, timeout=60)
    assert done.returncode == 0, done.stderr[-2000:]
    return done.stdout


def _check_images(images: list[str]) -> None:
    for src in images:
        assert src.startswith("data:image/png;base64,"), src[:60]
        pixels = imread(io.BytesIO(base64.b64decode(src.split(",", 1)[1])), format="png")
        flat = pixels.reshape(-1, pixels.shape[-1])
        assert len(np.unique(flat, axis=0)) > 10 and flat.std() > 0.02   # not one colour


@pytest.mark.skipif(CHROMIUM is None, reason="headless Chromium (Debian's `chromium` package) is not installed")
def test_chromium_reads_back_the_json_reports_clash_table(run):
    report, page = run
    parsed = _Page()
    parsed.feed(_dom(page))
    events = report["events"]
    assert len(events) == 1 and len(parsed.rows) == len(events)
    header = ["#", "severity", "type", "pair", "worst distance", "t worst", "start - end", "along", "phase"]
    digits = distance_decimals(1e-3 if report["units"] == "mm" else 1.0)
    for attrs, cells in parsed.rows:
        e = events[int(attrs["data-event"])]
        row = dict(zip(header, cells))
        assert (attrs["data-a"], attrs["data-b"]) == (e["a"], e["b"])
        assert row["severity"] == e["severity"] and row["type"] == e["type"] and row["phase"] == e["phase"]
        assert float(row["worst distance"]) == round(e["min_distance"], digits)
        assert row["worst distance"] == f"{e['min_distance']:.{digits}f}"
        assert float(row["t worst"]) == pytest.approx(e["t_worst"], abs=5e-4)
    # one picture per clash, a distance history per clash and a wear profile per cable, all inline
    assert len(parsed.images) == 2 * len(events) + len(report["cables"])
    _check_images(parsed.images)
    assert "script" not in parsed.tags and "link" not in parsed.tags
    assert all(link.startswith("#") for link in parsed.links)
    assert report["html"] == {"renderer": "egl", "pictures": 1, "warnings": []}


def test_the_file_is_self_contained(run):
    _, page = run
    text = page.read_text()
    assert not re.search(r"""(src|href)\s*=\s*["']?(https?:|//|file:)""", text)
    assert "<script" not in text and "@import" not in text and "url(" not in text
    assert not list(page.parent.glob(".*.tmp"))                 # written atomically


def test_status_and_notes_appear_in_the_table(run, tmp_path):
    report, _ = run
    earlier = tmp_path / "earlier.json"
    earlier.write_text(json.dumps(report))
    notes = tmp_path / "notes.toml"
    notes.write_text('[[review]]\na = "loop"\nb = "drawer/back"\nstatus = "reviewed"\ncomment = "<known> & fine"\n')
    page = tmp_path / "again.html"
    assert main(["run", str(SCENE), "--no-record", "--report", str(tmp_path / "again.json"), "--quiet",
                 "--baseline", str(earlier), "--review", str(notes), "--html", str(page)]) == 1
    parsed = _Page()
    parsed.feed(page.read_text())
    (attrs, cells), = parsed.rows
    assert "present" in cells and "reviewed: <known> & fine" in cells


def test_the_run_keeps_one_state_per_clash_its_worst_and_the_pairs_history(tmp_path):
    scene = load_scene(SCENE)
    plain = run_outcome(scene, RunOptions(report=tmp_path / "a.json", record=None))
    assert plain.html is None                                   # nothing kept without --html
    o = run_outcome(scene, RunOptions(report=tmp_path / "b.json", record=None, html=tmp_path / "b.html"))
    (event,), (kept,) = o.events, o.html.clashes
    assert kept.t_spot == event.t_worst and kept.qpos.ndim == 1 and not kept.qpos.flags.writeable
    assert len(kept.t) == len(kept.distance) and np.all(np.diff(kept.t) > 0)
    assert kept.distance.min() == pytest.approx(event.min_distance)
    assert kept.t[0] <= event.t_start and kept.t[-1] >= event.t_end
    assert o.html.pictures.renderer == "egl" and o.html.pictures.png[0][:8] == b"\x89PNG\r\n\x1a\n"


def test_no_opengl_context_is_said_in_the_report_and_the_page(tmp_path, monkeypatch):
    monkeypatch.setattr(render, "_context", lambda w, h: (None, None, ["egl: no display here (test)"]))
    scene = load_scene(SCENE)
    page = tmp_path / "r.html"
    report = run_scene(scene, RunOptions(report=tmp_path / "r.json", record=None, html=page))
    (warning,) = report["html"]["warnings"]
    assert "no offscreen OpenGL context" in warning and "egl: no display here (test)" in warning
    assert report["html"]["pictures"] == 0 and report["html"]["renderer"] is None
    text = page.read_text()
    assert "no offscreen OpenGL context" in text and "(no picture" in text


def test_an_html_path_that_cannot_be_written_fails_before_the_run(tmp_path, capsys):
    assert main(["run", str(SCENE), "--no-record", "--report", str(tmp_path / "r.json"),
                 "--html", str(tmp_path)]) == 2
    assert "--html" in capsys.readouterr().err
    assert not (tmp_path / "r.json").exists()


def test_a_twisted_cable_shows_its_torsion_along_it():
    """With the simulated rod's twist, the cable's section says how far it twisted and where the
    torsion was largest, with a chart of it along the cable; a cable that carried none, no chart."""
    from cablecheck.report.html import html_report

    def cable(name, moment):
        return {"name": name, "length": 1.0, "segments": 4, "max_strain": 0.001, "taut": False,
                "min_bend_radius": None, "bend_violation": False, "rest_points": [], "final_points": [],
                "wear": {"s": [0.0, 0.25, 0.5, 0.75], "contact_time": [0.0] * 4, "sliding": [0.0] * 4,
                         "bend_cycles": [0] * 4, "most_worn": None},
                "max_twist": 90.0 if moment else 0.0, "max_twist_moment": max(moment or [0.0]), "twist_from": "rod",
                "twist": {"s": [0.25, 0.5, 0.75], "max_moment": moment or [0.0] * 3, "max_rate": [1.0] * 3}}

    report = {"scene": "t", "units": "m", "complete": True, "events": [], "cables": [
        cable("wound", [0.01, 0.03, 0.02]), cable("still", None)],
        "summary": {"hard": 0, "soft": 0, "static": 0, "dynamic": 0},
        "settings": {"version": "x", "clearance": 0.005, "units": "m"}}
    page = html_report(report)
    assert "twist up to 90 degrees end to end, torsion up to 0.03 N m at 0.5 m along it" in page
    parser = _Page()
    parser.feed(page)
    torsion = [src for src in parser.images if src]
    assert 'alt="torsion along wound"' in page and 'alt="torsion along still"' not in page
    _check_images(torsion)
