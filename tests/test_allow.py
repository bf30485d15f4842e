"""`[[allow]]` names checked at load against the mjcf model's colliding geoms, named as the builder names them."""

from __future__ import annotations

import pytest
from buildscenes import arm_scene

from cablecheck.build.stages import build
from cablecheck.scene.errors import SceneError
from cablecheck.scene.load import parse_scene
from cablecheck.scene.mjcf import base_model, colliding_parts

_LAMP = """<mujoco><worldbody>
  <body name="base"><geom type="box" size="0.1 0.1 0.02"/></body>
  <body name="lamp" pos="0 0 0.4"><geom type="sphere" size="0.05" contype="0" conaffinity="0"/></body>
</worldbody></mujoco>"""


def _with_allow(data: dict, a: str, b: str = "hose") -> dict:
    return {**data, "allow": [{"a": a, "b": b, "reason": "by design"}]}


@pytest.mark.parametrize("visuals", [False, True])
def test_the_loaders_part_names_are_the_builders(tmp_path, visuals):
    data = arm_scene(tmp_path, visuals=visuals)
    built = build(parse_scene(data, tmp_path / "s.toml"), detect=False)
    from_model = [p.name for p in built.parts if p.name not in {q["name"] for q in data["parts"]}]
    assert list(colliding_parts(base_model(tmp_path / "arm.xml")).values()) == from_model
    assert len(from_model) == 5


@pytest.mark.parametrize("name", ["link", "link/capsule0", "stand/column", "post"])
def test_a_body_or_geom_with_colliding_geoms_may_be_allowed(tmp_path, name):
    scene = parse_scene(_with_allow(arm_scene(tmp_path, visuals=True), name), tmp_path / "s.toml")
    assert scene.allow[0].a == name


def test_a_body_with_only_visual_geoms_is_refused_at_load_naming_the_key(tmp_path):
    (tmp_path / "lamp.xml").write_text(_LAMP)
    data = {"scene": {"name": "l", "units": "m", "duration": 0.1, "mjcf": "lamp.xml"},
            "cables": [{"name": "hose", "radius": 0.005, "start": {"pos": [0, 0, 0.1]},
                        "end": {"pos": [0.3, 0, 0.1]}, "length": 0.35}]}
    parse_scene(_with_allow(data, "base"), tmp_path / "s.toml")
    with pytest.raises(SceneError) as e:
        parse_scene(_with_allow(data, "lamp"), tmp_path / "s.toml")
    assert e.value.key == "allow[0].a" and "no colliding geom" in str(e.value)


def test_a_geom_name_the_builder_does_not_give_is_refused_with_a_hint(tmp_path):
    with pytest.raises(SceneError) as e:
        parse_scene(_with_allow(arm_scene(tmp_path, visuals=True), "link/capsule"), tmp_path / "s.toml")
    assert e.value.key == "allow[0].a" and "did you mean 'link/capsule0'" in str(e.value)
