"""Drooping clear of the parts (cablecheck.build.obstacles): a cable along a floor, box or
plane, starts and stays on it."""

from __future__ import annotations

from buildscenes import floor_scene, run_steps, slider_scene

from cablecheck.build.stages import build
from cablecheck.scene.load import parse_scene


def test_cable_along_a_floor_starts_and_stays_on_it(tmp_path):
    for shape in ("box", "plane"):
        sim, states = run_steps(floor_scene(shape), tmp_path)
        r = sim.built.cables[0].radius
        routed = sim.built.cables[0].routed
        assert routed[:, 2].min() > r - 1e-9                          # droops sideways on the floor
        for state in (states[0], states[-1]):                          # settled, and at the end
            assert state.cables[0][:, 2].min() > 0.9 * r, shape
        assert not sim.warnings()


def test_two_planes_of_different_size_lengths_build(tmp_path):
    data = slider_scene(tmp_path)
    data["parts"] += [{"name": "floor", "shape": "plane", "pos": [0, 0, -0.1]},
                      {"name": "mat", "shape": "plane", "size": [0.4, 0.2], "pos": [0, 0, -0.05]}]
    built = build(parse_scene(data, tmp_path / "s.toml"))
    assert [p.name for p in built.parts][-2:] == ["floor", "mat"]
