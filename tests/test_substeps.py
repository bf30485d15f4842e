"""How finely the simulation steps (cablecheck.build.substeps): held points' speeds
against the script's closed form, the step divided to meet the fastest
cable's need (a moving part's speed against its radius among them), and a
part too fast for any step named."""

from __future__ import annotations

import numpy as np
import pytest
from buildscenes import slider_scene

from cablecheck.build.cablephysics import (
    COMPRESSION_SHARE,
    COMPRESSION_TOLERANCE,
    buckling_load,
    compression_step,
    compression_strain,
    damping_step,
    first_mode,
    step_damping_ratio,
)
from cablecheck.build.stages import build
from cablecheck.build.substeps import (
    CONTACT_FRACTION,
    MAX_SUBSTEPS,
    SPEED_FRACTION,
    bending_step,
    choose_substeps,
    held_speeds,
    tunnel_warnings,
)
from cablecheck.scene.load import parse_scene


def _built(tmp_path, travel: float, interpolation: str = "cubic", **cable):
    data = slider_scene(tmp_path)
    data["motion"][0]["keys"][1]["pos"] = [travel, 0, 0]
    data["motion"][0]["interpolation"] = interpolation
    data["cables"][0].update(cable)
    return build(parse_scene(data, tmp_path / "s.toml"))


def test_held_speed_is_the_scripts_fastest(tmp_path):
    """The slider moves 0.02 m in 0.2 s: 0.1 m/s throughout when linear; a
    cubic from rest to rest peaks at 1.5 times the mean halfway."""
    assert held_speeds(_built(tmp_path, 0.02, "linear"))["c"] == pytest.approx(0.1, rel=1e-9)
    assert held_speeds(_built(tmp_path, 0.02))["c"] == pytest.approx(0.15, rel=1e-4)


@pytest.mark.parametrize("travel", [0.02, 0.6, 6.0])
def test_the_scene_step_is_divided_to_meet_the_fastest_cables_need(tmp_path, travel):
    built = _built(tmp_path, travel, "linear", damping=0.0)   # no damping need (below)
    cable, cable_def = built.cables[0], built.scene.cables[0]
    v = travel / 0.2
    speed = SPEED_FRACTION * cable.element_length / v
    squeeze = compression_step(buckling_load(cable.rest_s, [a.vertex for a in cable.attachments], cable_def),
                               cable.element_length, cable_def)
    need = min(bending_step(cable, cable_def), speed, squeeze)
    sub = choose_substeps(built)
    assert sub.needed["c"] == pytest.approx(need, rel=1e-9)
    assert sub.reasons["c"][0] == ("speed" if speed < squeeze else "compression")
    assert sub.reasons["c"][1] == pytest.approx(v, rel=1e-9)
    dt = built.scene.timestep
    assert sub.count == min(MAX_SUBSTEPS, int(np.ceil(dt / need)))
    assert sub.step * sub.count == pytest.approx(dt, rel=1e-12)
    assert sub.capped is (dt / need > MAX_SUBSTEPS)
    assert sub.capped or sub.step <= need * (1 + 1e-9)


def test_a_stiff_cable_is_stepped_for_its_compression(tmp_path):
    """Under its buckling load (clamped over its held run) the edges give at
    most half the 0.1 % tolerance; that need is stricter than the former
    bending rule (edges stiffer than the highest bending mode, which let
    them give about 5.6 / n^2 of strain under that load: 1.4 % at 20
    elements) wherever a held run has fewer than about 105 elements."""
    built = _built(tmp_path, 0.02, young=2.0e11, density=7800.0, damping=0.0)
    sub = choose_substeps(built)
    c, cd = built.cables[0], built.scene.cables[0]
    load = buckling_load(c.rest_s, [a.vertex for a in c.attachments], cd)
    assert sub.reasons["c"][0] == "compression"
    assert sub.needed["c"] == pytest.approx(compression_step(load, c.element_length, cd), rel=1e-12)
    assert sub.needed["c"] < bending_step(c, cd)
    assert compression_strain(load, c.element_length, cd, sub.needed["c"]) == pytest.approx(
        COMPRESSION_SHARE * COMPRESSION_TOLERANCE, rel=1e-9)
    # the compression step shrinks with the element (the span fixed): half for half the elements' length
    # (the held run is the length less the clamps' held edges, 5 % of an element each: within 1 %)
    finer = _built(tmp_path, 0.02, young=2.0e11, density=7800.0, segments=2 * c.elements, damping=0.0)
    ratio = finer.cables[0].element_length / c.element_length
    assert choose_substeps(finer).needed["c"] == pytest.approx(sub.needed["c"] * ratio, rel=0.01)


def test_a_stiff_cable_is_stepped_for_its_damping(tmp_path):
    """With damping the step also keeps the integrator's own damping of the
    cable's first bending mode (about omega h / 2) within the declared ratio."""
    built = _built(tmp_path, 0.02, young=2.0e11, density=7800.0, damping=0.05)
    sub = choose_substeps(built)
    c, cd = built.cables[0], built.scene.cables[0]
    omega = first_mode(c.rest_s, [a.vertex for a in c.attachments], cd)
    assert sub.reasons["c"][0] == "damping" and sub.reasons["c"][1] == pytest.approx(omega, rel=1e-12)
    assert sub.needed["c"] == pytest.approx(damping_step(0.05, omega), rel=1e-12)
    assert step_damping_ratio(omega, sub.step) <= 0.05
    beta = float(built.model.flex_damping[c.flex_id])
    assert step_damping_ratio(omega, sub.step, beta) == pytest.approx(0.05, rel=1e-9)


def test_a_thin_plate_fast_enough_to_pass_through_the_cable_is_stepped_for_or_named(tmp_path):
    """A plate on its own body (the cable's held points stay slow): at
    1.5 x 2 m / 0.2 s = 15 m/s it would move 30 mm in the scene's 2 ms step,
    more than the cable's radius (4 mm): the step is divided so that it
    moves at most the radius (`CONTACT_FRACTION`), 8 steps of 0.25 ms. At
    1.5 x 400 m / 0.2 s = 3000 m/s not even `MAX_SUBSTEPS` do: named, with
    the timestep that would do."""
    data = slider_scene(tmp_path)
    data["bodies"].append({"name": "shuttle"})
    data["parts"].append({"name": "shuttle/plate", "body": "shuttle", "shape": "box",
                          "size": [0.001, 0.05, 0.05], "pos": [0.5, 0.0, 0.3]})
    data["motion"].append({"body": "shuttle", "keys": [{"t": 0, "pos": [0, 0, 0]}, {"t": 0.2, "pos": [0.02, 0, 0]}]})
    slow = build(parse_scene(data, tmp_path / "s.toml"))
    assert tunnel_warnings(slow) == [] and slow.model.opt.timestep == slow.scene.timestep
    data["motion"][1]["keys"][1]["pos"] = [2.0, 0, 0]
    built = build(parse_scene(data, tmp_path / "s.toml"))
    v = built.substeps.reasons["c"][1]
    assert built.substeps.reasons["c"][0] == "contact" and v == pytest.approx(15.0, rel=1e-3)
    assert built.substeps.count == int(np.ceil(built.scene.timestep * v / (CONTACT_FRACTION * 0.004)))
    assert v * built.model.opt.timestep <= CONTACT_FRACTION * 0.004 and tunnel_warnings(built) == []
    data["motion"][1]["keys"][1]["pos"] = [400.0, 0, 0]
    built = build(parse_scene(data, tmp_path / "s.toml"))
    assert built.substeps.count == MAX_SUBSTEPS and built.substeps.capped
    (warning,) = tunnel_warnings(built)
    assert warning.startswith("part 'shuttle/plate' moves at up to 3000 m/s")
    assert "(0.004 m; the part is 0.002 m thick)" in warning
    assert "scene.timestep <= 8.53e-05 s would do" in warning
    data["effects"]["contact"] = []
    assert tunnel_warnings(build(parse_scene(data, tmp_path / "s.toml"))) == []
