"""Friction per cable and per part (`friction`, cablecheck.build.mjspec): read and checked,
written as MuJoCo's coefficients and priorities, and measured: a short cable
on an inclined plane (stays at 15 degrees, slides at 20 with friction 0.3,
in every direction of the slope: elliptic cones) and a cable sliding round a
fixed drum (the capstan's T_B / T_A = e^(mu theta)).

Measured on the branch that introduced them (2 ms step): a 0.2 m cable with
friction 0.3 moves 1.6 mm in 1 s at 15 degrees (the resting float of half a
radius, 1.5 mm normal to the slope, and creep) and 326 mm at 20 (0.295 m for
exact Coulomb friction: sliding friction 2 % low), at every azimuth; with
MuJoCo's default pyramidal cone it slid 263 mm at 15 degrees with the slope at
35 degrees to x. Capstan, mu = 0.3: 2.566 for e^(0.3 pi) = 2.566 (half a
turn), 1.62 for 1.60 (a quarter). Without the contact margin (the resting
cable on the surface, tests/test_resting.py): 0.05 mm at 15 degrees, 295.4 mm
at 20; capstan 2.555 and 1.606.
"""

from __future__ import annotations

from pathlib import Path

import mujoco
import numpy as np
import pytest

from cablecheck.build.mjspec import CABLE_PRIORITY, FRICTION_PRIORITY
from cablecheck.build.stages import build
from cablecheck.run.loop import Simulation
from cablecheck.scene.errors import SceneError
from cablecheck.scene.frames import euler_matrix
from cablecheck.scene.load import parse_scene

FILE = Path("/virtual/friction.toml")


def _parse(data: dict):
    return parse_scene(data, FILE)


def _incline_scene(slope: float, azimuth: float, cable_mu=0.3, part_mu=None, shape="plane",
                   duration=1.0, across: bool = False) -> tuple[dict, np.ndarray]:
    """A 0.2 m cable (r = 3 mm, free ends) lying down a slope of `slope`
    degrees whose downhill direction is `azimuth` degrees from x (`across`:
    level across it, where it can roll); and the slope's normal."""
    th, ph = np.radians(slope), np.radians(azimuth)
    # R = Rx(a) Ry(b) puts the normal at (sin th cos ph, sin th sin ph, cos th)
    a = np.arctan2(-np.sin(th) * np.sin(ph), np.cos(th))
    b = np.arcsin(np.sin(th) * np.cos(ph))
    euler = [float(np.degrees(a)), float(np.degrees(b)), 0.0]
    n = euler_matrix(euler)[:, 2]
    assert np.allclose(n, [np.sin(th) * np.cos(ph), np.sin(th) * np.sin(ph), np.cos(th)], atol=1e-12)
    level = np.cross(n, [np.cos(ph), np.sin(ph), 0.0])
    level /= np.linalg.norm(level)
    along = level if across else np.cross(level, n)     # level across it, or down its fall line
    r = 0.003
    pts = [list(n * r + s * along) for s in (-0.1, 0.0, 0.1)]
    part = {"name": "slope", "shape": shape, "euler": euler}
    if shape == "box":
        part.update(size=[1.0, 1.0, 0.05], pos=list(-0.05 * n))
    if part_mu is not None:
        part["friction"] = part_mu
    cable = {"name": "c", "radius": r, "points": pts, "start": {"hold": "free"}, "end": {"hold": "free"}}
    if cable_mu is not None:
        cable["friction"] = cable_mu
    return ({"scene": {"name": "incline", "units": "m", "duration": duration, "settle": 0.0, "timestep": 0.002},
             "effects": {"contact": ["cable-structure"]}, "parts": [part], "cables": [cable]}, n)


def incline_slide(slope: float, azimuth: float, **kw) -> float:
    """How far (m) the cable's centre moves along the slope in 1 s from rest."""
    data, n = _incline_scene(slope, azimuth, **kw)
    sim = Simulation(build(_parse(data), detect=False))
    sim.reset()
    first = None
    for state in sim.steps(contacts=False):
        centre = state.cables[0].mean(axis=0)
        first = centre if first is None else first
    d = centre - first
    return float(np.linalg.norm(d - np.dot(d, n) * n))


def coulomb_slide(slope: float, mu: float, t: float = 1.0) -> float:
    th = np.radians(slope)
    return 0.5 * 9.81 * max(0.0, np.sin(th) - mu * np.cos(th)) * t * t


# -- the keys --------------------------------------------------------------------


@pytest.mark.parametrize("table", ["cables", "parts"])
@pytest.mark.parametrize("value, fragment", [(-0.1, "must not be negative"), (float("nan"), "finite"),
                                             ("0.3", "expected a number"), (True, "expected a number")])
def test_friction_must_be_a_number_at_least_zero(table, value, fragment):
    data, _ = _incline_scene(15, 0)
    data[table][0]["friction"] = value
    with pytest.raises(SceneError) as exc:
        _parse(data)
    assert exc.value.key == f"{table}[0].friction", str(exc.value)
    assert fragment in exc.value.problem


def test_friction_is_read_and_optional():
    data, _ = _incline_scene(15, 0, cable_mu=0.25, part_mu=0)
    scene = _parse(data)
    assert scene.cables[0].friction == 0.25 and scene.parts[0].friction == 0.0
    data, _ = _incline_scene(15, 0, cable_mu=None)
    scene = _parse(data)
    assert scene.cables[0].friction is None and scene.parts[0].friction is None


def test_friction_is_written_as_mujoco_coefficients_and_priorities():
    """Unset: priorities as before (cable 1 over the part's 0) and MuJoCo's 1.0;
    set: priority 2 with the coefficient; a part that sets friction carries the
    cables' solref and solimp, its solref following the step (set_step)."""
    def model(cable_mu, part_mu):
        data, _ = _incline_scene(15, 0, cable_mu=cable_mu, part_mu=part_mu)
        return build(_parse(data), detect=False)

    built = model(None, None)
    m = built.model
    assert m.opt.cone == mujoco.mjtCone.mjCONE_ELLIPTIC
    assert m.flex_priority[0] == CABLE_PRIORITY and m.flex_friction[0, 0] == 1.0
    g = built.parts[0].geom_id
    assert m.geom_priority[g] == 0 and m.geom_friction[g, 0] == 1.0

    built = model(0.3, 0.45)
    m = built.model
    g = built.parts[0].geom_id
    assert m.flex_priority[0] == FRICTION_PRIORITY and m.flex_friction[0, 0] == 0.3
    assert m.geom_priority[g] == FRICTION_PRIORITY and m.geom_friction[g, 0] == 0.45
    assert m.geom_condim[g] == 3
    assert np.allclose(m.geom_solref[g], m.flex_solref[0]) and np.allclose(m.geom_solimp[g], m.flex_solimp[0])


@pytest.mark.parametrize("cable_mu, part_mu, mu", [(0.3, None, 0.3), (None, 0.3, 0.3), (0.3, 0.8, 0.8),
                                                   (0.8, 0.3, 0.8), (None, None, 1.0), (0.0, None, 0.0)])
def test_contact_friction_combines_as_mujoco_does(cable_mu, part_mu, mu):
    """The contact's coefficient: the larger where both set one, the one that
    is set, else MuJoCo's 1.0 (read from MuJoCo's own contacts)."""
    data, _ = _incline_scene(15, 0, cable_mu=cable_mu, part_mu=part_mu, duration=0.02)
    sim = Simulation(build(_parse(data), detect=False))
    sim.reset()
    for _ in sim.steps(contacts=False):
        pass
    d = sim.data
    assert d.ncon > 0
    assert np.allclose(d.contact.friction[:d.ncon, :2], max(mu, mujoco.mjMINMU))   # MuJoCo's floor, 1e-5
    assert np.all(d.contact.dim[:d.ncon] == 3)


# -- the inclined plane ----------------------------------------------------------


@pytest.mark.parametrize("azimuth", [0.0, 35.0, 60.0, 135.0])
def test_cable_with_friction_0_3_stays_at_15_degrees_and_slides_at_20_in_every_direction(azimuth):
    """Lying down the slope (where a round cable cannot roll): tan 15 = 0.268
    < 0.3 < tan 20 = 0.364, so at 15 degrees the cable moves under 5 mm in
    1 s; at 20 it slides within 15 % of Coulomb's 0.295 m."""
    stay = incline_slide(15.0, azimuth)
    slide = incline_slide(20.0, azimuth)
    assert stay < 0.005, f"slid {stay * 1e3:.1f} mm at 15 degrees"
    assert slide == pytest.approx(coulomb_slide(20.0, 0.3), rel=0.15), f"slid {slide * 1e3:.1f} mm at 20 degrees"


@pytest.mark.parametrize("slope", [15.0, 20.0])
def test_a_cable_lying_across_a_slope_rolls_down_as_a_solid_cylinder(slope):
    """Lying level across the slope a round cable rolls (MuJoCo's rod turns
    each element about its axis, with its polar inertia m r^2 / 2): a solid
    cylinder rolls without slipping where mu >= tan(theta) / 3, down at
    2/3 g sin(theta), g sin(theta) t^2 / 3 in 1 s, friction 0.3 or not."""
    rolled = incline_slide(slope, 35.0, across=True)
    assert rolled == pytest.approx(9.81 * np.sin(np.radians(slope)) / 3.0, rel=0.02)


def test_friction_of_a_tilted_box_part_holds_and_frictionless_slides_freely():
    """A box part with friction 0.3 (the cable's unset) acts like the plane;
    friction 0 slides as a frictionless block, g sin(theta) t^2 / 2."""
    assert incline_slide(15.0, 35.0, cable_mu=None, part_mu=0.3, shape="box") < 0.005
    assert incline_slide(20.0, 35.0, cable_mu=None, part_mu=0.3, shape="box") == pytest.approx(
        coulomb_slide(20.0, 0.3), rel=0.15)
    assert incline_slide(15.0, 35.0, cable_mu=0.0) == pytest.approx(coulomb_slide(15.0, 0.0), rel=0.02)


def test_pyramidal_cone_would_let_the_cable_slide_at_15_degrees():
    """Why the elliptic cone: MuJoCo's default pyramidal cone (condim 3)
    bounds the friction force by |f_1| + |f_2| <= mu N in the contact frame,
    mu / (cos 35 + sin 35) = 0.215 < tan 15 at 35 degrees to its axes
    (measured 263 mm in 1 s at 35 degrees to x)."""
    data, n = _incline_scene(15.0, 35.0)
    built = build(_parse(data), detect=False)
    built.model.opt.cone = mujoco.mjtCone.mjCONE_PYRAMIDAL
    sim = Simulation(built)
    sim.reset()
    pts = [s.cables[0].mean(axis=0) for s in sim.steps(contacts=False)]
    d = pts[-1] - pts[0]
    assert np.linalg.norm(d - np.dot(d, n) * n) > 0.05


# -- the capstan -----------------------------------------------------------------


def capstan_ratio(mu: float, wrap: float, part: bool = False) -> float:
    """T_B / T_A of a cable (r = 2 mm, limp, gravity off) lying `wrap` radians
    round a fixed drum of radius 50 mm, both ends pinned to bodies moved
    along the cable's legs: the feeding end 50 mm towards the drum and the
    pulling end 60 mm away in 1 s, so the cable slides round the drum and
    stretches. The tensions are the edge-length equality forces of an edge
    in the middle of each straight leg, averaged over the last half second.

    Every sliding contact carries exactly mu N here; the setup is the one
    where the cable's own dynamics stay out of the way (docs/physics.md:
    a 1 ms step with the default damping reads 6.7 % low, a cable 7-70
    times denser 15-35 % low, mu = 1 about 50 % low)."""
    drum, r, leg, T = 0.05, 0.002, 0.1, 1.0
    rc = drum + r
    angs = np.linspace(np.pi / 2 + wrap / 2, np.pi / 2 - wrap / 2, 24)
    arc = np.stack([rc * np.cos(angs), np.zeros_like(angs), rc * np.sin(angs)], 1)
    d0 = np.array([-np.sin(angs[0]), 0.0, np.cos(angs[0])])     # from the arc out along the feeding leg
    d1 = np.array([np.sin(angs[-1]), 0.0, -np.cos(angs[-1])])   # from the arc out along the pulling leg
    a, b = arc[0] + leg * d0, arc[-1] + leg * d1
    part_t = {"name": "drum", "shape": "cylinder", "size": [drum, 0.05], "euler": [90, 0, 0]}
    cable = {"name": "c", "radius": r, "points": np.vstack([a, arc, b]).tolist(), "segments": 60, "young": 1e6,
             "start": {"body": "feeder", "hold": "pin"}, "end": {"body": "puller", "hold": "pin"}}
    (part_t if part else cable)["friction"] = mu
    scene = _parse({
        "scene": {"name": "capstan", "units": "m", "duration": T, "settle": 0.0, "timestep": 0.002},
        "effects": {"gravity": False, "contact": ["cable-structure"]},
        "bodies": [{"name": "feeder", "pos": a.tolist()}, {"name": "puller", "pos": b.tolist()}],
        "parts": [part_t], "cables": [cable],
        "motion": [{"body": "puller", "interpolation": "linear",
                    "keys": [{"t": 0, "pos": b.tolist()}, {"t": T, "pos": (b + 0.06 * d1).tolist()}]},
                   {"body": "feeder", "interpolation": "linear",
                    "keys": [{"t": 0, "pos": a.tolist()}, {"t": T, "pos": (a - 0.05 * d0).tolist()}]}]})
    sim = Simulation(build(scene, detect=False))
    sim.reset()
    m, d = sim.model, sim.data
    flex_eq = np.flatnonzero(m.eq_type == int(mujoco.mjtEq.mjEQ_FLEX))
    ta, tb = [], []
    for state in sim.steps(contacts=False):
        rows = np.flatnonzero((d.efc_type == mujoco.mjtConstraint.mjCNSTR_EQUALITY)
                              & np.isin(d.efc_id, flex_eq))
        assert len(rows) == 60   # one row per edge, in edge order
        if state.t >= 0.5 * T:
            ta.append(-d.efc_force[rows[4]])     # tension > 0
            tb.append(-d.efc_force[rows[-5]])
    assert min(ta) > 0.0
    return float(np.mean(tb) / np.mean(ta))


@pytest.mark.parametrize("wrap", [np.pi, np.pi / 2])
def test_capstan_ratio_within_five_percent_of_e_to_the_mu_theta(wrap):
    ratio = capstan_ratio(0.3, wrap)
    assert ratio == pytest.approx(np.exp(0.3 * wrap), rel=0.05), f"{ratio:.3f} vs {np.exp(0.3 * wrap):.3f}"


def test_capstan_with_the_drums_friction():
    ratio = capstan_ratio(0.3, np.pi, part=True)
    assert ratio == pytest.approx(np.exp(0.3 * np.pi), rel=0.05), f"{ratio:.3f} vs {np.exp(0.3 * np.pi):.3f}"
