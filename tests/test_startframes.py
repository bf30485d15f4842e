"""The scene at t = 0 in model coordinates (cablecheck.build.startframes): the model's
origin is the mean of the cables' routes (else of the parts and bodies),
and a body's frame carries points to the model's world and back."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from buildscenes import slider_scene
from hypothesis import given
from strategies import coords, rotations

from cablecheck.build.startframes import Frames, scene_origin
from cablecheck.scene.load import parse_scene

HERE = Path(__file__).resolve().parent
SCENE = parse_scene(slider_scene(None), HERE / "s.toml")


def test_origin_is_the_mean_of_the_routes_else_of_parts_and_bodies():
    route = np.asarray(SCENE.cables[0].route, float)
    assert np.allclose(scene_origin(SCENE), route.mean(axis=0), rtol=0, atol=1e-15)
    data = slider_scene(None)
    data.pop("cables")
    data["bodies"][0]["pos"] = [1.0, 2.0, 3.0]
    no_cables = parse_scene(data, HERE / "s.toml")
    assert np.allclose(scene_origin(no_cables), ([0.36, 0.0, 0.2] + np.array([1.0, 2.0, 3.0])) / 2)


@given(rotations(), coords(3, -1e4, 1e4), coords(3, -1e4, 1e4), coords(3, -1.0, 1.0))
def test_to_local_undoes_to_world(rot, pos, origin, local):
    frames = Frames(SCENE, origin, {"slider": (pos, rot), "world": (np.zeros(3), np.eye(3))})
    world = frames.to_world("slider", local)
    assert np.allclose(world, pos - origin + rot @ local, rtol=0, atol=1e-9)
    assert np.allclose(frames.to_local("slider", world), local, rtol=0, atol=1e-9)
    assert np.array_equal(frames.to_local("world", world), world)   # the model's world is the origin
