"""Model building and the step loop end to end: holds, contacts by name, units,
far from the origin, dynamics off, a cable pressed into a plane. The stages
are tested with their modules (test_startframes, test_cableplan,
test_obstacles, test_mjspec, test_contactbits, test_cablephysics,
test_modelread, test_substeps)."""

from __future__ import annotations

import copy

import numpy as np
from buildscenes import floor_scene, run_steps, slider_scene

from cablecheck.scene.load import parse_scene


def test_cable_is_held_at_start_end_and_clip(tmp_path):
    data = slider_scene(tmp_path)
    data["cables"][0]["clips"] = [{"pos": [0.2, 0, 0.45]}]
    sim, states = run_steps(data, tmp_path)
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
    data = slider_scene(tmp_path)
    # a post the cable crosses: the straight route passes through it
    data["parts"][0] = {"name": "frame/post", "shape": "box", "size": [0.02, 0.02, 0.2], "pos": [0.3, 0, 0.45]}
    data["cables"][0]["length"] = 0.6
    data["effects"] = {"contact": []}  # detected, never resolved
    data["scene"]["settle"] = 0.0
    sim, states = run_steps(data, tmp_path)
    found = states[0].contacts
    post = found.b == "frame/post"
    assert post.any()
    assert set(found.kind[post]) == {"cable-structure"} and set(found.a[post]) == {"c"}
    # the cable's centreline runs through the box: surface distance about -(0.02 + r) or less
    assert found.dist[post].min() < -0.02
    assert (found.elem_a[post] >= 0).all() and (found.elem_b[post] == -1).all()


def test_dynamics_off_keeps_cable_as_routed_and_moves_parts(tmp_path):
    data = slider_scene(tmp_path)
    data["effects"] = {"dynamics": False}
    data["parts"].append({"name": "slider/block", "body": "slider", "shape": "sphere", "size": [0.01],
                          "pos": [0.7, 0, 0.5]})
    sim, states = run_steps(data, tmp_path)
    routed = sim.built.cables[0].routed
    assert sim.settle_steps == 0 and sim.data.time == 0.0  # nothing was stepped
    for s in states:
        assert np.allclose(s.cables[0], routed)
    block = [p.name for p in sim.built.parts].index("slider/block")
    assert np.allclose(states[-1].part_poses[block][:3, 3], [0.72, 0, 0.5])


def test_mm_scene_gives_the_same_physics_scaled(tmp_path):
    m = slider_scene(tmp_path)
    mm = copy.deepcopy(m)
    mm["scene"]["units"] = "mm"
    scale = lambda v: [x * 1000 for x in v]  # noqa: E731
    mm["parts"][0]["size"] = scale(m["parts"][0]["size"])
    mm["parts"][0]["pos"] = scale(m["parts"][0]["pos"])
    c = mm["cables"][0]
    c["radius"], c["length"] = 4.0, 700.0
    c["start"]["pos"], c["end"]["pos"] = scale(c["start"]["pos"]), scale(c["end"]["pos"])
    mm["motion"][0]["keys"][1]["pos"] = [20.0, 0, 0]
    _, sm = run_steps(m, tmp_path, contacts=False)
    _, smm = run_steps(mm, tmp_path, contacts=False)
    for a, b in zip(sm, smm):
        assert np.allclose(a.cables[0], b.cables[0], atol=1e-9)


def test_scene_far_from_origin_gives_the_same_physics(tmp_path):
    near = slider_scene(tmp_path)
    far = copy.deepcopy(near)
    off = np.array([1.0e4, -2.0e4, 500.0])
    shift = lambda v: list(np.asarray(v, float) + off)  # noqa: E731
    far["parts"][0]["pos"] = shift(near["parts"][0]["pos"])
    far["cables"][0]["start"]["pos"] = shift(near["cables"][0]["start"]["pos"])
    far["bodies"][0]["pos"] = list(off)
    far["motion"][0]["keys"] = [{"t": 0, "pos": list(off)}, {"t": 0.2, "pos": shift([0.02, 0, 0])}]
    _, s_near = run_steps(near, tmp_path, contacts=True)
    _, s_far = run_steps(far, tmp_path, contacts=True)
    for a, b in zip(s_near, s_far):
        assert np.allclose(a.cables[0], b.cables[0] - off, atol=1e-7)
        assert np.allclose(np.sort(a.contacts.dist), np.sort(b.contacts.dist), atol=1e-7)



def test_cable_pressed_into_a_plane_is_measured_exactly_by_both_sides(tmp_path):
    from cablecheck.run.runner import RunOptions, run_scene
    data = floor_scene("plane", pressed=2.0)
    data["effects"]["dynamics"] = False
    report = run_scene(parse_scene(data, tmp_path / "s.toml"), RunOptions(report=tmp_path / "r.json", record=tmp_path / "r.rrd"))
    # the floor's; the cable's own V at the pressed via (its clamped ends leave
    # along the route, so its runs snake more steeply into the via) is not this test's
    (event,) = [e for e in report["events"] if e["b"] == "floor"]
    assert (event["a"], event["b"], event["severity"]) == ("c", "floor", "hard")
    assert np.isclose(event["min_distance"], -2.0, atol=1e-9)
    v = report["validation"]   # both sides agree on the floor; MuJoCo sees no self pair within the clearance
    assert v["agree"] == v["compared_steps"] and v["mujoco_only"] == 0 and v["unexplained"] == 0
    assert set(v["reasons"]) <= {"self, no margin"} and v["max_distance_error"] < 1e-9
    assert (tmp_path / "r.rrd").stat().st_size > 0





def test_a_detection_model_added_later_is_the_one_build_makes(tmp_path):
    """A run builds the simulation first and adds the detection model while
    the simulation settles: the same models as `build`, the first record
    left without one."""
    from cablecheck.build.stages import build, build_simulation, plan_cables, with_detection
    scene = parse_scene(slider_scene(tmp_path), tmp_path / "s.toml")
    planned = plan_cables(scene)
    first = build_simulation(scene, planned)
    later, whole = with_detection(first, planned), build(scene)
    assert first.detect is None and later.detect is not None
    for a, b in ((later.model, whole.model), (later.detect, whole.detect)):
        assert (a.nq, a.nv, a.ngeom, a.nflex, a.nflexvert) == (b.nq, b.nv, b.ngeom, b.nflex, b.nflexvert)
        assert np.array_equal(a.geom_size, b.geom_size) and np.array_equal(a.geom_margin, b.geom_margin)
        assert np.array_equal(a.flex_margin, b.flex_margin) and np.array_equal(a.qpos0, b.qpos0)
    assert later.substeps == whole.substeps and later.warnings == whole.warnings
    assert later.model is first.model


def test_a_held_end_starting_inside_a_part_of_another_body_is_warned_of(tmp_path, capsys):
    """The build, and so `cablecheck check`, warns of a held point MuJoCo finds pressed into a part of
    another body at t = 0 (a dress-pack end clamped inside the link before it: the zoo's Panda diverged
    there with no word before the run); a part riding the holding body is no such warning."""
    from cablecheck.build.stages import build
    from cablecheck.cli.main import main

    block = {"name": "frame/block", "shape": "box", "size": [0.03, 0.03, 0.03], "pos": [0.6, 0.0, 0.5]}
    data = slider_scene(tmp_path)
    data["parts"] = [block]
    warnings = build(parse_scene(data, tmp_path / "s.toml"), detect=False).warnings
    assert [w for w in warnings if w.startswith("at t = 0, as routed, cable 'c' is held at vertex")
            and "(its end on 'slider')" in w and "'frame/block'" in w]
    data["parts"] = [{**block, "body": "slider", "pos": [0.6, 0.0, 0.5]}]
    assert not [w for w in build(parse_scene(data, tmp_path / "s.toml"), detect=False).warnings
                if "as routed" in w]
    scene = tmp_path / "block.toml"
    scene.write_text('[scene]\nname = "b"\nunits = "m"\nduration = 0.2\nsettle = 0.3\n\n'
                     '[effects]\ncontact = ["cable-structure"]\n\n[[bodies]]\nname = "slider"\n\n'
                     '[[parts]]\nname = "frame/block"\nshape = "box"\nsize = [0.03, 0.03, 0.03]\npos = [0.6, 0.0, 0.5]\n\n'
                     '[[cables]]\nname = "c"\nradius = 0.004\nstart = { pos = [0, 0, 0.5] }\n'
                     'end = { body = "slider", pos = [0.6, 0, 0.5] }\nlength = 0.7\nsegments = 20\n')
    assert main(["check", str(scene)]) == 0
    assert "at t = 0, as routed, cable 'c' is held" in capsys.readouterr().err
