"""cablecheck.build.routecheck: a cable routed through a part it collides with is named before any step.

A straight cable along x from x = 0 to x = 400 mm at height 0; a box
spanning x in [150, 250] and height [-20, 20] holds the centreline over
that stretch, so every routed vertex with 150 < x < 250 is inside it (the
vertices are where the route's elements end: every 20 mm here).
"""

from __future__ import annotations

from pathlib import Path

import pytest
from hypothesis import example, given, settings, strategies as st

from cablecheck.build.routecheck import route_warnings
from cablecheck.build.stages import plan_cables
from cablecheck.cli.main import main
from cablecheck.scene.load import load_scene
from tests.helpers import examples

SCENE = """
[scene]
name = "through"
units = "mm"
duration = 0.1

[effects]
contact = [{contact}]

[[parts]]
name = "frame/block"
shape = "box"
size = [50, 40, 20]
pos = [200, {block_y}, 0]

[[parts]]
name = "frame/socket"
shape = "box"
size = [10, 10, 10]
pos = [400, 0, 0]

[[cables]]
name = "hose"
radius = 4
start = {{ pos = [0, 0, 0] }}
end = {{ pos = [400, 0, 0] }}
segments = 20
"""


def _warnings(tmp_path: Path, contact: str = '"cable-structure"', block_y: float = 0.0) -> tuple[str, ...]:
    path = tmp_path / "through.toml"
    path.write_text(SCENE.format(contact=contact, block_y=block_y))
    scene = load_scene(path)
    return route_warnings(scene, *plan_cables(scene))


def test_a_route_through_a_part_is_named_with_where_along_the_cable(tmp_path):
    (w,) = _warnings(tmp_path)
    assert w.startswith("cables[0] 'hose': its initial shape runs through part 'frame/block'")
    # the vertices inside: x = 160 ... 240 (every 20 mm, strictly inside the box's 150-250)
    assert "from s = 160 to 240 mm" in w and "up to 20 mm inside" in w


def test_a_plate_between_two_vertices_is_found_too(tmp_path):
    """A plate 4 mm thick across the route at x = 210, between the vertices
    at 200 and 220: no vertex is inside it, the element between them passes
    through it (a ring, a thin bracket), and that is named as the vertices
    inside a part are."""
    path = tmp_path / "plate.toml"
    path.write_text(SCENE.format(contact='"cable-structure"', block_y=0.0).replace(
        "size = [50, 40, 20]\npos = [200,", "size = [2, 40, 20]\npos = [210,"))
    scene = load_scene(path)
    (w,) = route_warnings(scene, *plan_cables(scene))
    assert w.startswith("cables[0] 'hose': its initial shape runs through part 'frame/block'")
    assert "from s = 210 to 210 mm" in w and "up to 2 mm inside" in w     # its deepest place: the plate's middle


def test_without_dynamics_it_says_the_route_is_checked_where_it_lies(tmp_path):
    """A static check simulates nothing: the warning says so, not that the
    simulation will push the cable out."""
    (moving,) = _warnings(tmp_path)
    path = tmp_path / "static.toml"
    path.write_text(SCENE.format(contact='"cable-structure"', block_y=0.0).replace(
        "[effects]\n", "[effects]\ndynamics = false\n"))
    scene = load_scene(path)
    (static,) = route_warnings(scene, *plan_cables(scene))
    assert "contact pushes it out where it can" in moving and "simulat" in static
    assert "push it out" not in static and "nothing is simulated (dynamics = false)" in static
    assert static.split(";")[0] == moving.split(";")[0]        # the same place and depth


def test_beside_the_part_or_without_contact_nothing_is_said(tmp_path):
    # the end sits in its socket by design (its attachment window), and a block beside the route is no warning
    assert _warnings(tmp_path, block_y=45.0) == ()
    assert _warnings(tmp_path, contact="") == ()


def test_check_prints_it(tmp_path, capsys):
    path = tmp_path / "through.toml"
    path.write_text(SCENE.format(contact='"cable-structure"', block_y=0.0))
    assert main(["check", str(path)]) == 0
    err = capsys.readouterr().err
    assert "runs through part 'frame/block'" in err and str(path) in err


@pytest.mark.parametrize("block_y", [0.0, 45.0])
def test_a_run_lists_it_in_physics_warnings(tmp_path, block_y):
    from cablecheck.run.runner import RunOptions, run_scene

    path = tmp_path / "through.toml"
    path.write_text(SCENE.format(contact='"cable-structure"', block_y=block_y).replace("duration = 0.1",
                                                                                      "duration = 0.0"))
    report = run_scene(load_scene(path), RunOptions(report=tmp_path / "r.json", record=None))
    through = [w for w in report["physics_warnings"] if "runs through part" in w]
    assert len(through) == (1 if block_y == 0.0 else 0)


@settings(max_examples=examples(12), deadline=None)
@given(st.floats(-30.0, 30.0), st.floats(-30.0, 30.0), st.floats(-60.0, 60.0), st.sampled_from(["bar", "ring"]))
@example(0.0, 0.0, 0.0, "bar").via("the route through the bar's middle")
@example(0.0, 30.0, 0.0, "ring").via("the route through the ring's tube twice")
def test_meshes_warn_as_their_exact_distances_do(tmp_path_factory, y, z, turn, mesh):
    """Against mesh parts the vertices are measured exactly only where a lower
    bound cannot prove them outside (`signed_distance` with a limit of 0):
    the same warnings, places and depths as measuring every vertex exactly,
    for a bar and a torus (a ring an element may pass through) drawn across
    the route at random."""
    import trimesh

    import cablecheck.build.routecheck as routecheck

    folder = tmp_path_factory.mktemp("meshes")
    trimesh.creation.box([60, 16, 16]).export(folder / "bar.stl")
    trimesh.creation.torus(30, 8).export(folder / "ring.stl")
    path = folder / "scene.toml"
    path.write_text(SCENE.format(contact='"cable-structure"', block_y=300.0)
                    + f'\n[[parts]]\nname = "frame/{mesh}"\nshape = "mesh"\nfile = "{mesh}.stl"\n'
                      f'pos = [200, {y:.6g}, {z:.6g}]\neuler = [0, {turn:.6g}, {turn / 2:.6g}]\n')
    scene = load_scene(path)
    planned = plan_cables(scene)
    exact = routecheck.signed_distance

    bounded = route_warnings(scene, *planned)
    try:
        routecheck.signed_distance = lambda shape, points, limit=None: exact(shape, points)
        everywhere = route_warnings(scene, *planned)
    finally:
        routecheck.signed_distance = exact
    assert bounded == everywhere
    if mesh == "bar" and abs(y) < 5 and abs(z) < 5:     # the route through the bar's middle
        assert len(bounded) == 1 and "'frame/bar'" in bounded[0]
