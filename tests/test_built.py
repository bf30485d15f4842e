"""The built scene's records (cablecheck.build.built): a cable's record agrees with itself
(rest coordinates, held vertices, elements), and the MuJoCo-free body tree
answers the names and counts an MjModel would."""

from __future__ import annotations

import numpy as np
from buildscenes import slider_scene

from cablecheck.build.built import BodyTree
from cablecheck.build.stages import build
from cablecheck.build.static import build_static
from cablecheck.scene.load import parse_scene


def test_a_cables_record_agrees_with_itself(tmp_path):
    data = slider_scene(tmp_path)
    data["cables"][0]["clips"] = [{"pos": [0.2, 0, 0.45]}]
    cable = build(parse_scene(data, tmp_path / "s.toml")).cables[0]
    assert cable.routed.shape == (cable.count, 3) and cable.rest_s.shape == (cable.count,)
    assert cable.rest_s[0] == 0.0 and np.isclose(cable.rest_s[-1], cable.length, rtol=1e-5)
    assert np.all(np.diff(cable.rest_s) > 0)
    # each clamp holds the two vertices of one short edge
    held = cable.attachments
    assert [a.kind for a in held] == ["start", "start", "clip", "clip", "end", "end"]
    assert [a.body for a in held] == ["world"] * 4 + ["slider"] * 2
    for first, second in zip(held[::2], held[1::2]):
        assert second.vertex == first.vertex + 1
        assert cable.rest_s[second.vertex] - cable.rest_s[first.vertex] < 0.1 * cable.element_length
    for a in held:
        assert a.s == cable.rest_s[a.vertex]
    assert held[0].vertex == 0 and held[-1].vertex == cable.count - 1
    assert cable.elements == 20 and cable.count == cable.elements + 3 + 1


def test_the_body_tree_answers_as_the_model_does(tmp_path):
    data = slider_scene(tmp_path)
    data["effects"] = {"dynamics": False}
    data["check"] = {"validate": False}
    data["parts"].append({"name": "slider/block", "body": "slider", "shape": "sphere", "size": [0.01],
                          "pos": [0.7, 0, 0.5]})
    scene = parse_scene(data, tmp_path / "s.toml")
    tree, model = build_static(scene).model, build(scene).model
    assert isinstance(tree, BodyTree)
    assert tree.nbody == len(tree.body_names) and tree.ngeom == len(tree.geom_bodyid)
    for i in range(tree.nbody):
        assert tree.body(i) == (i, tree.body_names[i])
        assert tree.body(i).name == model.body(tree.body_names[i]).name
    assert tree.body(0).name == "world" and "slider" in tree.body_names
    assert [tree.joint(j).name for j in range(tree.njnt)] == list(tree.joint_names)
