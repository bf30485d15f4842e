"""cablecheck.record: the clash review recording, read back with rerun's own reader.

The runs are the example scenes; every assertion reads the written .rrd
through `rerun.chunk.RrdReader` (the SDK's reader of recordings), never the
recorder's own buffers.
"""

from __future__ import annotations

import json
import tomllib
from pathlib import Path

import numpy as np
import pyarrow as pa
import pytest
from hypothesis import given, settings, strategies as st
from rerun.chunk import RrdReader

from cablecheck.cli.main import main, version
from cablecheck.record.layout import CLASH_COLUMNS
from cablecheck.record.style import (
    CABLE_PALETTE,
    CONTACT_COLOUR,
    FLOOR,
    FLOOR_DIMMED,
    KEEPOUT_COLOUR,
    PART_COLOUR,
    SPOT,
    STATE_COLOURS,
    cable_colour,
    pair_path,
)
from cablecheck.record import wearview
from cablecheck.record.wearview import CHARTED_CABLES, charted, wear_colours
from tests.helpers import examples, recorded_rows as _rows

ROOT = Path(__file__).resolve().parents[1]


def _run(scene: str, out: Path) -> tuple[dict, Path]:
    record = out / f"{Path(scene).stem}.rrd"
    assert main(["run", str(ROOT / "scenes" / scene), "--record", str(record), "--quiet",
                 "--fail-on", "never", "--report", str(record.with_suffix(".json"))]) == 0
    return json.loads(record.with_suffix(".json").read_text()), record


def _clash_rows(record: Path) -> list[dict]:
    """The clash list's rows in its order (rank on the `clash` sequence): {column: value, "t": worst time s,
    "clash": rank}, from its entities `clashes/<column>` (one per column), each column's header under "headers"."""
    rows: dict[int, dict] = {}
    for chunk in RrdReader(record).stream():
        if not chunk.entity_path.startswith("/clashes/"):
            continue
        name = chunk.entity_path.split("/")[-1]
        batch = chunk.to_record_batch()
        (header,) = [k for k in batch.schema.names if "RowId" not in k and k not in ("sim_time", "clash")]
        ranks = batch.column("clash").to_pylist()
        t = batch.column("sim_time").cast(pa.int64()).to_numpy() * 1e-9
        for rank, when, value in zip(ranks, t, batch.column(header).to_pylist()):
            row = rows.setdefault(rank, {"clash": rank, "t": float(when), "headers": {}})
            row[name] = value[0]
            row["headers"][name] = header
    return [rows[k] for k in sorted(rows)]


def _view_defaults(record: Path) -> list[dict]:
    """The views' component defaults in the recording's blueprint, one {column: values} per entry."""
    reader = RrdReader(record)
    (store,) = reader.blueprints()
    found = []
    for chunk in reader.stream(store=store):
        if chunk.entity_path.endswith("/defaults"):
            batch = chunk.to_record_batch()
            found.append({k: batch.column(k).to_pylist() for k in batch.schema.names if ":" in k})
    return found


def _entities(record: Path) -> set[str]:
    return {c.entity_path for c in RrdReader(record).stream()}


def _packed(rgb) -> int:
    """An 8-bit colour (opaque unless given 4 values) as rerun packs it."""
    return int.from_bytes(bytes([*rgb, 255][:4]), "big")


def _axes(quaternions) -> np.ndarray:
    """+z (a capsule's own axis) turned by each quaternion (x, y, z, w), by the rotation matrix's third column."""
    x, y, z, w = np.array(quaternions, float).T
    return np.stack([2 * (x * z + w * y), 2 * (y * z - w * x), 1 - 2 * (x * x + y * y)], axis=-1)


def _cable_rows(record: Path, cable: str) -> list[dict]:
    """A cable's timed rows, each with the capsules' lengths shown then (given again only where they changed)."""
    rows = [r for r in _rows(record, f"/world/cables/{cable}") if r["t"] is not None]
    for before, row in zip(rows, rows[1:]):
        row["lengths_given"] = row["Capsules3D:lengths"] is not None
        if not row["lengths_given"]:
            row["Capsules3D:lengths"] = before["Capsules3D:lengths"]
    return rows


def _capsule_ends(row: dict) -> tuple[np.ndarray, np.ndarray]:
    """A cable's capsules in one of its recorded rows: each one's two ends (the centres of its end spheres)."""
    start = np.array(row["Capsules3D:translations"])
    return start, start + np.array(row["Capsules3D:lengths"])[:, None] * _axes(row["Capsules3D:quaternions"])


def _centres(row: dict) -> np.ndarray:
    """A cable's body centres in one of its recorded rows: its capsules' first ends and the last one's second."""
    start, end = _capsule_ends(row)
    return np.concatenate([start, end[-1:]])


def _colours_at(rows: list[dict], t: float) -> np.ndarray:
    """A cable's capsule colours (one per element) shown at `t`: its latest row at or before it that gives them."""
    given = [r for r in rows if r["t"] is not None and r["t"] <= t + 1e-12 and r["Capsules3D:colors"] is not None]
    return np.array(given[-1]["Capsules3D:colors"], np.uint32)


@pytest.fixture(scope="module")
def pinch(tmp_path_factory) -> tuple[dict, Path]:
    """drawer_pinch: the drawer's back panel sweeps through a cable loop (one hard event)."""
    return _run("drawer_pinch.toml", tmp_path_factory.mktemp("pinch"))


@pytest.fixture(scope="module")
def crossing(tmp_path_factory) -> tuple[dict, Path]:
    """crossing: two leads overlapping from the start to the end (one event open at the end)."""
    return _run("crossing.toml", tmp_path_factory.mktemp("crossing"))


def test_every_run_is_its_own_recording_named_after_the_scene(crossing, tmp_path: Path):
    _, first = crossing
    _, second = _run("crossing.toml", tmp_path)
    ids = []
    for record in (first, second):
        recordings = RrdReader(record).recordings()
        assert len(recordings) == 1
        assert recordings[0].application_id == "crossing"
        ids.append(recordings[0].recording_id)
        names = [r["RecordingInfo:name"] for r in _rows(record, "/__properties") if "RecordingInfo:name" in r]
        assert names == [["crossing"]]
    assert ids[0] != ids[1]


def test_properties_hold_units_clearance_scene_file_and_version(pinch):
    report, record = pinch
    (props,) = _rows(record, "/__properties/cablecheck")
    assert props["units"] == ["mm"] and props["clearance"] == [pytest.approx(3.0)]
    assert props["scene_file"][0].endswith("drawer_pinch.toml") and props["version"] == [version()]
    s = report["settings"]
    assert (s["units"], s["scene_file"], s["version"]) == ("mm", props["scene_file"][0], version())


def test_only_the_simulation_timeline_is_written(pinch):
    _, record = pinch
    timelines = {t for c in RrdReader(record).stream() if not c.entity_path.startswith("/clashes/")
                 for t in c.timeline_names}
    assert timelines == {"sim_time"}
    # the clash list's rows also carry their rank, on a sequence of its own
    assert {t for c in RrdReader(record).stream() if c.entity_path.startswith("/clashes/")
            for t in c.timeline_names} == {"sim_time", "clash"}


def test_the_spot_is_labelled_with_pair_and_distance_in_its_own_colour(pinch):
    report, record = pinch
    (event,) = report["events"]
    path = "/world/interference/cable-structure/loop/drawer_back"
    rows = _rows(record, path)
    assert all(r["t"] is not None for r in rows)           # spot and gap in one chunk, no style entry
    # the style is every 3D view's default (the blueprint), so a pair costs one chunk
    styles = _view_defaults(record)
    spheres = [d for d in styles if "Ellipsoids3D:colors" in d]
    assert len(spheres) >= 2                                # the scene and the worst clash's viewpoint
    for d in spheres:
        rgba = d["Ellipsoids3D:colors"][0][0]
        assert (rgba >> 24, (rgba >> 16) & 255, (rgba >> 8) & 255) == SPOT
        assert d["Ellipsoids3D:line_radii"] == [[-2.5]]
        assert d["Points3D:show_labels"] == [[True]]        # the label rides on a point above the sphere
    spot = int.from_bytes(bytes([*SPOT, 255]), "big")
    assert [d["LineStrips3D:colors"] for d in styles if "LineStrips3D:colors" in d] == [[[spot]]] * len(spheres)
    assert [d["Points3D:colors"] for d in styles if "Points3D:colors" in d] == [[[spot]]] * len(spheres)
    assert SPOT not in (*STATE_COLOURS.values(), PART_COLOUR, KEEPOUT_COLOUR[:3])
    shown = [r for r in rows if r["t"] is not None]
    # every row holds as many sizes as centres: an emptied row draws nothing (not a sphere at the origin)
    assert all(len(r["Ellipsoids3D:half_sizes"]) == len(r["Ellipsoids3D:centers"]) for r in shown)
    worst = min(shown, key=lambda r: abs(r["t"] - event["t_worst"]))
    assert worst["Points3D:labels"] == [f"loop / drawer/back: {event['min_distance']:.3g} mm"]
    # the label just above the sphere (no other spot to keep clear of)
    (centre,), (top,), (half,) = worst["Ellipsoids3D:centers"], worst["Points3D:positions"], worst["Ellipsoids3D:half_sizes"]
    assert np.allclose(np.subtract(top, centre), [0.0, 0.0, 1.15 * half[0]], rtol=1e-5)
    # shown from the event's start, emptied at the frame after its last
    assert shown[0]["t"] == pytest.approx(event["t_start"]) and shown[-1]["Points3D:labels"] == []
    assert shown[-1]["Points3D:positions"] == [] and shown[-1]["Ellipsoids3D:centers"] == []
    # the gap: from the worst place on the centreline (radius 3 mm) to the panel's surface
    gaps = [r for r in rows if r.get("LineStrips3D:strips")]
    at = next(r for r in gaps if r["t"] == pytest.approx(event["t_worst"]))
    seg = np.array(at["LineStrips3D:strips"][0])
    assert np.linalg.norm(seg[1] - seg[0]) == pytest.approx(abs(event["min_distance"] + 3.0), abs=1e-3)
    # and a thinner line through it, on the gap's line, running out of the sphere on both sides
    through = np.array(at["LineStrips3D:strips"][1])
    d = (seg[1] - seg[0]) / np.linalg.norm(seg[1] - seg[0])
    off = through - seg[0]
    assert np.allclose(off - (off @ d)[:, None] * d, 0.0, atol=1e-3)
    assert (np.linalg.norm(off, axis=1) > 1.5 * half[0]).all() and (off @ d).min() < 0 < (off @ d).max()
    assert at["LineStrips3D:radii"][1] < at["LineStrips3D:radii"][0]


def test_only_the_elements_near_the_spot_take_the_state_colour(pinch):
    report, record = pinch
    (event,) = report["events"]
    rows = [r for r in _rows(record, "/world/cables/loop") if r["t"] is not None]
    hard, own = _packed(STATE_COLOURS["hard"]), _packed(cable_colour(0))
    colours = _colours_at(rows, event["t_worst"])           # one colour per element
    n = report["cables"][0]["segments"]
    assert len(colours) == n
    assert set(colours.tolist()) == {hard, own}
    assert 0 < (colours == hard).sum() < n // 3
    assert set(_colours_at(rows, 0.5).tolist()) == {own}     # before the clash: the cable's own colour


def test_the_clash_list_has_one_row_per_event_at_its_worst_time(pinch):
    report, record = pinch
    rows = _clash_rows(record)
    assert len(rows) == len(report["events"]) == 1
    (row,), (ev,) = rows, report["events"]
    assert row["t"] == pytest.approx(ev["t_worst"]) and row["clash"] == 1
    # short names (`back` is the only part so called), the full paths beside
    assert (row["type"], row["pair"], row["severity"], row["phase"], row["a"], row["b"]) == \
        ("cable-structure", "loop / back", "hard", "dynamic", "loop", "drawer/back")
    assert row["start"] == pytest.approx(ev["t_start"]) and row["end"] == pytest.approx(ev["t_end"])
    assert row["worst_distance"] == round(ev["min_distance"], 2) and row["headers"]["worst_distance"] == "mm"
    assert "status" not in row                              # only against a baseline run


def test_the_clash_view_shows_the_layouts_columns_in_order(pinch):
    """rerun's dataframe view orders columns by entity (`entity_order`), one
    entity's components alphabetically: the layout names one entity per
    column, in CLASH_COLUMNS' order, and selects the rank and the worst time."""
    _, record = pinch
    reader = RrdReader(record)
    (store,) = reader.blueprints()
    queries = []
    for chunk in reader.stream(store=store):
        batch = chunk.to_record_batch()
        if "DataframeQuery:entity_order" in batch.schema.names:
            queries.append({k: batch.column(k).to_pylist()[0] for k in batch.schema.names if ":" in k})
    (query,) = queries
    columns = [c for c in CLASH_COLUMNS if c != "status"]
    assert query["DataframeQuery:entity_order"] == [[f"/clashes/{c}" for c in columns]]
    assert query["DataframeQuery:timeline"] == ["clash"]
    (select,) = query["DataframeQuery:select"]
    assert select["time_columns"] == ["clash", "sim_time"]
    assert [c["entity_path"] for c in select["component_columns"]] == [f"/clashes/{c}" for c in columns]
    headers = _clash_rows(record)[0]["headers"]
    assert [c["component"] for c in select["component_columns"]] == [headers[c] for c in columns]


class _Event:
    def __init__(self, a, b, severity, distance, t, kind="cable-structure"):
        self.a, self.b, self.severity, self.min_distance, self.t_worst = a, b, severity, distance, t
        self.type, self.phase, self.t_start, self.t_end = kind, "dynamic", t - 0.1, t + 0.1


def _clash_list(tmp_path: Path, events: list, unit: float, units: str, status=None, names=()) -> list[dict]:
    import uuid

    import rerun as rr

    from cablecheck.record.clashes import send_clash_list
    path = tmp_path / f"list_{units}.rrd"
    rec = rr.RecordingStream(application_id="list", recording_id=uuid.uuid4())
    rec.save(str(path))
    send_clash_list(rec, events, [{} for _ in events], unit, units, status, names)
    rec.disconnect()
    return _clash_rows(path)


def test_the_clash_list_reads_at_a_glance_with_shared_prefixes(tmp_path: Path):
    """Two hoses against two uprights of one frame: short names tell them
    apart, the rows go hard before soft then deepest first (not by time),
    distances are rounded to 0.01 mm, the pair's header is as wide as the
    longest pair (the view sizes a column to its header)."""
    up1, up2 = "machine/frame/upright_1", "machine/frame/upright_2"
    events = [_Event("hose_left", up1, "hard", -0.000889260512, 0.27),
              _Event("hose_right", up2, "soft", 0.00007517234, 0.10),
              _Event("hose_left", up2, "hard", -0.002135284391, 0.438),
              _Event("hose_right", "hose_right", "hard", -0.0024997195, 0.51, kind="taut"),
              _Event("hose_right", up1, "hard", -0.000889264, 0.20)]
    rows = _clash_list(tmp_path, events, 1e-3, "mm", status=["new", "present", "new", "new", "present"],
                       names=["machine/frame/base", up1, up2])
    assert [r["clash"] for r in rows] == [1, 2, 3, 4, 5]
    assert [r["pair"] for r in rows] == ["hose_right", "hose_left / upright_2", "hose_right / upright_1",
                                         "hose_left / upright_1", "hose_right / upright_2"]
    assert [r["severity"] for r in rows] == ["hard"] * 4 + ["soft"]
    assert [r["worst_distance"] for r in rows] == [-2.5, -2.14, -0.89, -0.89, 0.08]
    assert [r["t"] for r in rows] == pytest.approx([0.51, 0.438, 0.20, 0.27, 0.10])     # equal depth: earlier first
    assert [r["status"] for r in rows] == ["new", "new", "present", "new", "present"]
    assert [(r["a"], r["b"]) for r in rows][1] == ("hose_left", up2)
    headers = rows[0]["headers"]
    assert headers["worst_distance"] == "mm" and headers["start"] == headers["end"] == "s"
    assert len(headers["pair"]) >= len("hose_right / upright_2") + 2 and headers["pair"].startswith("cable / other")
    # in metres, 0.01 mm is five decimals
    rows_m = _clash_list(tmp_path, events, 1.0, "m")
    assert [r["worst_distance"] for r in rows_m] == [-0.0025, -0.00214, -0.00089, -0.00089, 0.00008]
    assert rows_m[0]["headers"]["worst_distance"] == "m" and "status" not in rows_m[0]


def test_short_names_keep_the_levels_that_tell_names_apart():
    from cablecheck.record.style import short_names
    got = short_names(["machine/frame/upright_1", "machine/frame/upright_2", "left/rail", "right/rail", "hose",
                       "drawer/back"])
    assert got == {"machine/frame/upright_1": "upright_1", "machine/frame/upright_2": "upright_2",
                   "left/rail": "left/rail", "right/rail": "right/rail", "hose": "hose", "drawer/back": "back"}


def _short_names_every_pair(names) -> dict[str, str]:
    """short_names as first written: each name's tail against every other name's (the reference)."""
    full = sorted(set(names))
    levels = {n: n.split("/") for n in full}
    short = {}
    for n in full:
        parts = levels[n]
        for k in range(1, len(parts) + 1):
            tail = parts[-k:]
            if not any(m != n and levels[m][-k:] == tail for m in full):
                break
        short[n] = "/".join(tail)
    return short


@settings(max_examples=examples(40), deadline=None)
@given(st.lists(st.lists(st.sampled_from(["a", "b", "rail", "frame", "left", "x/y"]), min_size=1, max_size=4)
                .map("/".join), max_size=30))
def test_short_names_are_those_of_comparing_every_pair(names):
    """Drawn assembly paths (repeated, one a tail of another, a name twice): the
    short names counted by tail are those of comparing each name with every other."""
    from cablecheck.record.style import short_names
    assert short_names(names) == _short_names_every_pair(names)


def test_the_event_log_has_one_start_and_one_end_per_event_levelled_by_severity(pinch, crossing):
    for report, record in (pinch, crossing):
        log = [r for r in _rows(record, "/events")]
        assert len(log) == 2 * len(report["events"])
        for ev in report["events"]:
            pair = ev["a"] if ev["a"] == ev["b"] else f"{ev['a']} / {ev['b']}"
            mine = [r for r in log if f" {pair} " in r["TextLog:text"][0]]
            assert [r["t"] for r in mine] == [pytest.approx(ev["t_start"]), pytest.approx(ev["t_end"])]
            assert mine[-1]["TextLog:level"] == [{"hard": "ERROR", "soft": "WARN"}[ev["severity"]]]
    # crossing's event is still open when the run ends: its one end entry says so
    (ev,) = crossing[0]["events"]
    ends = [r for r in _rows(crossing[1], "/events") if "still present" in r["TextLog:text"][0]]
    assert len(ends) == 1 and ends[0]["t"] == pytest.approx(ev["t_end"])


def test_pair_state_lanes_follow_the_event(pinch):
    report, record = pinch
    (ev,) = report["events"]
    lane = _rows(record, "/lanes/cable-structure/loop/drawer_back")
    assert all(r["t"] is not None for r in lane)
    # the lanes' configuration is the state timeline's default (one chunk per lane)
    (config,) = [d for d in _view_defaults(record) if "StateConfiguration:values" in d]
    assert config["StateConfiguration:values"] == [["clear", "soft", "hard"]]
    assert config["StateConfiguration:colors"] == [[int.from_bytes(bytes([*STATE_COLOURS[x], 255]), "big")
                                                    for x in ("clear", "soft", "hard")]]
    states = [(r["t"], r["StateChange:state"][0]) for r in lane]
    assert states[0] == (pytest.approx(ev["t_start"]), "soft")
    assert "hard" in [s for _, s in states] and states[-1][1] == "clear"
    assert states[-1][0] > ev["t_end"]


def test_distances_have_limit_lines_and_break_where_unknown(pinch):
    report, record = pinch
    clearance = [r for r in _rows(record, "/checks/limits/clearance") if r["t"] is not None]
    assert [r["Scalars:scalars"] for r in clearance] == [[3.0], [3.0]]
    assert [r["t"] for r in clearance] == [0.0, pytest.approx(report["settings"]["t_end"])]
    dist = [r for r in _rows(record, "/checks/cable-structure/loop/drawer_back/distance") if r["t"] is not None]
    values = np.array([r["Scalars:scalars"][0] for r in dist])
    assert np.isnan(values).any()                          # the line stops after the event
    # the legend's label rides in the series' first row (one chunk per series)
    assert dist[0]["SeriesLines:names"] == ["cable-structure: loop / drawer/back"]
    assert not any(r.get("SeriesLines:names") for r in dist[1:])
    assert np.nanmin(values) == pytest.approx(report["events"][0]["min_distance"])
    # the loop has no min_bend_radius in the scene: no limit line
    assert "/cables/bend_radius/loop_limit" not in _entities(record)


def test_summary_at_t0_names_the_clash_and_the_most_worn_spot(pinch):
    report, record = pinch
    (doc,) = _rows(record, "/summary")
    assert doc["t"] == 0.0
    text = doc["TextDocument:text"][0]
    assert "drawer-pinch" in text and "loop / drawer/back" in text and "hard" in text
    worn = report["cables"][0]["wear"]["most_worn"]
    assert worn is not None and worn["touches"] == "drawer/back"
    assert f"s = {worn['s']:.4g} mm" in text and "touching drawer/back" in text


def test_the_wear_map_is_in_the_report_and_the_recording(pinch):
    report, record = pinch
    wear = report["cables"][0]["wear"]
    n = report["cables"][0]["segments"]
    assert all(len(wear[k]) == n for k in ("s", "contact_time", "sliding", "bend_cycles"))
    assert wear["s"][0] == 0.0 and np.all(np.diff(wear["s"]) > 0)
    touched = np.array(wear["contact_time"]) > 0
    # the panel cuts the loop for about the event's length, at some places only
    (ev,) = report["events"]
    assert 0 < touched.sum() < n
    assert max(wear["contact_time"]) <= ev["t_end"] - ev["t_start"] + 0.011
    assert not np.array(wear["sliding"])[~touched].any()
    entities = _entities(record)
    assert {"/wear_map/loop", "/wear/loop/contact_time", "/wear/loop/sliding", "/wear/loop/bend_cycles"} <= entities
    (strip,) = _rows(record, "/wear_map/loop")
    assert len(strip["LineStrips3D:colors"]) == n


def test_the_twist_along_each_cable_is_in_the_report_and_the_recording(pinch):
    """With dynamics, the report's twist along the cable (per interior vertex)
    is charted in the recording: a bar per vertex at its arc length."""
    report, record = pinch
    cable = report["cables"][0]
    assert cable["twist_from"] == "rod"
    twist = cable["twist"]
    assert len(twist["s"]) == cable["segments"] - 1 == len(twist["max_moment"]) == len(twist["max_rate"])
    assert cable["max_twist_moment"] == max(twist["max_moment"])
    (bars,) = _rows(record, "/twist/loop/max_moment")
    values = np.concatenate([np.asarray(v["buffer"], float).ravel() for v in bars["BarChart:values"]])
    assert np.allclose(values, twist["max_moment"])


class _Wear:
    def __init__(self, name, sliding, contact_time):
        self.name, self.sliding, self.contact_time = name, np.asarray(sliding, float), np.asarray(contact_time, float)


def test_wear_is_on_one_scale_for_the_run_with_a_noise_floor():
    """The same sliding is the same colour on two cables, whichever slid
    most; the top of the scale is the run's most; sliding at or below the
    floor (rounding noise: 9e-16 m here) is grey like no contact."""
    from cablecheck.record.wearview import ROUNDING_ULPS, SLIDING_FLOOR, wear_scale
    a = _Wear("a", [0.0, 9e-16, 0.002, 0.010], [0.0, 0.5, 0.5, 0.5])
    b = _Wear("b", [0.002, 0.030, 0.0], [0.5, 0.5, 0.5])
    steps, extent = 1000, 0.5
    scale = wear_scale([a, b], 1e-3, "mm", steps, extent)
    assert (scale.measure, scale.units) == ("sliding", "mm") and scale.top == pytest.approx(30.0)
    rounding = steps * ROUNDING_ULPS * np.finfo(float).eps * extent
    assert scale.floor == pytest.approx(max(SLIDING_FLOOR * 0.030, rounding) / 1e-3)
    ca = wear_colours(a.sliding, a.contact_time, scale, 1e-3)
    cb = wear_colours(b.sliding, b.contact_time, scale, 1e-3)
    grey = (200, 200, 200)
    assert tuple(ca[2]) == tuple(cb[0])                  # 2 mm on either cable
    assert tuple(cb[1]) == (253, 231, 37)                 # the run's most: the top colour
    assert tuple(ca[3]) != tuple(cb[1])                   # a's own most is not the top
    assert tuple(ca[0]) == grey and tuple(ca[1]) == grey  # no contact; rounding noise
    assert tuple(cb[2]) == grey                           # in contact, slid nothing
    # a run whose sliding is all noise is coloured by contact time (s), nothing under a floor
    still = wear_scale([_Wear("c", [9e-16, 0.0], [0.2, 0.4])], 1e-3, "mm", steps, extent)
    assert (still.measure, still.top, still.floor, still.units) == ("contact_time", 0.4, 0.0, "s")
    assert "0.4 s" in still.legend() and "30 mm" in scale.legend()


def test_the_wear_view_names_each_cable_draws_the_parts_and_a_legend(pinch):
    report, record = pinch
    (name,) = _rows(record, "/wear_map/loop/name")
    assert name["Points3D:labels"] == ["loop"]
    entities = _entities(record)
    assert "/wear_map/parts/drawer/back" in entities      # what the loop touches, as at t = 0
    assert not any(e.startswith("/wear_map/parts/cabinet") for e in entities)
    (values,) = _rows(record, "/wear_map/legend/values")
    top = max(report["cables"][0]["wear"]["sliding"])
    assert f"{top:.3g} mm sliding" in values["Points3D:labels"][2] and values["Points3D:labels"][0] == "0"
    assert "grey" in values["Points3D:labels"][3] and " mm" in values["Points3D:labels"][3]
    (bar,) = _rows(record, "/wear_map/legend/bar")
    assert len(bar["LineStrips3D:colors"]) == len(bar["LineStrips3D:strips"]) > 10


def test_wear_colours_grey_where_untouched():
    c = wear_colours(np.array([0.0, 0.0, 1.0, 2.0]), np.array([0.0, 1.0, 1.0, 1.0]))
    assert tuple(c[0]) == (200, 200, 200) and tuple(c[1]) == (200, 200, 200)   # touched, slid nothing
    assert tuple(c[2]) != (200, 200, 200) and tuple(c[3]) == (253, 231, 37)
    # nothing slid: over contact time
    c = wear_colours(np.zeros(3), np.array([0.0, 1.0, 2.0]))
    assert tuple(c[0]) == (200, 200, 200) and tuple(c[1]) != (200, 200, 200) and tuple(c[2]) == (253, 231, 37)
    assert not np.isnan(wear_colours(np.zeros(3), np.zeros(3)).astype(float)).any()


ON_PLATE = """
[scene]
name = "on-plate"
units = "mm"
duration = 0.5
settle = 0.3

[effects]
contact = ["cable-structure"]

[check]
clearance = 2.0

[[bodies]]
name = "slider"

[[parts]]
name = "plate"
shape = "box"
size = [300, 100, 5]
pos = [150, 0, -5]

[[cables]]
name = "lead"
radius = 3.0
start = { pos = [-60, 0, 120] }
via = [ [0, 0, 3] ]
end = { body = "slider", pos = [200, 0, 3] }
segments = 24

[[motion]]
body = "slider"
keys = [ { t = 0.0, pos = [0, 0, 0] }, { t = 0.5, pos = [60, 0, 0] } ]
"""


def test_a_cable_lying_on_a_plate_with_one_end_sliding_wears_only_where_it_touches(tmp_path: Path):
    """The simulated cable hangs from above the plate's edge and lies on the
    plate to its end, which is dragged 60 mm along it (lifting the cable off
    the plate bit by bit as it draws taut). Judged against the cable's shape
    in every recorded frame: bins that never came near the plate have no
    contact and no sliding, bins that lay on it throughout were in contact
    the whole run and slid."""
    scene = tmp_path / "on_plate.toml"
    scene.write_text(ON_PLATE)
    record = tmp_path / "p.rrd"
    assert main(["run", str(scene), "--record", str(record), "--quiet", "--fail-on", "never"]) == 0
    report = json.loads(record.with_suffix(".json").read_text())
    wear = report["cables"][0]["wear"]
    frames = [_centres(row) for row in _cable_rows(record, "lead")]
    z = np.stack(frames)[:, :, 2]                                   # (frames, body centres)
    low, high = z.min(axis=0), z.max(axis=0)
    r, clearance, top = 3.0, 2.0, 0.0
    never = (low[:-1] > top + r + clearance + 1.0) & (low[1:] > top + r + clearance + 1.0)
    always = (high[:-1] < top + r + 0.5 * clearance) & (high[1:] < top + r + 0.5 * clearance)
    contact, sliding = np.array(wear["contact_time"]), np.array(wear["sliding"])
    assert never.sum() >= 3 and always.sum() >= 1
    assert not contact[never].any() and not sliding[never].any()
    duration = report["settings"]["t_end"]
    assert (contact[always] > duration - 0.011).all() and contact.max() <= duration + 1e-9
    assert (sliding[always] > 30.0).all() and sliding.max() <= 60.0 + 1.0   # the end travels 60 mm
    assert wear["most_worn"]["touches"] == "plate"
    # the recording's wear map colours the untouched bins grey, and those that slid (not under the floor) not
    (strip,) = _rows(record, "/wear_map/lead")
    grey = int.from_bytes(bytes([200, 200, 200, 255]), "big")
    colours = np.array(strip["LineStrips3D:colors"], np.uint32)
    assert (colours[never] == grey).all() and not (colours[sliding > 1e-3 * sliding.max()] == grey).any()


def test_a_style_given_once_rides_in_the_first_row(pinch):
    _, record = pinch
    # one chunk per entity: the capsules' radius and fill mode, the name and its style, the contacts'
    # style in the first row, absent after
    for entity, style in (("/world/cables/loop", ["Capsules3D:radii", "Capsules3D:fill_mode", "Points3D:labels",
                                                  "Points3D:colors", "Points3D:radii", "Points3D:show_labels"]),
                          ("/world/mujoco_contacts", ["Points3D:radii", "Points3D:colors"])):
        chunks = [c for c in RrdReader(record).stream() if c.entity_path == entity]
        assert len(chunks) == 1 and not chunks[0].is_static
        rows = _rows(record, entity)
        for key in style:
            assert rows[0][key] and all(r[key] is None for r in rows[1:])
    scene = tomllib.loads((ROOT / "scenes" / "drawer_pinch.toml").read_text())
    (first, *_) = _rows(record, "/world/cables/loop")
    assert first["Capsules3D:radii"] == [pytest.approx(scene["cables"][0]["radius"], rel=1e-6)]
    assert first["Capsules3D:fill_mode"] == [3]                         # solid: shaded, not a wireframe


def test_frames_recorded_for_an_event_alone_keep_only_what_changes(pinch):
    """Frames between the run's samples (every 10 ms here) are recorded where an
    event starts or ends: there a cable's shape is kept only if its state
    colours change, and the cable's measures (strain, bend, twist) not at all.
    An event's worst instant is a whole frame (its shape and measures), and so
    is, in each checked batch, the last state at which an event deepened (its
    worst so far: the batch cannot know the states after it)."""
    report, record = pinch
    (ev,) = report["events"]
    on_grid = lambda t: abs(t / 0.01 - round(t / 0.01)) < 1e-6 or t == pytest.approx(report["settings"]["t_end"])
    deepening = lambda t: ev["t_start"] - 1e-9 <= t <= ev["t_worst"] + 1e-9      # noqa: E731
    strain = [r["t"] for r in _rows(record, "/cables/strain/loop") if r["t"] is not None]
    assert strain and all(on_grid(t) or deepening(t) for t in strain)
    deepest = {t for t in strain if not on_grid(t)}
    on_grid = lambda t: (abs(t / 0.01 - round(t / 0.01)) < 1e-6 or t == pytest.approx(report["settings"]["t_end"])  # noqa: E731
                         or t in deepest)
    rows = [r for r in _rows(record, "/world/cables/loop") if r["t"] is not None]
    off = [k for k, r in enumerate(rows) if not on_grid(r["t"])]
    assert rows[off[0]]["t"] == pytest.approx(ev["t_start"])          # the clash shows when it starts
    for k in off:                                                       # each gives its new colours
        assert rows[k]["Capsules3D:colors"] is not None
        assert _colours_at(rows, rows[k]["t"]).tolist() != _colours_at(rows, rows[k - 1]["t"]).tolist()
    events = {round(r["t"], 6) for r in _rows(record, "/events")}
    assert any(not on_grid(t) for t in events)                          # there are event-only frames


def test_a_series_keeps_only_what_changes_and_its_line_stays_within_a_bin():
    """A still stretch, a parabola and a break: few rows, the drawn line within
    the resolution of every value, breaks, ends and extremes kept; a brute-force
    reference (every value against the line through the kept ones)."""
    from cablecheck.record.series import RESOLUTION, changes
    rng = np.random.default_rng(7)
    t = np.sort(rng.uniform(0.0, 1.0, 400))
    v = np.where(t < 0.3, 5.0, 5.0 - 8.0 * (t - 0.3) ** 2) + 1e-7 * rng.standard_normal(400)
    v[250:260] = np.nan                                     # the pair left the check for a while
    keep = changes(t, v)
    assert keep.sum() < 0.25 * len(v)
    assert keep[0] and keep[-1] and keep[np.nanargmin(v)] and keep[np.nanargmax(v)]
    assert keep[249:261].all()                              # the break and its ends are kept
    span = np.nanmax(v) - np.nanmin(v)
    for part in (slice(0, 250), slice(260, 400)):         # the drawn line, run by run
        tt, vv, kk = t[part], v[part], keep[part]
        drawn = np.interp(tt, tt[kk], vv[kk])
        assert np.abs(drawn - vv).max() <= RESOLUTION * span
    assert changes(np.arange(5.0), np.full(5, 2.0)).tolist() == [True, False, False, False, True]
    assert changes(np.arange(3.0), np.array([np.nan, 1.0, np.nan])).all()


def test_many_series_at_once_are_each_on_its_own():
    from cablecheck.record.series import changes, changes_many
    rng = np.random.default_rng(11)
    ts = [np.sort(rng.uniform(0, 1, n)) for n in (1, 2, 7, 64, 300)]
    vs = [np.cumsum(rng.standard_normal(len(t))) * s for t, s in zip(ts, (1.0, 0.0, 1e3, 1e-6, 1.0))]
    vs[3][10:12] = np.nan
    for k, t, v in zip(changes_many(ts, vs), ts, vs):
        one = changes(t, v)
        assert k.tolist() == one.tolist()


def test_plane_is_drawn_sized_to_the_scene_or_as_given():
    from cablecheck.record.scene import plane_half_sizes
    pose = np.eye(4)
    pose[:3, 3] = [1.0, 0.0, 0.0]
    pts = np.array([[0.0, -0.5, 0.3], [3.0, 0.2, 0.1]])
    assert np.allclose(plane_half_sizes(np.zeros(3), pose, pts), [2.4, 0.6])
    tilted = np.eye(4)
    tilted[:3, :3] = [[0, 0, 1], [0, 1, 0], [-1, 0, 0]]     # normal along +x: local x is world -z
    assert np.allclose(plane_half_sizes(np.zeros(3), tilted, pts), [0.36, 0.6])
    assert np.allclose(plane_half_sizes(np.array([0.5, 0.25, 0.1]), pose, pts), [0.5, 0.25])


@pytest.mark.parametrize("fixture", ["pinch", "crossing"])
def test_every_events_worst_instant_is_a_frame_with_the_reports_distance(fixture, request):
    """The clash list's time, scrubbed to, shows the report's distance: each
    event's worst state is recorded at its exact time (not the sample
    before it), with the pair's distance and spot as the report has them."""
    report, record = request.getfixturevalue(fixture)
    assert report["events"]
    for event in report["events"]:
        kind, a, b = event["type"], event["a"], event["b"]
        rows = [r for r in _rows(record, f"/checks/{pair_path(kind, a, b)}/distance") if r["t"] is not None]
        at = [r for r in rows if abs(r["t"] - event["t_worst"]) < 1e-9]
        assert len(at) == 1, (event, [r["t"] for r in rows][:20])
        value = at[0]["Scalars:scalars"][0]
        assert value == pytest.approx(event["min_distance"], rel=1e-9, abs=1e-12)


def test_each_capsule_joins_two_body_centres_in_the_closed_form(tmp_path: Path):
    """Closed form: body centres on a circle of radius R in z = 0 at angles
    theta_k, then straight down (-z, the capsule's own axis turned half
    round) and one element of no length. Element k's capsule, read back
    from a recording, starts at centre k, runs along the chord
    (-sin, cos, 0)(theta_mid) for 2 R sin(dtheta / 2) (down: along -z for
    its drop), ends at centre k + 1, at the cable's radius, solid, in the
    cable's colour, named by a label on a centre."""
    from types import SimpleNamespace

    import rerun as rr

    from cablecheck.record.cables import CableFrames, capsules
    big, r, n, drop = 80.0, 3.0, 25, 7.0
    theta = np.linspace(0.0, 1.5 * np.pi, n)
    ring = np.stack([big * np.cos(theta), big * np.sin(theta), np.zeros(n)], axis=-1)
    centres = np.concatenate([ring, ring[-1:] - [0.0, 0.0, drop], ring[-1:] - [0.0, 0.0, drop]])
    mid = 0.5 * (theta[1:] + theta[:-1])
    want_axis = np.concatenate([np.stack([-np.sin(mid), np.cos(mid), np.zeros(n - 1)], axis=-1),
                                [[0.0, 0.0, -1.0], [0.0, 0.0, 1.0]]])       # no length: +z, as it comes
    want_length = np.concatenate([np.full(n - 1, 2.0 * big * np.sin(0.5 * (theta[1] - theta[0]))), [drop, 0.0]])
    start, q, length = capsules(centres[None])
    assert np.allclose(start[0], centres[:-1]) and np.allclose(length[0], want_length, rtol=1e-12)
    assert np.allclose(np.linalg.norm(q, axis=-1), 1.0) and np.allclose(_axes(q[0]), want_axis, atol=1e-12)
    # through a recording and back, in float32
    rest_s = np.concatenate([[0.0], np.cumsum(want_length)])
    cable = SimpleNamespace(name="ring", rest_s=rest_s, element_length=want_length[0], radius=r)
    frames = CableFrames(SimpleNamespace(cables=[cable]), unit=1.0)
    frames.add(0, [centres], [])
    frames.add(1, [centres + [0.0, 0.0, 10.0]], [])
    record = tmp_path / "ring.rrd"
    rec = rr.RecordingStream(application_id="ring")
    rec.save(str(record))
    frames.send(rec, np.array([0.0, 0.1]))
    rec.disconnect()
    rows = _cable_rows(record, "ring")
    assert [row["t"] for row in rows] == [0.0, pytest.approx(0.1)]
    for row, lift in zip(rows, (0.0, 10.0)):
        got_start, got_end = _capsule_ends(row)
        assert np.allclose(got_start, centres[:-1] + [0.0, 0.0, lift], atol=1e-4)
        assert np.allclose(got_end, centres[1:] + [0.0, 0.0, lift], atol=1e-4)
        assert np.allclose(row["Capsules3D:lengths"], want_length, rtol=1e-6, atol=1e-6)
        assert np.allclose(_axes(row["Capsules3D:quaternions"])[:-1], want_axis[:-1], atol=1e-6)
        (label,) = row["Points3D:positions"]
        assert np.linalg.norm(_centres(row) - label, axis=1).min() < 1e-4
    assert rows[0]["Capsules3D:radii"] == [r] and rows[0]["Capsules3D:fill_mode"] == [3]
    assert rows[0]["Capsules3D:colors"] == [_packed(cable_colour(0))] * len(want_length)
    assert rows[1]["Capsules3D:colors"] is None                          # the states did not change
    assert not rows[1]["lengths_given"]                                  # nor the lengths (moved as one)
    assert rows[0]["Points3D:labels"] == ["ring"]


def test_each_cable_is_named_capsules_in_its_own_colour(crossing):
    """crossing: two leads, each a chain of capsules at its own radius, one
    per element, each from one body centre to the next (the report's final
    centres: the last shape kept, within `STILL` radii of them), in its own
    colour, named by a label on it; the two names apart; the cables' plots
    in their colours."""
    from cablecheck.record.cables import STILL
    report, record = crossing
    scene = tomllib.loads((ROOT / "scenes" / "crossing.toml").read_text())
    owns, names = [], []
    for i, cable in enumerate(scene["cables"]):
        rows = _cable_rows(record, cable["name"])
        assert rows                     # crossing's leads lie still: one shape each (`STILL`)
        assert rows[0]["Capsules3D:radii"] == [pytest.approx(cable["radius"], rel=1e-6)]
        for row in rows[:: max(1, len(rows) // 5)]:
            start, end = _capsule_ends(row)
            assert len(start) == report["cables"][i]["segments"]
            # a chain: each ends where the next starts (its length given again where it changed by `STILL` radii)
            assert np.abs(end[:-1] - start[1:]).max() <= STILL * cable["radius"] + 1e-3
            # the label on the cable, at one of its centres, all along the run
            (label,) = row["Points3D:positions"]
            assert np.linalg.norm(_centres(row) - label, axis=1).min() < 1e-3
        final = np.array(report["cables"][i]["final_points"])
        assert np.abs(_centres(rows[-1]) - final).max() <= STILL * cable["radius"] + 1e-3
        assert rows[0]["Points3D:labels"] == [cable["name"]]
        assert rows[0]["Points3D:colors"] == [_packed(cable_colour(i))]
        colours = _colours_at(rows, rows[-1]["t"])
        assert len(colours) == report["cables"][i]["segments"]
        own = np.bincount(np.unique(colours, return_inverse=True)[1]).argmax()
        owns.append(int(np.unique(colours)[own]))
        names.append(np.array(rows[0]["Points3D:positions"][0]))
        (strain, *_) = _rows(record, f"/cables/strain/{cable['name']}")
        assert strain["SeriesLines:colors"] == [_packed(cable_colour(i))]
    assert owns == [_packed(cable_colour(0)), _packed(cable_colour(1))]
    reserved = [_packed(c) for c in (*STATE_COLOURS.values(), SPOT, PART_COLOUR)]
    assert len(set(owns)) == 2 and not set(owns) & set(reserved)
    span = max(np.ptp(np.array(c["via"] if "via" in c else [c["start"]["pos"], c["end"]["pos"]]), axis=0).max()
               for c in scene["cables"])
    assert np.linalg.norm(names[0] - names[1]) > 0.05 * span


def test_the_palette_keeps_cables_apart_from_each_other_and_from_the_states():
    def far(a, b):                      # "redmean" colour distance
        r = 0.5 * (a[0] + b[0])
        d = np.subtract(a, b, dtype=float)
        return np.sqrt((2 + r / 256) * d[0] ** 2 + 4 * d[1] ** 2 + (2 + (255 - r) / 256) * d[2] ** 2)
    reserved = [*STATE_COLOURS.values(), SPOT, PART_COLOUR, CONTACT_COLOUR]
    for i, a in enumerate(CABLE_PALETTE):
        assert min(far(a, b) for b in reserved if b != STATE_COLOURS["clear"]) > 100
        assert min(far(a, b) for b in CABLE_PALETTE[i + 1:]) > 75 if i + 1 < len(CABLE_PALETTE) else True
    n = len(CABLE_PALETTE)
    assert cable_colour(0) == CABLE_PALETTE[0] and cable_colour(n) != cable_colour(0)


def test_labels_of_spots_shown_together_are_lifted_apart():
    """Two spots side by side whose labels would overlap: the second's goes
    up a label height; a spot far away, or at another frame, stays just
    above its sphere."""
    from cablecheck.record.marks import LABEL_ABOVE, label_lifts
    label = "hose_left / flange: -3.5 mm"
    rows = {"a": [(0, np.array([0.0, 0.0, 100.0]), None, label, "x", -3.5),
                  (1, np.array([0.0, 0.0, 100.0]), None, label, "x", -3.5)],
            "b": [(0, np.array([12.0, 0.0, 100.0]), None, label, "y", -3.5)],
            "c": [(0, np.array([500.0, 0.0, 100.0]), None, label, "z", -3.5)]}
    radii = {"a": 10.0, "b": 10.0, "c": 10.0}
    lifts = label_lifts(rows, radii, 8.0)
    assert lifts["a"].tolist() == [LABEL_ABOVE * 10.0] * 2 and lifts["c"].tolist() == [LABEL_ABOVE * 10.0]
    assert lifts["b"][0] >= LABEL_ABOVE * 10.0 + 8.0
    # where a step above is not exactly a step apart in floating point (it looped forever)
    odd = {p: [(0, np.array([0.1 * k, 0.0, 0.7]), None, label, "x", -1.0)] for k, p in enumerate("abcdef")}
    lifts = label_lifts(odd, dict.fromkeys(odd, 0.1), 0.30000000000000004)
    assert sorted(v[0] for v in lifts.values()) == pytest.approx(0.115 + 0.30000000000000004 * np.arange(6))



@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), n_pairs=st.integers(1, 60), spread=st.floats(1.0, 400.0),
       step=st.floats(0.5, 20.0))
def test_label_lifts_keep_labels_apart_as_low_as_they_can(seed, n_pairs, spread, step):
    """Drawn spots over a few frames, crowded or spread, labels of drawn
    lengths and depths: at most LABELS_SHOWN labels a frame, those of its
    deepest spots; no two shown at a frame overlap; each sits just above its
    sphere or exactly a step above a label placed before it that it would
    overlap across (as low as the stacking lets it)."""
    from cablecheck.record.marks import CHAR_WIDTH, LABEL_ABOVE, LABELS_SHOWN, label_lifts
    rng = np.random.default_rng(seed)
    rows, radii = {}, {}
    for p in range(n_pairs):
        frames = np.sort(rng.choice(6, size=int(rng.integers(1, 6)), replace=False))
        rows[f"pair{p:03d}"] = [(int(f), rng.uniform(-spread, spread, 3), None, "x" * int(rng.integers(3, 40)), "x",
                                 float(rng.uniform(-5.0, 2.0))) for f in frames]
        radii[f"pair{p:03d}"] = float(rng.uniform(0.5, 10.0))
    got = label_lifts(rows, radii, step)
    for f in range(6):
        at = [(p, k) for p in sorted(rows) for k, r in enumerate(rows[p]) if r[0] == f]
        shown = [(p, k) for p, k in at if not np.isnan(got[p][k])]
        assert len(shown) == min(len(at), LABELS_SHOWN)
        if len(at) > LABELS_SHOWN:
            deepest = max(rows[p][k][5] for p, k in shown)
            assert all(rows[p][k][5] >= deepest for p, k in at if (p, k) not in shown)
        z = {(p, k): rows[p][k][1][2] + got[p][k] for p, k in shown}
        for i, (p, k) in enumerate(shown):
            a, la = rows[p][k][1], rows[p][k][3]
            below = []
            for q, j in shown[:i]:
                b, lb = rows[q][j][1], rows[q][j][3]
                if np.hypot(a[0] - b[0], a[1] - b[1]) < 0.5 * CHAR_WIDTH * step * (len(la) + len(lb)):
                    assert abs(z[p, k] - z[q, j]) >= 0.999 * step
                    below.append(z[q, j])
            tol = 1e-9 * (spread + step)         # (a lift is kept as a height less the centre's)
            assert abs(got[p][k] - LABEL_ABOVE * radii[p]) <= tol or any(abs(z[p, k] - pz - step) <= tol for pz in below)




def test_a_spots_rows_sent_as_arrays_read_back_row_by_row(tmp_path):
    """ClashMarks._send_spot with frames in runs, gaps to another side or none
    (and one of zero length), a lifted label, a hidden one (NaN: no label and
    no point for it): read back,
    each frame holds its sphere, label point, label, gap, the line through it
    and a leader where lifted, in that order, and each run is emptied at the
    frame after it; built here one row at a time."""
    import rerun as rr
    from cablecheck.record.marks import GAP_WIDTH, LABEL_ABOVE, THIN_WIDTH, THROUGH, ClashMarks
    from cablecheck.record.columns import times as sim_time
    radius = 2.0
    frames = [0, 1, 2, 5, 6, 9]
    rng = np.random.default_rng(4)
    where = rng.uniform(-50, 50, (6, 3))
    other = [where[0] + [0.0, 0.0, -3.0], None, where[2] + [1.0, 2.0, 0.5], where[3].copy(), None,
             where[5] + [-4.0, 0.0, 0.0]]
    lifts = np.array([LABEL_ABOVE * radius, LABEL_ABOVE * radius + 7.0, np.nan, LABEL_ABOVE * radius,
                      LABEL_ABOVE * radius + 14.0, LABEL_ABOVE * radius])
    rows = [(f, w, o, f"a / b: {k}", "a", -1.0) for k, (f, w, o) in enumerate(zip(frames, where, other))]
    times = np.arange(12) * 0.01
    rec = rr.RecordingStream("spot-test")
    path = tmp_path / "spot.rrd"
    rec.save(str(path))
    ClashMarks._send_spot(rec, "cable-structure/a/b", rows, 10, lambda f: [sim_time(times[np.asarray(f, int)])],
                          radius, lifts)
    rec.disconnect()
    got = [r for r in _rows(path, "/world/interference/cable-structure/a/b") if r["t"] is not None]
    assert [round(r["t"] / 0.01) for r in got] == [0, 1, 2, 3, 5, 6, 7, 9]
    by_frame = {round(r["t"] / 0.01): r for r in got}
    for f in (3, 7):
        assert by_frame[f]["Ellipsoids3D:centers"] == [] and by_frame[f]["Points3D:labels"] == []
        assert not by_frame[f].get("LineStrips3D:strips")
    for k, (f, w, o) in enumerate(zip(frames, where, other)):
        r = by_frame[f]
        assert np.allclose(r["Ellipsoids3D:centers"], [w]) and np.allclose(r["Ellipsoids3D:half_sizes"], [[radius] * 3])
        shown = not np.isnan(lifts[k])
        top = w + [0.0, 0.0, lifts[k] if shown else LABEL_ABOVE * radius]
        # a hidden label (a crowded frame's) has no point to ride on either
        assert np.allclose(np.reshape(r["Points3D:positions"], (-1, 3)), [top] if shown else np.zeros((0, 3)))
        assert r["Points3D:labels"] == ([f"a / b: {k}"] if shown else [])
        lines, widths = [], []
        if o is not None:
            lines.append([w, o])
            widths.append(GAP_WIDTH * radius)
            d = o - w
            n = np.linalg.norm(d)
            if n > 1e-9 * radius:
                d = d / n
                lines.append([w - THROUGH * radius * d, w + THROUGH * radius * max(1.0, n / radius + 0.3) * d])
                widths.append(THIN_WIDTH * radius)
        if shown and lifts[k] > 1.01 * radius * LABEL_ABOVE:
            lines.append([w + [0.0, 0.0, radius], top])
            widths.append(0.5 * THIN_WIDTH * radius)
        assert np.allclose(np.array(r.get("LineStrips3D:strips") or [], float).reshape(-1, 2, 3),
                           np.array(lines, float).reshape(-1, 2, 3), rtol=1e-6, atol=1e-5)
        assert np.allclose(r.get("LineStrips3D:radii") or [], widths, rtol=1e-6)



def test_between_samples_only_the_updated_pairs_and_their_cables_are_given(tmp_path):
    """A frame between the regular samples (an event's worst instant) gives
    rows to its updated pairs and keeps their cables' shapes only: another
    clash still shown keeps its last row, its spot not emptied until the
    frame after it is last shown, and a cable of no updated pair (moved, its
    colours the same) keeps its last shape; a pair shown again after a gap
    gets a row though not asked for."""
    import rerun as rr
    from types import SimpleNamespace
    from cablecheck.record.cables import CableFrames
    from cablecheck.record.marks import ClashMarks, Mark
    rest = np.linspace(0.0, 100.0, 11)
    cables = [SimpleNamespace(name=n, rest_s=rest, element_length=10.0, radius=2.0) for n in ("a", "b")]
    built = SimpleNamespace(cables=cables, parts=[SimpleNamespace(name="p")])
    marks = ClashMarks(built, 1.0, "mm", None)
    frames = CableFrames(built, 1.0)
    line = np.stack([rest, np.zeros(11), np.zeros(11)], axis=1)
    on_part = lambda d: Mark("cable-structure", "a", "p", d, "soft", np.array([50.0, 0.0, 0.0]), 50.0, None)
    on_cable = lambda d: Mark("cable-cable", "a", "b", d, "soft", np.array([20.0, 0.0, 0.0]), 20.0, None)
    A, B = ("cable-structure", "a", "p"), ("cable-cable", "a", "b")
    script = [([on_part(1.0), on_cable(1.5)], None), ([on_part(0.5), on_cable(1.4)], {A}),
              ([on_part(0.6), on_cable(1.3)], set()), ([on_part(0.7)], None), ([on_part(0.8)], set()),
              ([on_part(0.9), on_cable(1.2)], set())]
    given = []
    for f, (ms, update) in enumerate(script):
        _, updated = marks.add(f, ms, [line + f, line + f], np.zeros((1, 4, 4)), update)
        frames.add(f, [line + f, line + f], ms, True, None if update is None else {n for _, a, b in updated for n in (a, b)})
        given.append(updated)
    assert given == [{A, B}, {A}, set(), {A}, set(), {B}]
    assert frames._frames == [[0, 1, 3, 5], [0, 3, 5]]
    record = tmp_path / "light.rrd"
    rec = rr.RecordingStream("light-test")
    rec.save(str(record))
    marks.send(rec, np.arange(6) * 0.01, (np.zeros(3), np.full(3, 100.0)), 2.0)
    rec.disconnect()
    def at(path):
        return {round(r["t"] / 0.01): len(r.get("Ellipsoids3D:centers") or []) for r in _rows(record, path)
                if r["t"] is not None}
    assert at("/world/interference/cable-structure/a/p") == {0: 1, 1: 1, 3: 1}
    assert at("/world/interference/cable-cable/a/b") == {0: 1, 3: 0, 5: 1}



def test_a_harness_of_many_elements_keeps_its_shapes_within_the_budget(tmp_path):
    """A crossing harness of 26 cables of 40 elements (1,040 elements, over
    CABLE_SHAPES / RECORD_RATE): its cables' shapes come at every second
    regular sample at most (and at their own events' instants between
    samples); each event's worst instant still shows its spot, and its
    cables' last shape then lies within a quarter radius of their centres."""
    from cablecheck.bench.crossing import crossing_scene
    from cablecheck.bench.harness import write_scene
    from cablecheck.run.runner import CABLE_SHAPES, RECORD_RATE
    data = crossing_scene(26, 5, segments=40, duration=0.06, settle=0.1)
    scene = write_scene(data, tmp_path / "c.toml")
    record = tmp_path / "c.rrd"
    assert main(["run", str(scene), "--record", str(record), "--quiet", "--fail-on", "never",
                 "--report", str(tmp_path / "c.json")]) == 0
    report = json.loads((tmp_path / "c.json").read_text())
    assert 26 * 40 * RECORD_RATE > CABLE_SHAPES
    samples = np.round(np.arange(0.0, 0.06 + 1e-9, 1.0 / RECORD_RATE), 6)
    events = [e for e in report["events"] if e["type"] == "cable-cable"]
    assert events
    from cablecheck.record.style import escape
    for c in data["cables"]:
        times = np.round([r["t"] for r in _cable_rows(record, escape(c["name"]))], 6)
        assert len(times)
        own = {round(e["t_worst"], 6) for e in events if c["name"] in (e["a"], e["b"])} | \
              {round(e["t_start"], 6) for e in events if c["name"] in (e["a"], e["b"])}
        regular = [t for t in times if t in samples and t not in own]
        odd = [t for t in regular if round(t * RECORD_RATE) % 2 and t < samples[-1]]
        assert not odd, (c["name"], odd)
    from cablecheck.record.style import pair_path
    for e in events[:5]:
        spot = [r for r in _rows(record, f"/world/interference/{pair_path('cable-cable', e['a'], e['b'])}")
                if r["t"] is not None and r["t"] == pytest.approx(e["t_worst"], abs=1e-9)]
        assert spot and spot[0]["Ellipsoids3D:centers"]


FLOOR_SCENE = """
[scene]
name = "on-floor"
units = "mm"
duration = 0.05
settle = 0.05

[effects]
contact = []

[check]
clearance = 2.0

[[parts]]
name = "floor"
shape = "plane"

[[parts]]
name = "post"
shape = "box"
size = [5, 5, 30]
pos = [0, 0, 30]

[[cables]]
name = "lead"
radius = 3.0
start = { pos = [-60, 0, 40] }
end = { pos = [60, 0, 40] }
length = 121.0
segments = 10
"""


def test_floors_are_translucent_and_more_so_while_a_clash_is_shown(tmp_path: Path):
    scene = tmp_path / "on_floor.toml"
    scene.write_text(FLOOR_SCENE)
    record = tmp_path / "f.rrd"
    assert main(["run", str(scene), "--record", str(record), "--quiet", "--fail-on", "never"]) == 0
    report = json.loads(record.with_suffix(".json").read_text())
    assert report["events"]                                  # the lead runs through the post from the start
    colours = [c for r in _rows(record, "/world/parts/floor") if r.get("Boxes3D:colors") for c in r["Boxes3D:colors"]]
    assert colours and all(c & 255 < 255 for c in colours)   # translucent throughout
    assert set(colours) <= {_packed(FLOOR), _packed(FLOOR_DIMMED)} and _packed(FLOOR_DIMMED) in colours


@settings(max_examples=examples(60), deadline=None)
@given(amounts=st.lists(st.sampled_from([0.0, 0.5, 1.0, 2.0]) | st.floats(0, 10), min_size=0, max_size=20))
def test_the_charted_cables_are_the_most_worn_in_scene_order(amounts):
    """Against a sort of every cable by amount, then scene order: the first `CHARTED_CABLES` of it."""
    names = [f"c{k}" for k in range(len(amounts))]
    picked = charted(names, amounts)
    ranked = sorted(range(len(amounts)), key=lambda k: (-amounts[k], k))[:CHARTED_CABLES]
    assert picked == tuple(names[k] for k in sorted(ranked))


def test_a_harness_of_more_cables_than_charts_charts_the_most_worn_and_says_so(tmp_path: Path, monkeypatch):
    """Three cables on the plate, one end dragged along it: with one chart allowed, the dragged cable's
    wear is charted (data and view), the still ones' are not, the wear map still draws all three, and
    the summary names the charted cable."""
    monkeypatch.setattr(wearview, "CHARTED_CABLES", 1)
    still = "".join(f"""
[[cables]]
name = "{name}"
radius = 3.0
start = {{ pos = [-60, {y}, 120] }}
via = [ [0, {y}, 3] ]
end = {{ pos = [200, {y}, 3] }}
segments = 24
""" for name, y in (("still_a", 40), ("still_b", -40)))
    scene = tmp_path / "three.toml"
    scene.write_text(ON_PLATE + still)
    record = tmp_path / "t.rrd"
    assert main(["run", str(scene), "--record", str(record), "--quiet", "--fail-on", "never"]) == 0
    report = json.loads(record.with_suffix(".json").read_text())
    most = max(report["cables"], key=lambda c: max(c["wear"]["sliding"]))["name"]
    assert most == "lead"
    entities = _entities(record)
    assert {e for e in entities if e.startswith("/wear/")} == {f"/wear/lead/{m}" for m in
                                                               ("contact_time", "sliding", "bend_cycles")}
    assert {f"/wear_map/{c}" for c in ("lead", "still_a", "still_b")} <= entities
    reader = RrdReader(record)
    (store,) = reader.blueprints()
    views = [n for chunk in reader.stream(store=store) for batch in [chunk.to_record_batch()]
             if "ViewBlueprint:display_name" in batch.schema.names
             for row in batch.column("ViewBlueprint:display_name").to_pylist() for n in row]
    assert sorted(v.split(":")[0] for v in views if v.startswith("Wear ") and "per bin" in v) == ["Wear lead"] * 3
    (summary,) = _rows(record, "/summary")
    assert "wear bar charts of the 1 most worn of 3 cables (lead)" in summary["TextDocument:text"][0]


@settings(max_examples=examples(25), deadline=None)
@given(seed=st.integers(0, 2**31), step=st.sampled_from([0.0, 0.01, 0.05, 0.3]), n=st.integers(2, 40),
       drift=st.sampled_from([0.0, 0.02]))
def test_a_still_spot_is_stored_once_and_every_frame_shows_it_within_its_tolerance(tmp_path_factory, seed,
                                                                                     step, n, drift):
    """A spot resting, jittering (steps of `step` radii a frame) or drifting slowly (`drift` radii a frame
    along x, under the tolerance each frame; gaps coming and going, labels shown at
    some frames, runs broken, frames between samples): read back, what the viewer shows at every frame
    (the last row at or before it) is the frame's spot within SPOT_STILL radii, its gap there exactly when
    the frame has one, its label exactly at the labelled frames (and no other); rows between samples and
    at a run's start are all there."""
    import rerun as rr
    from cablecheck.record.columns import times as sim_time
    from cablecheck.record.marks import LABEL_ABOVE, SPOT_STILL, ClashMarks
    rng = np.random.default_rng(seed)
    radius = 2.0
    frames = np.sort(rng.choice(np.arange(3 * n), n, replace=False))
    where = 100.0 + np.cumsum(rng.normal(0.0, step * radius, (n, 3)), axis=0)
    where[:, 0] += drift * radius * frames
    gap = rng.random(n) < 0.7
    other = [w + [0.0, 0.0, -3.0] + rng.normal(0.0, step * radius, 3) if g else None for w, g in zip(where, gap)]
    labelled = rng.random(n) < 0.3
    lifts = np.where(labelled, LABEL_ABOVE * radius, np.nan)
    between = {int(f) for f in frames if rng.random() < 0.1}
    rows = [(int(f), w, o, f"a / b: {k}", "a", -1.0) for k, (f, w, o) in enumerate(zip(frames, where, other))]
    times = np.arange(3 * n + 2) * 0.01
    rec = rr.RecordingStream("still-spot")
    path = tmp_path_factory.mktemp("s") / "s.rrd"
    rec.save(str(path))
    ClashMarks._send_spot(rec, "cable-cable/a/b", rows, 3 * n + 1, lambda f: [sim_time(times[np.asarray(f, int)])],
                          radius, lifts, list(frames), np.array(sorted(between), np.int64))
    rec.disconnect()
    got = [r for r in _rows(path, "/world/interference/cable-cable/a/b") if r["t"] is not None]
    at = [round(r["t"] / 0.01) for r in got]
    assert at == sorted(at)
    for k, f in enumerate(frames.tolist()):
        if f in between or k == 0 or f - 1 not in frames:
            assert f in at                                      # an event's instant, a run's start: as measured
        last = max(i for i, g in enumerate(at) if g <= f)
        shown = {key: next((got[i][key] for i in range(last, -1, -1) if got[i].get(key) is not None), None)
                 for key in ("Ellipsoids3D:centers", "Points3D:labels", "LineStrips3D:strips")}
        assert np.abs(np.array(shown["Ellipsoids3D:centers"]) - where[k]).max() <= SPOT_STILL * radius + 1e-4
        assert shown["Points3D:labels"] == ([f"a / b: {k}"] if labelled[k] else [])
        strips = shown["LineStrips3D:strips"] or []
        if gap[k]:
            assert np.abs(np.array(strips[0][1]) - other[k]).max() <= SPOT_STILL * radius + 1e-4
        else:
            assert not strips                               # no gap, and a label just above: no leader
    if step == 0.0 and drift == 0.0 and not gap.any() and not labelled.any() and not between:
        last_of_run = frames[np.r_[np.diff(frames) > 1, True]]
        # one row per run and its emptying (none after the recording's last frame)
        assert len(got) == len(last_of_run) + int(np.sum(last_of_run + 1 < 3 * n + 1))


@settings(max_examples=examples(40), deadline=None)
@given(seed=st.integers(0, 2 ** 32 - 1), mm=st.booleans())
def test_a_frames_element_states_are_each_marks_own(seed, mm):
    """Cables of drawn element counts and lengths (m or mm), a frame's drawn
    marks (soft and hard, taut ones, on one cable or two, on an unknown
    cable, places at an element's reach exactly): each element's state, all
    marks at once, is what taking the marks one by one gives (the highest
    rank of the marks whose place on the element's cable lies within the
    cable's reach of the element's middle; a taut mark: all its cable)."""
    from types import SimpleNamespace

    from cablecheck.record.cables import _RANK, CableFrames
    from cablecheck.record.marks import Mark
    rng = np.random.default_rng(seed)
    unit = 1000.0 if mm else 1.0
    cables = []
    for k in range(int(rng.integers(1, 5))):
        n = int(rng.integers(2, 30))
        rest = np.r_[0.0, np.cumsum(rng.uniform(0.005, 0.03, n - 1))] * unit
        cables.append(SimpleNamespace(name=f"c{k}", rest_s=rest, element_length=float(np.diff(rest).mean()),
                                      radius=float(rng.uniform(0.002, 0.01)) * unit))
    frames = CableFrames(SimpleNamespace(cables=cables), unit=1.0)
    names = [c.name for c in cables] + ["elsewhere"]
    marks = []
    for _ in range(int(rng.integers(0, 12))):
        a, b = rng.choice(names, 2)
        kind = rng.choice(["cable-structure", "cable-cable", "taut", "bend"])
        ca = next((c for c in cables if c.name == a), cables[0])
        s = float(rng.uniform(-0.1, 1.1) * ca.rest_s[-1])
        if rng.random() < 0.3:                                       # exactly at an element's reach
            mid = 0.5 * (ca.rest_s[1:] + ca.rest_s[:-1])
            s = float(mid[rng.integers(len(mid))] + max(2.0 * ca.element_length, 3.0 * ca.radius))
        s_b = float(rng.uniform(0.0, 1.0) * unit) if kind == "cable-cable" else None
        marks.append(Mark(str(kind), str(a), str(b), 0.0, str(rng.choice(["soft", "hard"])), np.zeros(3), s, s_b))
    want = [np.zeros(len(c.rest_s) - 1, np.uint8) for c in cables]
    index = {c.name: i for i, c in enumerate(cables)}
    for m in marks:                                                       # one mark at a time
        for name, s, whole in ((m.a, m.s, m.kind == "taut"), (m.b, m.s_b, False)):
            if name not in index or s is None:
                continue
            c = cables[index[name]]
            mid = 0.5 * (c.rest_s[1:] + c.rest_s[:-1])
            near = np.ones(len(mid), bool) if whole else \
                np.abs(mid - s) <= max(2.0 * c.element_length, 3.0 * c.radius)
            want[index[name]][near] = np.maximum(want[index[name]][near], _RANK[m.state])
    got = np.split(frames._element_states(marks), np.cumsum([len(w) for w in want])[:-1])
    for g, w in zip(got, want):
        np.testing.assert_array_equal(g, w)


THROUGH_BOX = """
[scene]
name = "through-box"
units = "mm"
duration = 0.1
settle = 0.1

[effects]
contact = []

[check]
clearance = 2.0

[[parts]]
name = "frame/post"
shape = "box"
size = [10, 10, 30]
pos = [0, 0, 40]

[[cables]]
name = "lead"
radius = 3.0
start = { pos = [-120, 0, 40] }
end = { pos = [120, 0, 40] }
length = 240.0
segments = 24
young = 1.0e9
density = 1500
"""


def test_no_frame_shows_a_pair_deeper_than_its_worst(pinch, tmp_path: Path):
    """A pair's distance line never reads below the report's worst of it:
    a lead straight through a post (nothing moves: -13 mm, half the post's
    10 mm side at its middle, 3 mm of radius more, at every frame) and
    drawer_pinch's panel through its loop. The full checks' candidates,
    drawn at their frames, once counted the points' error off their
    values (the bound the skip rule keeps), 1.24 mm deeper than the lead
    ever is."""
    scene = tmp_path / "through_box.toml"
    scene.write_text(THROUGH_BOX)
    record = tmp_path / "through_box.rrd"
    assert main(["run", str(scene), "--record", str(record), "--quiet", "--fail-on", "never",
                 "--report", str(record.with_suffix(".json"))]) == 0
    through = json.loads(record.with_suffix(".json").read_text()), record
    (event,) = through[0]["events"]
    assert event["min_distance"] == pytest.approx(-13.0, abs=1e-9)
    for report, rec in (through, pinch):
        for event in report["events"]:
            path = f"/checks/{pair_path(event['type'], event['a'], event['b'])}/distance"
            values = [r["Scalars:scalars"][0] for r in _rows(rec, path) if r["t"] is not None]
            assert np.nanmin(values) >= event["min_distance"] - 1e-9, (event["a"], event["b"], np.nanmin(values))
