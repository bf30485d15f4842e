"""Cables the simulation holds on a concave part's convex hull (cablecheck.detection.hullgap)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import trimesh
from test_detection_mesh import u_mesh

from cablecheck.build.stages import build
from cablecheck.detection.contacts import Contacts
from cablecheck.detection.hullgap import GAP_TOLERANCE, HullGaps, HullRaw, HullReader, watched
from cablecheck.run.runner import RunOptions, run_scene
from cablecheck.scene.load import load_scene

# the U of test_detection_mesh: prongs x in [-0.04, -0.02] and [0.02, 0.04]
# rising to z = 0.04 over a pocket whose floor is z = -0.02, 0.1 long in y;
# its hull's top face is z = 0.04 over the whole x in [-0.04, 0.04]
R = 0.005
"""Cable radius, metres (also the clearance)."""


def _scene(tmp_path, dynamics: bool = True, validate: bool = True, block: bool = False):
    """Two straight cables (r 5 mm) along y, held at y = +-0.1 (past the
    U's ends) on the hull's top (the simulation has no contact margin,
    cablecheck.build.mjspec.SIM_MARGIN_FRACTION), so each lies on the U's top: `over`
    in the middle, above the pocket (the hull's top face spans it there: the surface is the pocket's
    walls and floor, 15 mm and more away); `flat` at x = 0.03, on a prong's
    top face, which the hull shares. `block`: a convex mesh part too, first,
    out of the cables' way (a mesh whose hull is its surface: not watched)."""
    u_mesh().export(tmp_path / "u.stl")
    trimesh.creation.box(extents=[0.02, 0.02, 0.02]).export(tmp_path / "block.stl")
    extra = """
[[parts]]
name = "block"
shape = "mesh"
file = "block.stl"
pos = [0.3, 0.3, 0.0]
""" if block else ""
    z = 0.04 + R
    cables = "".join(f"""
[[cables]]
name = "{name}"
radius = {R}
start = {{ pos = [{x}, -0.1, {z}] }}
end = {{ pos = [{x}, 0.1, {z}] }}
segments = 20
""" for name, x in (("over", 0.0), ("flat", 0.03)))
    (tmp_path / "u.toml").write_text(f"""
[scene]
name = "hull"
units = "m"
duration = 0.02
settle = 0.4
[effects]
dynamics = {str(dynamics).lower()}
contact = ["cable-structure"]
[check]
clearance = {R}
validate = {str(validate).lower()}
[[bodies]]
name = "fixture"
""" + extra + """
[[parts]]
name = "u"
body = "fixture"
shape = "mesh"
file = "u.stl"
""" + cables)
    return load_scene(tmp_path / "u.toml")


def test_a_cable_on_the_hull_over_the_pocket_is_named_and_one_on_a_flat_face_is_not(tmp_path, capsys):
    rep = run_scene(_scene(tmp_path), RunOptions(report=tmp_path / "r.json", record=None))
    hull = [w for w in rep["physics_warnings"] if "convex hull" in w]
    (w,) = hull
    assert "cable 'over'" in w and "part 'u'" in w and "from t = 0.000 to 0.020 s" in w
    # the pocket's surface is beyond the clearance there: the gap is the
    # clearance less the hull distance, a bound; the cable rests on the hull
    # (no contact margin), less the contact's give: within 2 % of its radius
    gap = float(w.split("more than ")[1].split(" m ")[0])
    assert gap == pytest.approx(R, abs=0.02 * R)
    # the checker and MuJoCo's detection agree: `over` is clear of the U's
    # surface, `flat` lies within the clearance of the prong's top, as far
    # from it as `over` from the hull (both rest on the hull's top plane)
    assert [(e["a"], e["b"]) for e in rep["events"]] == [("flat", "u")]
    assert rep["events"][0]["min_distance"] == pytest.approx(R - gap, abs=0.02 * R)
    assert rep["validation"]["agreement"] == 1.0
    from cablecheck.cli.printing import print_summary
    print_summary(rep, tmp_path / "r.json")
    assert f"  warning: {w}" in capsys.readouterr().out


def test_no_watch_without_a_detection_model_or_a_stepped_simulation(tmp_path):
    built = build(_scene(tmp_path))
    assert [built.parts[i].name for i in watched(built)] == ["u"]
    assert watched(build(_scene(tmp_path, dynamics=False))).tolist() == []
    assert watched(build(_scene(tmp_path, validate=False), detect=False)).tolist() == []
    assert HullReader.of(build(_scene(tmp_path, dynamics=False))) is None


def _contacts(rows):
    """rows: (cable, part, element, dist) of the detection model, named."""
    if not rows:
        return Contacts(*(np.zeros(0, object),) * 3, np.zeros(0, int), np.zeros(0, int), np.zeros(0),
                        np.zeros((0, 3)))
    a, b, e, d = zip(*rows)
    n = len(rows)
    return Contacts(np.full(n, "cable-structure", object), np.array(a, object), np.array(b, object),
                    np.array(e), np.full(n, -1), np.array(d, float), np.zeros((n, 3)))


def _hulls(built, rows):
    """rows: (cable index, part index, element, dist) of the simulation, as
    MuJoCo lists them (`HullReader.raw`): the cable on either side (in turn),
    within the contact's margin."""
    n = len(rows)
    flex, geom, elem = (np.full((n, 2), -1, np.int64) for _ in range(3))
    for i, (c, p, e, _) in enumerate(rows):
        side = i % 2
        flex[i, side], geom[i, 1 - side], elem[i, side] = built.cables[c].flex_id, built.parts[p].geom_id, e
    dist = np.array([r[3] for r in rows], float)
    return HullRaw(flex, geom, elem, dist, dist + 1e-3)


@pytest.fixture(scope="module")
def gaps_built(tmp_path_factory):
    return build(_scene(tmp_path_factory.mktemp("hull")))


def test_gaps_are_element_by_element_the_surface_less_the_hull(gaps_built):
    g = HullGaps(gaps_built)
    over, flat = g.cables.index("over"), g.cables.index("flat")
    tol = GAP_TOLERANCE * R
    # state 0: `over` element 3 on the hull 1 mm, its surface 3 mm (a gap of 2 mm);
    # element 4 on the hull, no surface within the clearance (more than 4 mm);
    # `flat` element 5 on the hull 1 mm, the surface 1 mm + tol / 2 (within the tolerance);
    # a surface contact of another element and another cable's hull contact do not pair up
    g.take(np.array([0.5]),
           [_hulls(gaps_built, [(over, 0, 3, 0.001), (over, 0, 4, 0.001), (flat, 0, 5, 0.001)])],
           [_contacts([("over", "u", 3, 0.003), ("over", "u", 3, 0.0045), ("flat", "u", 5, 0.001 + tol / 2),
                       ("flat", "u", 6, 0.004)])])
    (found,) = g.found()
    assert (found.cable, found.part, found.t_start, found.t_end) == ("over", "u", 0.5, 0.5)
    assert found.gap == pytest.approx(R - 0.001) and found.bounded
    # later states: a larger measured gap wins and clears the bound; the span grows
    g.take(np.array([0.6, 0.7, 0.8]),
           [_hulls(gaps_built, [(over, 0, 3, 0.0)]), None, _hulls(gaps_built, [(over, 0, 7, 0.0005)])],
           [_contacts([("over", "u", 3, 0.0045)]), _contacts([]), _contacts([("over", "u", 7, 0.0006)])])
    (found,) = g.found()
    assert found.gap == pytest.approx(0.0045) and not found.bounded and (found.t_start, found.t_end) == (0.5, 0.6)
    (w,) = g.warnings()
    assert "up to 0.0045 m beyond the hull" in w and "from t = 0.500 to 0.600 s" in w


def test_contacts_numbered_by_a_shared_table_give_the_gaps_their_names_give(gaps_built):
    """Contacts carrying codes into one name table (as `ContactReader` gives
    them; a name twice, names of neither side) find the same gaps, spans
    and bounds as the same contacts by name."""
    from cablecheck.checker.validation import NameTable
    table = NameTable(np.array(["part-part", "cable-structure"], object),
                      np.array(["", "u", "over", "flat", "u", "frame", "over"], object))
    rng = np.random.default_rng(3)

    def coded(c):
        where = {}
        for i, x in enumerate(table.names.tolist()):
            where.setdefault(x, []).append(i)
        codes = np.array([[1, rng.choice(where[a]), rng.choice(where[b])] for a, b in zip(c.a, c.b)],
                         np.int64).reshape(-1, 3)
        return dataclasses.replace(c, codes=codes, table=table)

    by_name, by_code = HullGaps(gaps_built), HullGaps(gaps_built)
    over, flat = by_name.cables.index("over"), by_name.cables.index("flat")
    for k in range(6):
        drawn = zip(rng.integers(0, 8, 3), rng.uniform(0, 2e-3, 3))
        hulls = [_hulls(gaps_built, [(over, 0, int(e), float(d)) for e, d in drawn] + [(flat, 0, 5, 0.001)])]
        found = [_contacts([("over", "u", int(e), float(d)) for e, d in zip(rng.integers(0, 8, 4),
                                                                            rng.uniform(0, 5e-3, 4))]
                           + [("flat", "frame", 5, 0.003), ("flat", "u", 5, 0.004)])]
        by_name.take(np.array([0.1 * k]), hulls, found)
        by_code.take(np.array([0.1 * k]), hulls, [coded(c) for c in found])
    assert by_code.found() == by_name.found() and by_name.found()


def test_only_active_simulation_contacts_of_cables_with_watched_hulls_are_read(gaps_built):
    """The reader keeps contacts within their margin (MuJoCo's force
    threshold), either side order, and drops contacts of other geoms."""
    import mujoco

    from cablecheck.run.loop import Simulation
    sim = Simulation(gaps_built)
    sim.reset()
    sim.settle()
    d = sim.data
    rows = sim.hull.rows(d)
    n = int(d.ncon)
    con = d.contact
    part = gaps_built.parts[0].geom_id
    mine = [(i, con.flex[i], con.dist[i], con.includemargin[i]) for i in range(n)
            if part in con.geom[i] and max(con.flex[i]) >= 0]
    assert len(rows.dist) == sum(dist <= margin for _, _, dist, margin in mine) > 0
    assert set(rows.cable.tolist()) == {0, 1} and (rows.part == 0).all()
    assert mujoco.mjtGeom(int(gaps_built.model.geom_type[part])) == mujoco.mjtGeom.mjGEOM_MESH


def test_hull_rows_of_a_mesh_part_that_is_not_watched_are_left_out(tmp_path):
    """The simulation reads every mesh part's hull contacts (it runs before
    the detection model exists); the gaps keep the watched parts' only."""
    built = build(_scene(tmp_path, block=True))
    block = [p.name for p in built.parts].index("block")
    u = [p.name for p in built.parts].index("u")
    g = HullGaps(built)
    assert g.parts == ["u"] and block != u
    g.take(np.array([0.5]), [_hulls(built, [(0, block, 3, 0.001)])], [_contacts([])])
    assert g.found() == []
    g.take(np.array([0.6]), [_hulls(built, [(0, u, 3, 0.001)])], [_contacts([])])
    (found,) = g.found()
    assert found.part == "u" and found.bounded


def test_many_states_raw_contacts_read_at_once_are_each_states_rows(gaps_built):
    from cablecheck.run.loop import Simulation
    sim = Simulation(gaps_built)
    sim.reset()
    sim.settle()
    raws, one = [], []
    for state in sim.steps(contacts=False):
        raws.append(state.hull)
        one.append(sim.hull.rows_many([state.hull])[1:])
    raws.insert(1, None)
    one.insert(1, tuple(np.zeros(0) for _ in range(4)))
    state, *rows = sim.hull.rows_many(raws)
    assert len(state) and np.array_equal(state, np.repeat(np.arange(len(raws)), [len(r[0]) for r in one]))
    for got, parts in zip(rows, zip(*one)):
        assert np.array_equal(got, np.concatenate(parts))
