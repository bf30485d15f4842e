"""Model building and the step loop: parts, cables, holds, contacts, units, dynamics off."""

from __future__ import annotations

import copy
from pathlib import Path

import numpy as np
import trimesh

from sim.build import build
from sim.loop import Simulation
from sim.scene import parse_scene


def _scene(tmp_path: Path, **over) -> dict:
    data = {
        "scene": {"name": "t", "units": "m", "duration": 0.2, "settle": 0.3},
        "effects": {"contact": ["cable-structure"]},
        "bodies": [{"name": "slider"}],
        # off the cable's midpoint: a droop centred on a box edge-on is a tie between faces
        "parts": [{"name": "frame/post", "shape": "box", "size": [0.02, 0.02, 0.2], "pos": [0.36, 0.0, 0.2]}],
        "cables": [{"name": "c", "radius": 0.004, "start": {"pos": [0, 0, 0.5]},
                    "end": {"body": "slider", "pos": [0.6, 0, 0.5]}, "length": 0.7, "segments": 20}],
        "motion": [{"body": "slider", "keys": [{"t": 0, "pos": [0, 0, 0]}, {"t": 0.2, "pos": [0.02, 0, 0]}]}],
    }
    data.update(over)
    return data


def _run(data: dict, tmp_path: Path, contacts=True):
    sim = Simulation(build(parse_scene(data, tmp_path / "s.toml")))
    sim.reset()
    sim.settle()
    return sim, list(sim.steps(contacts=contacts))


def test_cable_is_held_at_start_end_and_clip(tmp_path):
    data = _scene(tmp_path)
    data["cables"][0]["clips"] = [{"pos": [0.2, 0, 0.45]}]
    sim, states = _run(data, tmp_path)
    cable = sim.built.cables[0]
    clip = [a for a in cable.attachments if a.kind == "clip"][0]
    for state in states:
        pts = state.cables[0]
        assert np.allclose(pts[0], [0, 0, 0.5], atol=1e-9)
        assert np.linalg.norm(pts[clip.vertex] - [0.2, 0, 0.45]) < 5e-4
    end_target = np.array([0.62, 0, 0.5])
    assert np.linalg.norm(states[-1].cables[0][-1] - end_target) < 5e-4
    assert not sim.warnings()


def test_contacts_are_mapped_to_names_with_signed_distance(tmp_path):
    data = _scene(tmp_path)
    # a post the cable crosses: the straight route passes through it
    data["parts"][0] = {"name": "frame/post", "shape": "box", "size": [0.02, 0.02, 0.2], "pos": [0.3, 0, 0.45]}
    data["cables"][0]["length"] = 0.6
    data["effects"] = {"contact": []}  # detected, never resolved
    data["scene"]["settle"] = 0.0
    sim, states = _run(data, tmp_path)
    found = states[0].contacts
    post = found.b == "frame/post"
    assert post.any()
    assert set(found.kind[post]) == {"cable-structure"} and set(found.a[post]) == {"c"}
    # the cable's centreline runs through the box: surface distance about -(0.02 + r) or less
    assert found.dist[post].min() < -0.02
    assert (found.elem_a[post] >= 0).all() and (found.elem_b[post] == -1).all()


def test_mesh_part_matches_box_part(tmp_path):
    box = trimesh.creation.box(extents=[0.04, 0.04, 0.4])
    box.export(tmp_path / "post.stl")
    a = _scene(tmp_path)
    b = copy.deepcopy(a)
    b["parts"][0] = {"name": "frame/post", "shape": "mesh", "file": "post.stl", "pos": [0.36, 0.0, 0.2]}
    built_a = build(parse_scene(a, tmp_path / "s.toml"))
    built_b = build(parse_scene(b, tmp_path / "s.toml"))
    pa, pb = built_a.parts[0], built_b.parts[0]
    assert pb.shape == "mesh" and pb.vertices.shape == (8, 3)
    sa, sb = Simulation(built_a), Simulation(built_b)
    sa.reset(), sb.reset()
    ta, tb = sa.state(0, False).part_poses[0], sb.state(0, False).part_poses[0]
    world_b = pb.vertices @ tb[:3, :3].T + tb[:3, 3]
    assert np.allclose(np.sort(world_b, axis=0),
                       np.sort(np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)])
                               * pa.size + ta[:3, 3], axis=0), atol=1e-6)  # MuJoCo stores mesh vertices as float32


def test_points_cable_starts_exactly_on_its_points(tmp_path):
    pts = [[0, 0, 0.5], [0.2, 0, 0.45], [0.4, 0, 0.45], [0.6, 0, 0.5]]
    data = _scene(tmp_path)
    data["cables"][0] = {"name": "c", "radius": 0.004, "points": pts, "end": {"body": "slider"}, "segments": 30}
    built = build(parse_scene(data, tmp_path / "s.toml"))
    routed = built.cables[0].routed
    assert np.allclose(routed[[0, -1]], [pts[0], pts[-1]])
    seg_len = np.linalg.norm(np.diff(routed, axis=0), axis=1).sum()
    p = np.asarray(pts, float)
    assert np.isclose(seg_len, np.linalg.norm(np.diff(p, axis=0), axis=1).sum(), rtol=1e-3)


def test_dynamics_off_keeps_cable_as_routed_and_moves_parts(tmp_path):
    data = _scene(tmp_path)
    data["effects"] = {"dynamics": False}
    data["parts"].append({"name": "slider/block", "body": "slider", "shape": "sphere", "size": [0.01],
                          "pos": [0.7, 0, 0.5]})
    sim, states = _run(data, tmp_path)
    routed = sim.built.cables[0].routed
    assert sim.settle_steps == 0 and sim.data.time == 0.0  # nothing was stepped
    for s in states:
        assert np.allclose(s.cables[0], routed)
    block = [p.name for p in sim.built.parts].index("slider/block")
    assert np.allclose(states[-1].part_poses[block][:3, 3], [0.72, 0, 0.5])


def test_mm_scene_gives_the_same_physics_scaled(tmp_path):
    m = _scene(tmp_path)
    mm = copy.deepcopy(m)
    mm["scene"]["units"] = "mm"
    scale = lambda v: [x * 1000 for x in v]  # noqa: E731
    mm["parts"][0]["size"] = scale(m["parts"][0]["size"])
    mm["parts"][0]["pos"] = scale(m["parts"][0]["pos"])
    c = mm["cables"][0]
    c["radius"], c["length"] = 4.0, 700.0
    c["start"]["pos"], c["end"]["pos"] = scale(c["start"]["pos"]), scale(c["end"]["pos"])
    mm["motion"][0]["keys"][1]["pos"] = [20.0, 0, 0]
    _, sm = _run(m, tmp_path, contacts=False)
    _, smm = _run(mm, tmp_path, contacts=False)
    for a, b in zip(sm, smm):
        assert np.allclose(a.cables[0], b.cables[0], atol=1e-9)


def test_only_listed_interactions_push_back(tmp_path):
    data = _scene(tmp_path)
    # a shelf below the sagging cable rises through it during the motion
    data["bodies"].append({"name": "lift"})
    data["parts"][0] = {"name": "lift/shelf", "body": "lift", "shape": "box",
                        "size": [0.1, 0.2, 0.01], "pos": [0.3, 0, 0.2]}
    data["motion"].append({"body": "lift", "keys": [{"t": 0, "pos": [0, 0, 0]}, {"t": 0.2, "pos": [0, 0, 0.2]}]})
    _, resolved = _run(data, tmp_path, contacts=False)
    data["effects"] = {"contact": []}
    _, ghost = _run(data, tmp_path, contacts=False)
    top = 0.4 + 0.01  # the shelf's top face at the end
    over = lambda states: states[-1].cables[0][np.abs(states[-1].cables[0][:, 0] - 0.3) < 0.05, 2]  # noqa: E731
    assert over(resolved).min() > top + 0.004 - 2e-3  # lifted: lies on the shelf
    assert over(ghost).min() < top - 0.05  # passed through: never pushed


def test_scene_far_from_origin_gives_the_same_physics(tmp_path):
    near = _scene(tmp_path)
    far = copy.deepcopy(near)
    off = np.array([1.0e4, -2.0e4, 500.0])
    shift = lambda v: list(np.asarray(v, float) + off)  # noqa: E731
    far["parts"][0]["pos"] = shift(near["parts"][0]["pos"])
    far["cables"][0]["start"]["pos"] = shift(near["cables"][0]["start"]["pos"])
    far["bodies"][0]["pos"] = list(off)
    far["motion"][0]["keys"] = [{"t": 0, "pos": list(off)}, {"t": 0.2, "pos": shift([0.02, 0, 0])}]
    _, s_near = _run(near, tmp_path, contacts=True)
    _, s_far = _run(far, tmp_path, contacts=True)
    for a, b in zip(s_near, s_far):
        assert np.allclose(a.cables[0], b.cables[0] - off, atol=1e-7)
        assert np.allclose(np.sort(a.contacts.dist), np.sort(b.contacts.dist), atol=1e-7)


# -- initial shapes: points routes as given, droop clear of parts, planes ------------------

def _points_scene(dynamics: bool, length=None, segments=None) -> dict:
    a = np.linspace(0.0, np.pi, 9)
    points = np.stack([0.2 * np.cos(a), 0.05 * np.sin(2 * a), 0.3 + 0.1 * np.sin(a)], axis=1)
    cable = {"name": "c", "radius": 0.004, "points": points.tolist()}
    if length is not None:
        cable["length"] = length
    if segments is not None:
        cable["segments"] = segments
    return {"scene": {"name": "p", "units": "m", "duration": 0.0, "settle": 0.2},
            "effects": {"dynamics": dynamics}, "cables": [cable]}, points


def _distance_to_polyline(points: np.ndarray, route: np.ndarray) -> np.ndarray:
    a, b = route[:-1], route[1:]
    ab = b - a
    t = np.clip(np.einsum("pij,ij->pi", points[:, None, :] - a[None], ab) / np.einsum("ij,ij->i", ab, ab), 0, 1)
    return np.linalg.norm(points[:, None, :] - (a[None] + t[:, :, None] * ab[None]), axis=2).min(axis=1)


def test_points_route_with_dynamics_off_is_checked_as_given(tmp_path):
    data, points = _points_scene(dynamics=False, segments=20)
    sim, states = _run(data, tmp_path)
    checked = states[0].cables[0]
    assert len(checked) == 23   # 20 elements and the short held edge of each clamped end
    assert _distance_to_polyline(checked, points).max() < 1e-12      # on the given centreline
    assert all(np.abs(checked - p).sum(axis=1).min() < 1e-12 for p in points)   # every point a vertex
    route = float(np.linalg.norm(np.diff(points, axis=0), axis=1).sum())
    assert np.isclose(sim.built.cables[0].length, route, rtol=1e-12)


def test_points_route_longer_than_given_with_dynamics_off_is_refused(tmp_path):
    import pytest
    from sim.scene import SceneError
    data, points = _points_scene(dynamics=False, length=0.8)
    with pytest.raises(SceneError, match="checked as given") as e:
        parse_scene(data, tmp_path / "s.toml")
    assert e.value.key == "cables[0].length"


def test_points_route_with_slack_starts_through_every_point(tmp_path):
    data, points = _points_scene(dynamics=True, length=0.8)
    built = build(parse_scene(data, tmp_path / "s.toml"))
    routed = built.cables[0].routed
    assert all(np.abs(routed - p).sum(axis=1).min() < 1e-12 for p in points)
    assert np.isclose(np.linalg.norm(np.diff(routed, axis=0), axis=1).sum(), 0.8, rtol=1e-9)


def test_too_few_segments_for_the_points_is_refused(tmp_path):
    import pytest
    from sim.scene import SceneError
    data, _ = _points_scene(dynamics=True, segments=6)
    with pytest.raises(SceneError, match="at least 8") as e:
        parse_scene(data, tmp_path / "s.toml")
    assert e.value.key == "cables[0].segments"


def _floor_scene(shape: str, pressed: float = 0.0) -> dict:
    """A cable of radius 5 mm laid along a floor (top at z = 0): ends and via
    on it, 20 % longer than its route; the via `pressed` into it."""
    r = 5.0
    floor = ({"name": "floor", "shape": "box", "size": [400, 300, 10], "pos": [0, 0, -10]} if shape == "box"
             else {"name": "floor", "shape": "plane", "pos": [0, 0, 0]})
    return {"scene": {"name": "f", "units": "mm", "duration": 0.3, "settle": 1.0},
            "effects": {"contact": ["cable-structure"]}, "parts": [floor],
            "cables": [{"name": "c", "radius": r, "start": {"pos": [-300, 0, r]}, "end": {"pos": [300, 0, r]},
                        "via": [[0, 0, r - pressed]], "length": 720.0}]}


def test_cable_along_a_floor_starts_and_stays_on_it(tmp_path):
    for shape in ("box", "plane"):
        sim, states = _run(_floor_scene(shape), tmp_path)
        r = sim.built.cables[0].radius
        routed = sim.built.cables[0].routed
        assert routed[:, 2].min() > r - 1e-9                          # droops sideways on the floor
        for state in (states[0], states[-1]):                          # settled, and at the end
            assert state.cables[0][:, 2].min() > 0.9 * r, shape
        assert not sim.warnings()


def test_cable_pressed_into_a_plane_is_measured_exactly_by_both_sides(tmp_path):
    from sim.run import RunOptions, run_scene
    data = _floor_scene("plane", pressed=2.0)
    data["effects"]["dynamics"] = False
    report = run_scene(parse_scene(data, tmp_path / "s.toml"), RunOptions(report=tmp_path / "r.json", record=tmp_path / "r.rrd"))
    (event,) = report["events"]
    assert (event["a"], event["b"], event["severity"]) == ("c", "floor", "hard")
    assert np.isclose(event["min_distance"], -2.0, atol=1e-9)
    assert report["validation"]["agreement"] == 1.0 and report["validation"]["max_distance_error"] < 1e-9
    assert (tmp_path / "r.rrd").stat().st_size > 0


def test_plane_is_drawn_sized_to_the_scene_or_as_given():
    from sim.record import plane_half_sizes
    pose = np.eye(4)
    pose[:3, 3] = [1.0, 0.0, 0.0]
    pts = np.array([[0.0, -0.5, 0.3], [3.0, 0.2, 0.1]])
    assert np.allclose(plane_half_sizes(np.zeros(3), pose, pts), [2.4, 0.6])
    tilted = np.eye(4)
    tilted[:3, :3] = [[0, 0, 1], [0, 1, 0], [-1, 0, 0]]     # normal along +x: local x is world -z
    assert np.allclose(plane_half_sizes(np.zeros(3), tilted, pts), [0.36, 0.6])
    assert np.allclose(plane_half_sizes(np.array([0.5, 0.25, 0.1]), pose, pts), [0.5, 0.25])


# -- an mjcf model as it comes ------------------------------------------------

_ARM = """<mujoco>
  <asset><mesh name="lug" vertex="0 0 0  0.02 0 0  0 0.02 0  0 0 0.02"/></asset>
  <worldbody>
    <body name="stand" pos="0 0 0.2">
      {visual_stand}
      <geom name="column" type="box" size="0.03 0.03 0.1" contype="1" conaffinity="1"/>
      <body name="link" pos="0 0 0.15">
        <joint name="j" type="hinge" axis="0 0 1"/>
        {visual_link}
        <geom type="capsule" fromto="0 0 0 0.25 0 0" size="0.02" contype="2" conaffinity="0"/>
        <geom type="mesh" mesh="lug" pos="0.25 0 0" contype="2" conaffinity="0"/>
        <geom type="sphere" size="0.015" pos="0.1 0 0.05" contype="0" conaffinity="2"/>
      </body>
    </body>
    <body name="post" pos="0.45 0 0.2">
      <joint name="lift" type="slide" axis="0 0 1"/>
      <geom name="rod" type="cylinder" size="0.02 0.15" contype="2" conaffinity="1"/>
    </body>
  </worldbody>
  {contact}
</mujoco>"""

_VISUALS = dict(
    visual_stand='<geom type="box" size="0.05 0.05 0.12" contype="0" conaffinity="0" group="2"/>',
    visual_link='<geom type="mesh" mesh="lug" contype="0" conaffinity="0" group="2"/>'
                '<geom name="shell" type="capsule" fromto="0 0 0 0.25 0 0" size="0.03" '
                'contype="0" conaffinity="0" group="2"/>')


def _arm_scene(tmp_path: Path, visuals: bool, contact: str = "", effects=("cable-structure",)) -> dict:
    fill = _VISUALS if visuals else dict.fromkeys(_VISUALS, "")
    (tmp_path / "arm.xml").write_text(_ARM.format(contact=contact, **fill))
    return {
        "scene": {"name": "t", "units": "m", "duration": 0.05, "settle": 0.05, "mjcf": "arm.xml"},
        "effects": {"contact": list(effects)},
        "parts": [{"name": "cell/table", "shape": "box", "size": [0.5, 0.5, 0.01], "pos": [0.2, 0, 0.09]}],
        "cables": [{"name": "hose", "radius": 0.005, "start": {"body": "stand", "pos": [-0.05, 0, 0.0]},
                    "end": {"body": "link", "pos": [0.2, 0, 0.03]}, "length": 0.5, "segments": 16}],
    }


def _built(tmp_path: Path, **kw):
    return build(parse_scene(_arm_scene(tmp_path, **kw), tmp_path / "s.toml"))


def test_visual_geoms_are_drawn_never_parts_and_names_do_not_move(tmp_path):
    """A model with and without its visual geoms gives the same parts, names
    and skipped pairs; the visual geoms are listed to be drawn."""
    from sim.stepcheck import part_pairs_skipped
    bare, dressed = _built(tmp_path, visuals=False), _built(tmp_path, visuals=True)
    names = [p.name for p in bare.parts]
    assert names == [p.name for p in dressed.parts]
    assert set(names) == {"cell/table", "stand/column", "link/capsule0", "link/lug", "link/sphere2", "post/rod"}
    assert [v.name for v in dressed.visuals] == ["stand/box0", "link/lug", "link/shell"] and not bare.visuals
    assert np.array_equal(part_pairs_skipped(bare), part_pairs_skipped(dressed))
    for built in (bare, dressed):
        for m in (built.model, built.detect):
            for v in built.visuals:
                assert m.geom_contype[v.geom_id] == 0 and m.geom_conaffinity[v.geom_id] == 0


def test_the_models_own_bits_are_kept_and_filter_part_pairs(tmp_path):
    from sim.stepcheck import part_pairs_skipped
    built = _built(tmp_path, visuals=True, effects=("cable-structure", "part-part"))
    by = {p.name: p.geom_id for p in built.parts}
    m, det = built.model, built.detect
    # the scene's bits are the three lowest the model leaves free (it uses 1 and 2): 4, 8, 16
    cable, part = 4, 16
    assert m.flex_contype[0] == cable
    for name, own in {"stand/column": (1, 1), "link/capsule0": (2, 0), "link/sphere2": (0, 2)}.items():
        g = by[name]
        assert (m.geom_contype[g], m.geom_conaffinity[g]) == (own[0], own[1] | cable | part)
        assert (det.geom_contype[g], det.geom_conaffinity[g]) == (own[0], own[1] | cable | part)
    assert (m.geom_contype[by["cell/table"]], m.geom_conaffinity[by["cell/table"]]) == (part, part | cable)
    # without part-part the model's geoms take no part in collisions but the cable's
    only_cable = _built(tmp_path, visuals=True)
    g = [p.geom_id for p in only_cable.parts if p.name == "stand/column"][0]
    assert (only_cable.model.geom_contype[g], only_cable.model.geom_conaffinity[g]) == (0, cable)
    skip = part_pairs_skipped(built)
    idx = {p.name: k for k, p in enumerate(built.parts)}
    # the rod (2/1) meets the column (1/1) and the sphere (0/2), never the capsule or lug (2/0)
    assert not skip[idx["stand/column"], idx["post/rod"]] and not skip[idx["link/sphere2"], idx["post/rod"]]
    assert skip[idx["link/capsule0"], idx["post/rod"]] and skip[idx["post/rod"], idx["link/lug"]]
    # scene parts meet every model geom
    assert not skip[idx["cell/table"], idx["link/capsule0"]] and not skip[idx["cell/table"], idx["stand/column"]]


def test_model_exclude_pairs_are_honoured(tmp_path):
    from sim.stepcheck import part_pairs_skipped
    plain = _built(tmp_path, visuals=False)
    excluded = _built(tmp_path, visuals=False, contact='<contact><exclude body1="link" body2="post"/></contact>')
    for built, expect in ((plain, False), (excluded, True)):
        idx = {p.name: k for k, p in enumerate(built.parts)}
        skip = part_pairs_skipped(built)
        assert skip[idx["link/sphere2"], idx["post/rod"]] == expect
        assert skip[idx["post/rod"], idx["link/sphere2"]] == expect
        assert not skip[idx["cell/table"], idx["post/rod"]]


def test_visual_geoms_make_no_contacts_nor_events(tmp_path):
    """A visual shell the cable runs through is never a contact, part or event."""
    data = _arm_scene(tmp_path, visuals=True)
    sim, states = _run(data, tmp_path)
    visual_ids = {v.geom_id for v in sim.built.visuals}
    raw = sim.collide(states[-1].qpos)
    assert not (set(raw.geom.ravel()) & visual_ids)
    assert all(not str(n).startswith(("link/shell", "stand/box0")) for s in states for n in s.contacts.b)
