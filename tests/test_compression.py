"""Length in compression (issue 31 item 2): the edges' give under an axial
load against its closed form, a rod buckled by its ends within 0.1 % of
its length at the default element count, a perfectly straight rod pushed
past its buckling load buckling (from the route's deterministic
imperfection), and a run warning where a cable is shorter than its length
by more than the tolerance.

Rod: 0.5 m, r 3 mm, 2 GPa, 1500 kg/m^3 (EI = 0.127 N m^2, clamped Euler
load 20.1 N; default 20 elements), gravity off; `damping = 0` so that the
compression need alone sets the step (the default damping's need is
stricter still for it)."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

import cablecheck.build.cableplan
from cablecheck.bench import physics_cases as validation
from cablecheck.build.cablephysics import (
    COMPRESSION_TOLERANCE,
    EDGE_IMPEDANCE,
    buckling_load,
    compression_strain,
)
from cablecheck.build.cableplan import IMPERFECTION, imperfect
from cablecheck.build.mjspec import set_step
from cablecheck.build.stages import build, cable_damping
from cablecheck.run.loop import Simulation
from cablecheck.run.runner import RunOptions, run_outcome
from cablecheck.scene.load import parse_scene

ROD = validation.ROD


def _bowed_scene(elements: int, shortening: float = 0.02) -> dict:
    return {"scene": {"name": "bowed", "units": "m", "duration": 0.0, "settle": 3.0},
            "effects": {"gravity": False},
            "cables": [{"name": "rod", "radius": ROD["radius"], "start": {"pos": [0, 0, 1]},
                        "end": {"pos": [(1 - shortening) * ROD["length"], 0, 1]}, "length": ROD["length"],
                        "young": ROD["young"], "density": ROD["density"], "segments": elements,
                        "damping": 0.0}]}


@pytest.mark.parametrize("elements, count", [(10, 1), (20, 1), (20, 2), (40, 2)])
def test_the_edges_give_as_the_closed_form_says(elements, count):
    """At a step forced to `count` substeps the bowed rod is shorter by
    (1 - d) (tc + h)^2 F / (mu l^2), F its end force (the middle edge's):
    (elements x step)^2. Measured within 3 %: 20 elements at 2 ms, 0.27 %."""
    built = build(parse_scene(_bowed_scene(elements), Path("/virtual/bowed.toml")), detect=False)
    built = replace(built, substeps=replace(built.substeps, count=count, step=0.002 / count))
    set_step(built.model, built.substeps.step, cable_damping(built))
    sim = Simulation(built)
    sim.reset()
    sim.settle()
    pts = next(sim.steps(contacts=False)).cables[0]
    c = built.cables[0]
    strain = np.linalg.norm(np.diff(pts, axis=0), axis=1).sum() / c.length - 1.0
    force = validation._middle_force(sim)
    expected = compression_strain(force, c.element_length, built.scene.cables[0], built.substeps.step)
    assert -strain == pytest.approx(expected, rel=0.03)


def test_a_rod_buckled_by_its_ends_keeps_its_length_at_the_default_count():
    """Default elements (20), damping 0: the compression need takes 3
    substeps; least strain -0.030 % (-0.27 % at 1 substep before), end force
    and mid deflection the clamped elastica's within 0.5 %."""
    r = validation.bowed(damping=0.0, duration=0.1)
    assert r.extra["reason"] == "compression"
    assert -COMPRESSION_TOLERANCE < r.measured < 0.0
    assert r.extra["force"] == pytest.approx(r.extra["force_ref"], rel=0.01)
    assert r.extra["deflection"] == pytest.approx(r.extra["deflection_ref"], rel=0.02)


def test_a_stiff_short_wire_bowed_at_the_default_count_keeps_its_length():
    """0.1 m steel wire, 1 mm thick, 8 elements: 2.0 % short and flat
    (force 1.8 N for 39 N) at the former 2 substeps; now within 0.1 %."""
    r = validation.bowed(damping=0.0, rod=validation.WIRE, duration=0.05)
    assert -COMPRESSION_TOLERANCE < r.measured < 0.0
    assert r.extra["force"] == pytest.approx(r.extra["force_ref"], rel=0.05)


def test_buckling_load_is_the_stiffest_runs():
    cable = build(parse_scene(_bowed_scene(20), Path("/virtual/bowed.toml")), detect=False).scene.cables[0]
    ei = cable.young * np.pi * cable.radius ** 4 / 4.0
    s = np.linspace(0.0, 1.0, 11)
    assert buckling_load(s, [0, 10], cable) == pytest.approx(4 * np.pi ** 2 * ei, rel=1e-12)
    # a clip at 0.3 holding an edge (3, 4): the shorter run; held pairs with no free vertex between do not count
    assert buckling_load(s, [0, 3, 4, 10], cable) == pytest.approx(4 * np.pi ** 2 * ei / 0.3 ** 2, rel=1e-12)
    assert buckling_load(s, [0], cable) == pytest.approx(np.pi ** 2 * ei / 4, rel=1e-12)       # a cantilever
    assert buckling_load(s, [], cable) == pytest.approx(np.pi ** 2 * ei, rel=1e-12)            # held nowhere
    # a clip in the middle of a cable with free ends: the two cantilevers of 0.5
    assert buckling_load(s, [5], cable) == pytest.approx(np.pi ** 2 * ei, rel=1e-12)
    assert EDGE_IMPEDANCE < 1.0


def test_a_straight_run_between_holds_gets_the_imperfection():
    line = np.column_stack([np.linspace(0, 2.0, 11), np.zeros(11), np.zeros(11)])
    bowed = imperfect(line, [0, 1, 9, 10])
    assert bowed[5] == pytest.approx([1.0, 0.0, -IMPERFECTION * 1.6], abs=1e-15)    # the run 1..9, 1.6 long
    assert np.array_equal(bowed[[0, 1, 9, 10]], line[[0, 1, 9, 10]])
    lengths = np.linalg.norm(np.diff(bowed, axis=0), axis=1).sum()
    assert lengths - 2.0 == pytest.approx(0.0, abs=1e-11)
    upright = imperfect(line[:, [2, 1, 0]], [0, 10])                 # vertical: towards +x
    assert upright[5, 0] == pytest.approx(IMPERFECTION * 2.0, rel=1e-12) and upright[5, 1] == 0.0
    assert np.array_equal(imperfect(line, [0]), line)                # a run to a free end
    bent = line.copy()
    bent[5, 2] = 1e-3
    assert np.array_equal(imperfect(bent, [0, 10]), bent)            # already bent


def test_a_straight_rod_pushed_past_its_buckling_load_buckles():
    """Pushed in 3 % over 0.2 s: the clamped elastica's mid deflection and
    end force within 0.5 %, its length within 0.1 % throughout. Without the
    imperfection the same rod stays exactly straight, 3 % short, carrying
    over 100 times its Euler load (4446 N for 20.1)."""
    r = validation.straight_buckling(0.03, duration=0.3)
    assert r.measured == pytest.approx(r.reference, rel=0.01)
    assert r.extra["force"] == pytest.approx(r.extra["force_ref"], rel=0.01)
    assert -COMPRESSION_TOLERANCE < r.extra["least"] < 0.0
    assert abs(r.extra["side"][2]) == 1.0                   # in the plane of the imperfection (x, z)


def test_without_the_imperfection_a_straight_rod_stays_straight(monkeypatch):
    monkeypatch.setattr(cablecheck.build.cableplan, "IMPERFECTION", 0.0)
    r = validation.straight_buckling(0.03, duration=0.3)
    assert r.measured == 0.0
    assert r.extra["final"] == pytest.approx(-0.03, rel=0.01)
    assert r.extra["force"] > 100 * r.extra["force_ref"]


def _push_scene(tmp_path: Path) -> Path:
    path = tmp_path / "push.toml"
    path.write_text(f"""
[scene]
name = "push"
units = "m"
duration = 0.3
timestep = 0.002

[effects]
gravity = false

[[bodies]]
name = "b"
pos = [{ROD['length']}, 0, 1]

[[motion]]
body = "b"
interpolation = "linear"
keys = [ {{ t = 0.0, pos = [{ROD['length']}, 0, 1] }}, {{ t = 0.2, pos = [{0.97 * ROD['length']}, 0, 1] }} ]

[[cables]]
name = "rod"
radius = {ROD['radius']}
young = {ROD['young']}
density = {ROD['density']}
start = {{ pos = [0, 0, 1] }}
end = {{ body = "b", pos = [0, 0, 0] }}
""")
    return path


def test_a_cable_shorter_than_the_tolerance_is_warned_about(tmp_path, monkeypatch):
    """The straight rod without its imperfection is 3 % short at the end:
    the report's physics_warnings name it, the least strain and when; with
    it, no such warning."""
    from cablecheck.scene.load import load_scene
    path = _push_scene(tmp_path)
    out = run_outcome(load_scene(path), RunOptions(report=tmp_path / "r.json", record=None))
    assert not [w for w in out.physics_warnings if "shorter than its length" in w]
    assert out.cables[0].max_strain > -COMPRESSION_TOLERANCE
    monkeypatch.setattr(cablecheck.build.cableplan, "IMPERFECTION", 0.0)
    out = run_outcome(load_scene(path), RunOptions(report=tmp_path / "r.json", record=None))
    warned = [w for w in out.physics_warnings if "shorter than its length" in w]
    assert len(warned) == 1
    assert warned[0].startswith("cable 'rod' is shorter than its length by more than 0.1 %")
    assert "from t = 0.008 s" in warned[0] and "strain -3 %" in warned[0]
    assert out.cables[0].max_strain == pytest.approx(-0.03, rel=0.01)
