"""Tests of cablecheck.checker.refine: method points' records near touching, and its near misses
past the clearance, measured again exactly, against an independent `Checker` with method exact on
the same drawn cable and part (primitives and meshes, turned, far from the origin), and the points'
error bound that decides which records are."""

import json

import numpy as np
import trimesh
from hypothesis import event, given, settings
from hypothesis import strategies as st

from cablecheck.checker.interference import Checker
from cablecheck.checker.interference.discrete import points_error
from cablecheck.checker.recheck import Recheck
from cablecheck.checker.records import PairType, Severity
from cablecheck.checker.refine import near_miss_records, refined_records
from cablecheck.checker.scene_state import CableState, CheckConfig, Exclusion, PartState
from cablecheck.checker.shapes import Shape, ShapeType, mesh_shape
from helpers import examples
from strategies import coords, rotations

_BOX = trimesh.creation.box((0.06, 0.04, 0.05))
_SHAPES = {
    "box": Shape(ShapeType.BOX, [0.03, 0.02, 0.025]),
    "capsule": Shape(ShapeType.CAPSULE, [0.015, 0.03]),
    "mesh box": mesh_shape(_BOX.vertices, _BOX.faces),
    "mesh sphere": mesh_shape(trimesh.creation.icosphere(1, 0.03).vertices, trimesh.creation.icosphere(1, 0.03).faces),
}


def _record(recs, kind, name):
    found = [r for r in recs if PairType(r.type) is kind and r.b == name]
    return found[0] if found else None


def _top(kind: str, rot: np.ndarray) -> np.ndarray:
    """The part's highest point (turned by rot, about its origin)."""
    sh = _SHAPES[kind]
    if sh.type is ShapeType.BOX:
        pts = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]) * sh.size
    elif sh.type is ShapeType.CAPSULE:
        pts = np.array([[0, 0, -sh.size[1]], [0, 0, sh.size[1]]])
        pts = pts @ rot.T
        return pts[np.argmax(pts[:, 2])] + [0.0, 0.0, sh.size[0]]
    else:
        pts = np.asarray(sh.vertices, float)
    pts = pts @ rot.T
    return pts[np.argmax(pts[:, 2])]


@settings(max_examples=examples(60), deadline=None)
@given(st.sampled_from(sorted(_SHAPES)), rotations(), st.floats(0.0, np.pi), coords((5,), -0.004, 0.004),
       st.floats(-0.4, 1.5), coords(2, -0.01, 0.01), st.floats(0.002, 0.01), st.sampled_from([0.0, 500.0]),
       st.booleans())
def test_records_near_touching_are_the_exact_methods(kind, rot, heading, jitter, lift, off, radius, far, keepout):
    """A cable laid level across a drawn part's highest point at a drawn height (-0.4 to 1.5 radii
    off its surface there), its points jittered along it: a soft points record within the points'
    error of touching becomes method exact's record of the pair (the same value, severity and
    place, to rounding); a record farther out keeps the points' value; and the points never over-state
    exact's distance by more than that error where exact finds no overlap (so no exact-hard pair
    is left soft)."""
    top = _top(kind, rot)
    along = np.array([np.cos(heading), np.sin(heading), 0.0])
    steps = np.linspace(-0.05, 0.05, 5) + jitter
    line = top + np.array([off[0], off[1], radius * (1.0 + lift)]) + steps[:, None] * along
    pose = np.eye(4)
    pose[:3, :3], pose[:3, 3] = rot, far
    part = PartState("p", _SHAPES[kind], pose, keepout=keepout)
    cable = CableState("c", line + far, radius)
    clearance = 0.004
    points = Checker([part], CheckConfig(method="points", clearance=clearance)).check([cable])
    exact = Checker([part], CheckConfig(method="exact", clearance=clearance)).check([cable])
    ptype = PairType.KEEPOUT if keepout else PairType.CABLE_STRUCTURE
    p_rec, e_rec = _record(points, ptype, "p"), _record(exact, ptype, "p")
    err = points_error(radius, 2.0)
    rounding = 1e-12 * (1.0 + far)
    if e_rec is not None and e_rec.severity is Severity.HARD:
        assert p_rec is not None and p_rec.min_distance < err          # the refinement asks for it
    if p_rec is not None:
        assert e_rec is not None and e_rec.min_distance <= p_rec.min_distance + rounding
        if e_rec.min_distance >= 0.0:                 # the bound holds where exact finds no overlap
            assert p_rec.min_distance - e_rec.min_distance <= err + rounding
    recheck = Recheck([PartState("p", _SHAPES[kind], np.eye(4), keepout)], CheckConfig(clearance=clearance), [])
    swap = refined_records([points], lambda i: {"c": cable}, pose[None, None], recheck, {"c": err})[0]
    if p_rec is None:
        assert not swap
        return
    got = swap.get(id(p_rec), p_rec)
    event(f"points {p_rec.severity.value}{' near touching' if p_rec.min_distance < err else ''}, exact {e_rec.severity.value}")
    if p_rec.severity is Severity.SOFT and p_rec.min_distance <= err * (1 + 1e-9):    # at the bound too (refine)
        assert abs(got.min_distance - e_rec.min_distance) <= rounding   # two elements meeting at a point tie
        assert got.severity is e_rec.severity or abs(e_rec.min_distance) <= rounding
        assert np.allclose(got.where, e_rec.where, atol=rounding) and abs(got.s - e_rec.s) <= rounding
    else:
        assert got is p_rec


def test_a_corner_between_two_points_reads_as_touching():
    """A box's edge across a straight cable half way between two of its points (10 mm apart, r =
    5 mm), touching its surface: the points read the whole error bound, sqrt(r^2 + (h/2)^2) - r =
    2.07 mm; the refined record reads what exact does, 0 (soft, touching); the edge 0.1 mm further
    in, -0.1 mm (hard)."""
    r, half = 0.005, 0.01
    cable = CableState("c", np.array([[-0.03, 0.0, 0.0], [0.0, 0.0, 0.0], [0.01, 0.0, 0.0], [0.04, 0.0, 0.0]]), r)
    cfg = CheckConfig(clearance=0.003, spacing=2.0)
    err = points_error(r, 2.0)
    for depth, severity in ((0.0, Severity.SOFT), (1e-4, Severity.HARD)):
        pose = np.eye(4)                               # a box turned 45 degrees about y: an edge up, along y
        pose[:3, :3] = [[np.sqrt(0.5), 0.0, np.sqrt(0.5)], [0.0, 1.0, 0.0], [-np.sqrt(0.5), 0.0, np.sqrt(0.5)]]
        pose[:3, 3] = [0.005, 0.0, -(r - depth) - half * np.sqrt(2.0)]
        part = PartState("p", Shape(ShapeType.BOX, [half, 0.05, half]), pose)
        rec = _record(Checker([part], cfg).check([cable]), PairType.CABLE_STRUCTURE, "p")
        assert abs(rec.min_distance - (np.hypot(0.005, r - depth) - r)) < 1e-6     # to the edge or a face beside it
        recheck = Recheck([PartState("p", part.shape, np.eye(4))], cfg, [])
        got = refined_records([[rec]], lambda i: {"c": cable}, pose[None, None], recheck, {"c": err})[0][id(rec)]
        assert got.severity is severity
        assert abs(got.min_distance + depth) < 1e-12
        assert abs(got.where[0] - 0.005) < 1e-9


@settings(max_examples=examples(60), deadline=None)
@given(st.sampled_from(sorted(_SHAPES)), rotations(), st.floats(0.0, np.pi), coords((5,), -0.004, 0.004),
       coords(2, -0.01, 0.01), st.floats(0.002, 0.01), st.floats(0.0, 1.0), st.sampled_from([0.0, 500.0]),
       st.booleans())
def test_no_pair_exact_finds_inside_the_clearance_is_left_clear(kind, rot, heading, jitter, off, radius, at,
                                                                 far, keepout):
    """A cable laid level across a drawn part's highest point, its surface drawn between the
    clearance and the clearance plus the points' error above it: whatever the points read, the pair
    has a record exactly where method exact finds one, either the points' own or, for a near miss
    (the points at or past the clearance by less than their error), exact's, the same value to
    rounding."""
    clearance = 0.004
    err = points_error(radius, 2.0)
    top = _top(kind, rot)
    along = np.array([np.cos(heading), np.sin(heading), 0.0])
    steps = np.linspace(-0.05, 0.05, 5) + jitter
    line = top + np.array([off[0], off[1], radius + clearance - err + at * 2.0 * err]) + steps[:, None] * along
    pose = np.eye(4)
    pose[:3, :3], pose[:3, 3] = rot, far
    part = PartState("p", _SHAPES[kind], pose, keepout=keepout)
    cable = CableState("c", line + far, radius)
    checked = Checker([part], CheckConfig(method="points", clearance=clearance)).check_with_gaps([cable])
    exact = Checker([part], CheckConfig(method="exact", clearance=clearance)).check([cable])
    ptype = PairType.KEEPOUT if keepout else PairType.CABLE_STRUCTURE
    p_rec, e_rec = _record(checked.records, ptype, "p"), _record(exact, ptype, "p")
    recheck = Recheck([PartState("p", _SHAPES[kind], np.eye(4), keepout)], CheckConfig(clearance=clearance), [])
    found = near_miss_records([checked.near_misses], lambda i: {"c": cable}, pose[None, None], recheck)[0]
    n_rec = _record(found, ptype, "p")
    rounding = 1e-12 * (1.0 + far)
    near = _record(checked.near_misses, ptype, "p")
    event("points record" if p_rec else ("near miss, inside by exact" if n_rec else
                                         ("near miss, clear by exact" if near else "clear")))
    assert p_rec is None or n_rec is None and near is None      # a pair is a record or a near miss, not both
    if near is not None:
        assert clearance <= near.min_distance < clearance + err
    if e_rec is None:
        assert p_rec is None and n_rec is None
    elif p_rec is None:
        assert n_rec is not None and abs(n_rec.min_distance - e_rec.min_distance) <= rounding
        assert n_rec.severity is e_rec.severity


@settings(max_examples=examples(60), deadline=None)
@given(st.sampled_from(["box", "mesh box"]), rotations(), st.floats(0.0, 2.0 * np.pi), st.integers(1, 3),
       st.floats(1.0, 6.0), st.floats(0.0, 0.3), st.floats(-0.5, 2.0), st.floats(0.002, 0.01),
       st.sampled_from([0.0, 500.0]))
def test_a_window_end_is_checked_as_the_element_beyond_it(kind, rot, heading, j, element, slope, at, radius, far):
    """A cable leaving a part from inside an attachment window (its start
    clamped there), rising away at a drawn slope, the window ending on its
    vertex j: nearest the part outside the window is that vertex, where the
    element beyond the window begins. Method exact measures that element
    whole and MuJoCo's contacts are filtered by elements the same way: the
    points must check the point there too, so that wherever exact finds the
    pair inside the clearance, the points (with their near misses measured
    again) have its record, the same value to rounding. (A rotary table's
    cable, clamped beside a column, ran along the column's edge 2.19 mm
    from it, inside 3 mm, a soft contact exact and MuJoCo both found, past
    the window's last point the points left out: 83 % agreement.)"""
    clearance = 0.004
    err = points_error(radius, 2.0)
    top = _top(kind, rot)
    along = np.array([np.cos(heading), np.sin(heading), 0.0])
    arc = element * radius * np.arange(6)
    # the surface distance at vertex j: drawn from half a radius inside to twice the error past the clearance
    lift = radius + at * (clearance + 2.0 * err) - slope * arc[j]
    line = top + np.array([0.0, 0.0, lift]) + arc[:, None] * along + (slope * arc)[:, None] * [0.0, 0.0, 1.0]
    pose = np.eye(4)
    pose[:3, :3], pose[:3, 3] = rot, far
    part = PartState("p", _SHAPES[kind], pose)
    cable = CableState("c", line + far, radius, rest_s=arc)
    window = [Exclusion("c", "p", 0.0, float(arc[j]), "start")]
    checked = Checker([part], CheckConfig(method="points", clearance=clearance)).check_with_gaps([cable], None, window)
    exact = Checker([part], CheckConfig(method="exact", clearance=clearance)).check([cable], None, window)
    p_rec, e_rec = _record(checked.records, PairType.CABLE_STRUCTURE, "p"), _record(exact, PairType.CABLE_STRUCTURE, "p")
    recheck = Recheck([PartState("p", _SHAPES[kind], np.eye(4))], CheckConfig(clearance=clearance), window)
    n_rec = _record(near_miss_records([checked.near_misses], lambda i: {"c": cable}, pose[None, None], recheck)[0],
                    PairType.CABLE_STRUCTURE, "p")
    event("points record" if p_rec else ("near miss, inside by exact" if n_rec else "clear"))
    rounding = 1e-12 * (1.0 + far)
    if e_rec is None:
        assert p_rec is None and n_rec is None
        return
    assert e_rec.s >= arc[j] - rounding                  # nothing inside the window
    got = p_rec if p_rec is not None else n_rec
    assert got is not None
    if p_rec is None or p_rec.min_distance <= err * (1 + 1e-9):
        if p_rec is not None:
            got = refined_records([checked.records], lambda i: {"c": cable}, pose[None, None], recheck,
                                  {"c": err})[0].get(id(p_rec), p_rec)
        assert abs(got.min_distance - e_rec.min_distance) <= rounding
    else:
        assert e_rec.min_distance <= got.min_distance + rounding <= e_rec.min_distance + err + 2 * rounding


def test_a_corner_just_past_the_clearance_by_points_is_a_record_by_exact():
    """The box edge of the test above, 1 mm from the cable's surface half way between two points
    (r = 5 mm, 10 mm apart), with a 2 mm clearance: the points read 3.07 mm, past it, a near miss;
    exact finds 1 mm, a soft record."""
    r, half = 0.005, 0.01
    cable = CableState("c", np.array([[-0.03, 0.0, 0.0], [0.0, 0.0, 0.0], [0.01, 0.0, 0.0], [0.04, 0.0, 0.0]]), r)
    cfg = CheckConfig(clearance=0.002, spacing=2.0)
    pose = np.eye(4)
    pose[:3, :3] = [[np.sqrt(0.5), 0.0, np.sqrt(0.5)], [0.0, 1.0, 0.0], [-np.sqrt(0.5), 0.0, np.sqrt(0.5)]]
    pose[:3, 3] = [0.005, 0.0, -(r + 0.001) - half * np.sqrt(2.0)]
    part = PartState("p", Shape(ShapeType.BOX, [half, 0.05, half]), pose)
    checked = Checker([part], cfg).check_with_gaps([cable])
    assert _record(checked.records, PairType.CABLE_STRUCTURE, "p") is None
    near = _record(checked.near_misses, PairType.CABLE_STRUCTURE, "p")
    assert abs(near.min_distance - (np.hypot(0.005, r + 0.001) - r)) < 1e-6
    recheck = Recheck([PartState("p", part.shape, np.eye(4))], cfg, [])
    got = near_miss_records([[near]], lambda i: {"c": cable}, pose[None, None], recheck)[0]
    assert len(got) == 1 and got[0].severity is Severity.SOFT and abs(got[0].min_distance - 0.001) < 1e-12


EDGE_PASS = """
[scene]
name = "edge-pass"
units = "mm"
duration = 1.0
timestep = 0.01

[effects]
dynamics = false

[check]
clearance = 2.0
validate = false

[[bodies]]
name = "sled"

[[motion]]
body = "sled"
interpolation = "linear"
keys = [{ t = 0.0, pos = [0, 0, 0] }, { t = 1.0, pos = [40, 0, 0] }]

[[parts]]
name = "wedge"
body = "sled"
shape = "box"
size = [10, 30, 10]
euler = [0, 45, 0]
pos = [-20, 0, -20.642135623730951]

[[cables]]
name = "c"
radius = 5.0
start = { pos = [-100, 0, 0] }
end = { pos = [100, 0, 0] }
segments = 20
"""


def test_an_edge_sliding_along_a_cable_inside_the_clearance_is_one_event(tmp_path):
    """A box's edge slid 40 mm along a straight cable (r 5 mm, points 10 mm apart), 1.5 mm from its
    surface all the way, with a 2 mm clearance: half way between two points the points read 3.2 mm,
    past it (before: five soft events, the pair clear between them); measured exactly there, one soft
    event over the whole slide, at 1.5 mm, the same with the skip rule and checked in full."""
    from cablecheck.run.runner import RunOptions, run_scene
    from cablecheck.scene.load import load_scene

    path = tmp_path / "edge.toml"
    path.write_text(EDGE_PASS)
    reports = [run_scene(load_scene(path), RunOptions(report=tmp_path / f"{k}.json", record=None, advance=k == 0))
               for k in (0, 1)]
    for r in reports:
        assert [(e["type"], e["severity"]) for e in r["events"]] == [("cable-structure", "soft")]
        e = r["events"][0]
        assert (e["t_start"], e["t_end"]) == (0.0, 1.0) and abs(e["min_distance"] - 1.5) < 1e-9
    plain = [json.loads(json.dumps(r, default=lambda x: np.asarray(x).tolist())) for r in reports]
    assert plain[0]["events"] == plain[1]["events"] and plain[0]["pairs"] == plain[1]["pairs"]


@settings(max_examples=examples(60), deadline=None)
@given(rotations(), st.floats(0.1, np.pi / 2), coords((2, 6), -0.003, 0.003), st.floats(-0.6, 1.2),
       st.floats(0.002, 0.008), st.floats(0.002, 0.008), st.sampled_from([0.0, 500.0]), st.floats(0.0, 1.0))
def test_two_cables_pressed_together_read_as_exact_reads_them(rot, angle, jitter, gap, ra, rb, far, bow):
    """Two cables crossing at a drawn angle, their surfaces a drawn gap
    apart (from 0.6 of the smaller radius overlapping to 1.2 of it clear),
    the vertices jittered along them and one bowed: a soft cable-cable
    record by points becomes method exact's record of the pair (the same
    value to rounding, so its severity: two hoses pressed together read a
    few hundredths of a millimetre apart by points where exact and MuJoCo
    say they overlap); exact's value is never above the points'."""
    from cablecheck.checker.refine import refined_cable_records

    clearance = 0.004
    steps = np.linspace(-0.06, 0.06, 6)
    line_a = np.stack([steps + jitter[0], np.zeros(6), np.zeros(6)], axis=1)
    along = np.array([np.cos(angle), np.sin(angle), 0.0])
    centre = min(ra, rb) * gap + ra + rb
    line_b = (steps + jitter[1])[:, None] * along + [0.0, 0.0, centre]
    line_b[:, 2] += bow * 0.002 * (steps / 0.06) ** 2            # bowed away from a at its ends
    a = CableState("a", line_a @ rot.T + far, ra)
    b = CableState("b", line_b @ rot.T + far, rb)
    points = Checker([], CheckConfig(method="points", clearance=clearance)).check([a, b])
    exact = Checker([], CheckConfig(method="exact", clearance=clearance)).check([a, b])
    p_rec, e_rec = _record(points, PairType.CABLE_CABLE, "b"), _record(exact, PairType.CABLE_CABLE, "b")
    rounding = 1e-12 * (1.0 + far)
    if p_rec is None:
        return
    assert e_rec is not None and e_rec.min_distance <= p_rec.min_distance + rounding
    swap = refined_cable_records([points], lambda i: {"a": a, "b": b}, clearance)[0]
    got = swap.get(id(p_rec), p_rec)
    event(f"points {p_rec.severity.value}, exact {e_rec.severity.value}")
    if p_rec.severity is Severity.SOFT:
        assert abs(got.min_distance - e_rec.min_distance) <= rounding
        assert got.severity is e_rec.severity or abs(e_rec.min_distance) <= rounding
        assert abs(got.s - e_rec.s) <= 1e-9 * (1.0 + far) and abs(got.s_b - e_rec.s_b) <= 1e-9 * (1.0 + far)
    else:
        assert got is p_rec                          # hard by points: exact's is harder still


@settings(max_examples=examples(40), deadline=None)
@given(st.floats(0.002, 0.008), st.floats(-0.5, 1.5), st.floats(0.5, 3.0), rotations(), st.sampled_from([0.0, 500.0]),
       st.integers(3, 9))
def test_a_cable_pressed_on_its_own_turn_reads_as_exact_reads_it(radius, gap, leg, rot, far, per_leg):
    """A hairpin: two straight legs joined by a half turn, the legs' surfaces
    a drawn gap apart (from half a radius into each other to 1.5 radii
    clear), each leg a drawn number of elements: a soft self record by
    points becomes method exact's self record of the cable (the same value,
    so the same severity; MuJoCo's capsules agree with exact), never
    farther than the points'."""
    from cablecheck.checker.refine import refined_self_records

    clearance = 0.004
    centre = 2.0 * radius + gap * radius                  # the legs' axes apart
    length = leg * 0.05
    s = np.linspace(0.0, length, per_leg + 1)
    turn = np.linspace(0.0, np.pi, 9)[1:-1]
    bend = 0.5 * centre
    line = np.concatenate([
        np.stack([s[::-1], np.zeros_like(s), np.zeros_like(s)], axis=1)[:-1],
        np.stack([-bend * np.sin(turn), bend - bend * np.cos(turn), np.zeros_like(turn)], axis=1),
        np.stack([s, np.full_like(s, centre), np.zeros_like(s)], axis=1)])
    cable = CableState("c", line @ rot.T + far, radius)
    points = Checker([], CheckConfig(method="points", clearance=clearance)).check([cable])
    exact = Checker([], CheckConfig(method="exact", clearance=clearance)).check([cable])
    p_rec, e_rec = _record(points, PairType.SELF, "c"), _record(exact, PairType.SELF, "c")
    if p_rec is None:
        return
    assert e_rec is not None and e_rec.min_distance <= p_rec.min_distance + 1e-12 * (1.0 + far)
    got = refined_self_records([points], lambda i: {"c": cable}, clearance)[0].get(id(p_rec), p_rec)
    event(f"points {p_rec.severity.value}, exact {e_rec.severity.value}")
    # by hand: the legs run parallel, their axes `centre` apart, and far enough along them past
    # the self window, so the capsules come within centre - 2 r = gap r there (nearer still
    # where the half turn's chords pass the other leg, as a tight turn's do)
    assert e_rec.min_distance <= gap * radius + 1e-9 * (1.0 + far)
    if p_rec.severity is Severity.SOFT:
        assert got.min_distance == e_rec.min_distance and got.severity is e_rec.severity
    else:
        assert got is p_rec


_THROUGH = """
[scene]
name = "through"
units = "{units}"
duration = {duration}
settle = 0.0

[effects]
dynamics = false

[check]
clearance = {clearance}

[[bodies]]
name = "sheet"
pos = [{x0}, {far}, {far}]

[[parts]]
name = "sheet/plate"
body = "sheet"
shape = "box"
size = [{half}, {wide}, {wide}]
euler = [0, {tilt}, 0]

[[motion]]
body = "sheet"
keys = [ {{ t = 0.0, pos = [{x0}, {far}, {far}] }}, {{ t = {duration}, pos = [{x1}, {far}, {far}] }} ]

[[cables]]
name = "lead"
radius = {radius}
start = {{ pos = [{a}, {far}, {far}] }}
end = {{ pos = [{b}, {far}, {far}] }}
length = {length}
segments = {segments}
"""


def _through(tmp_path, method: str, **drawn) -> dict:
    scene = tmp_path / f"through_{method}.toml"
    scene.write_text(_THROUGH.format(**drawn))
    report = tmp_path / f"through_{method}.json"
    from cablecheck.cli.main import main

    assert main(["run", str(scene), "--no-record", "--report", str(report), "--quiet", "--fail-on", "never",
                 "--method", method]) == 0
    return json.loads(report.read_text())


@settings(max_examples=examples(5), deadline=None)
@given(radius=st.floats(2.0, 6.0), half=st.floats(0.05, 1.0), start=st.floats(0.0, 1.0), tilt=st.sampled_from([0, 25]),
       units=st.sampled_from(["mm", "m"]), far=st.sampled_from([0.0, 1.0e4]), segments=st.integers(8, 14))
def test_a_cable_through_a_sheet_reads_its_whole_depth_as_exact_does(tmp_path_factory, radius, half, start, tilt,
                                                                     units, far, segments):
    """A straight cable through a sheet thinner than the gap between its points, the sheet sliding
    along it by a few gaps over the run (dynamics off): method points' hard event is as deep as
    method exact's and the analytic depth (the radius plus half the sheet, square to the cable or
    tilted), though the points alone read it shallower by up to half a gap."""
    unit = 1.0 if units == "mm" else 1e-3
    r = radius * unit
    drawn = dict(units=units, duration=0.1, clearance=2.0 * unit, radius=r, half=half * unit, wide=60 * unit,
                 tilt=tilt, far=far * unit, a=-100 * unit, b=100 * unit, length=200 * unit, segments=segments,
                 x0=(start * 7.0 - 3.0) * unit, x1=(start * 7.0 + 8.0) * unit)
    tmp = tmp_path_factory.mktemp("through")
    got, want = _through(tmp, "points", **drawn), _through(tmp, "exact", **drawn)
    (ev,), (ex,) = got["events"], want["events"]
    assert ev["severity"] == ex["severity"] == "hard"
    depth = (radius + half) * unit          # the centreline through the sheet's middle, tilted or not
    scale = 1e-9 * (1.0 + far) * unit
    assert abs(ex["min_distance"] + depth) <= scale + 1e-9 * depth
    assert abs(ev["min_distance"] - ex["min_distance"]) <= scale + 1e-9 * depth


_CROSSED = """
[scene]
name = "crossed"
units = "mm"
duration = 0.02
settle = 0.0

[effects]
dynamics = false

[check]
clearance = 1.0

[[cables]]
name = "a"
radius = {ra}
start = {{ pos = [-100, 0, 0] }}
end = {{ pos = [100, 0, 0] }}
length = 200.0
segments = {segments}

[[cables]]
name = "b"
radius = {rb}
start = {{ pos = [{x}, -100, {z}] }}
end = {{ pos = [{x}, 100, {z}] }}
length = 200.0
segments = {segments}
"""


@settings(max_examples=examples(5), deadline=None)
@given(ra=st.floats(2.0, 5.0), rb=st.floats(2.0, 5.0), sink=st.floats(0.1, 0.9), x=st.floats(-10.0, 10.0),
       segments=st.integers(8, 12))
def test_two_cables_pressed_into_each_other_read_their_whole_overlap(tmp_path_factory, ra, rb, sink, x, segments):
    """Two straight cables crossing square, their centrelines `sink` of the radii's sum apart, where they
    cross drawn anywhere between points: the hard cable-cable event reads the analytic overlap (the
    centrelines' distance less both radii), as method exact does."""
    z = (1.0 - sink) * (ra + rb)
    tmp = tmp_path_factory.mktemp("crossed")
    scene = tmp / "crossed.toml"
    scene.write_text(_CROSSED.format(ra=ra, rb=rb, x=x, z=z, segments=segments))
    from cablecheck.cli.main import main

    assert main(["run", str(scene), "--no-record", "--report", str(tmp / "r.json"), "--quiet", "--fail-on", "never"]) == 0
    (ev,) = [e for e in json.loads((tmp / "r.json").read_text())["events"] if e["type"] == "cable-cable"]
    assert ev["severity"] == "hard" and abs(ev["min_distance"] - (z - ra - rb)) <= 1e-9 * (ra + rb)


@settings(max_examples=examples(60), deadline=None)
@given(st.lists(st.lists(st.tuples(st.sampled_from(["p", "q", "c"]), st.sampled_from(["hard", "soft"]),
                                   st.sampled_from([-2.0, -1.0, -0.5, 0.5]) | st.floats(-3.0, 1.0)),
                         max_size=3, unique_by=lambda x: x[0]), min_size=1, max_size=8),
       st.integers(1, 8))
def test_the_deepest_candidates_are_each_runs_deepest_hard_records_so_far(states, cut):
    """Against a loop over each pair's run of states: a hard record is a candidate exactly where no hard
    record of its pair earlier in its run (since the pair last had no record) is deeper (ties taken; soft
    records never are), whether the states come in one batch or two (`cut`)."""
    from cablecheck.checker.records import Interference
    from cablecheck.checker.refine import deepest_candidates

    kinds = {"p": (PairType.CABLE_STRUCTURE, "lead", "plate"), "q": (PairType.CABLE_STRUCTURE, "lead", "post"),
             "c": (PairType.CABLE_CABLE, "lead", "other")}
    records = [[Interference(kinds[k][0], kinds[k][1], kinds[k][2], v, Severity(sev), np.zeros(3), 0.0)
                for k, sev, v in recs] for recs in states]
    types = (PairType.CABLE_STRUCTURE, PairType.CABLE_CABLE)
    whole, _ = deepest_candidates(records, types)
    first, least = deepest_candidates(records[:cut], types)
    second, _ = deepest_candidates(records[cut:], types, least)
    assert first + second == whole
    for i, recs in enumerate(records):
        for r in recs:
            key = (r.type, r.a, r.b)
            start = i
            while start > 0 and any((x.type, x.a, x.b) == key for x in records[start - 1]):
                start -= 1
            before = [x.min_distance for s in records[start:i] for x in s
                      if (x.type, x.a, x.b) == key and x.severity is Severity.HARD]
            want = r.severity is Severity.HARD and all(r.min_distance <= b for b in before)
            assert (id(r) in whole[i]) == want
