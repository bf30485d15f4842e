"""A cable's material as MuJoCo's parameters (cablecheck.build.cablephysics), against the
beam's closed forms: the first bending mode as held, the Rayleigh damping
ratio it sets with the integrator's own, and the edge impedance's width."""

from __future__ import annotations

import dataclasses
from types import SimpleNamespace

import numpy as np
import pytest
from buildscenes import slider_scene
from scipy.optimize import brentq

from cablecheck.build.cablephysics import (
    EDGE_IMPEDANCE,
    EDGE_YIELD,
    FIRST_BENDING_MODE,
    damping_step,
    edge_solimp,
    first_bending_frequency,
    first_mode,
    rayleigh_damping,
    step_damping_ratio,
)
from cablecheck.scene.load import parse_scene


@pytest.fixture
def cable(tmp_path):
    return parse_scene(slider_scene(tmp_path), tmp_path / "s.toml").cables[0]


def test_first_mode_is_the_first_root_of_the_clamped_beam_equation():
    def f(x):
        return np.cos(x) * np.cosh(x) - 1.0

    assert FIRST_BENDING_MODE == pytest.approx(brentq(f, 4.0, 5.5, xtol=1e-15), abs=1e-13)
    inner = np.linspace(0.1, 4.7, 2000)
    assert np.all(f(inner) < 0)                     # no root between 0 and it


@pytest.mark.parametrize("young, density, radius, length", [
    (1.0e6, 1500.0, 0.004, 0.7), (2.0e9, 7800.0, 0.0005, 0.05), (5.0e4, 900.0, 0.02, 12.0)])
def test_first_bending_frequency_and_damping_ratio(cable, young, density, radius, length):
    c = dataclasses.replace(cable, young=young, density=density, radius=radius, damping=0.3)
    ei = young * np.pi * radius ** 4 / 4.0           # bending stiffness of a round section
    mu = density * np.pi * radius ** 2                # mass per length
    omega = FIRST_BENDING_MODE ** 2 * np.sqrt(ei / (mu * length ** 4))
    assert first_bending_frequency(c, length) == pytest.approx(omega, rel=1e-12)
    beta = rayleigh_damping(0.3, omega, 1e-9 / omega)
    assert beta * omega / 2.0 == pytest.approx(0.3, rel=1e-6)   # zeta = beta omega / 2 as h -> 0
    assert rayleigh_damping(0.0, omega, 1e-3) == 0.0


def _rod(cable, n, length=0.5, clamps=()):
    """rest_s of `n` regular elements plus a clamp's held edge (5 % of one) at each end in `clamps`."""
    e = length / n
    seg = [e] * n
    if "start" in clamps:
        seg = [0.05 * e] + seg
    if "end" in clamps:
        seg = seg + [0.05 * e]
    return np.concatenate([[0.0], np.cumsum(seg)])


@pytest.mark.parametrize("holds, bl", [
    ("clamped-free", 1.8751040687), ("clamped-clamped", 4.7300407449), ("pinned-pinned", np.pi),
    ("free-free", 4.7300407449), ("clamped-pinned", 3.9266023120)])
def test_first_mode_as_held_against_the_beams_closed_forms(cable, holds, bl):
    """The discrete rod's first mode with its held vertices fixed (a clamp:
    the end vertex and its short held edge's other one) within 0.3 % of
    (beta_1 L)^2 / L^2 sqrt(EI / mu) at 80 elements."""
    length, n = 0.5, 80
    c = dataclasses.replace(cable, young=4e8, density=1500.0, radius=0.004)
    start, end = holds.split("-")
    clamps = [k for k, h in (("start", start), ("end", end)) if h == "clamped"]
    s = _rod(c, n, length, clamps)
    held = {"clamped": [0, 1], "pinned": [0], "free": []}[start]
    last = len(s) - 1
    held += {"clamped": [last - 1, last], "pinned": [last], "free": []}[end]
    omega = bl ** 2 / length ** 2 * np.sqrt(c.young * c.radius ** 2 / (4.0 * c.density))
    assert first_mode(s, held, c) == pytest.approx(omega, rel=3e-3)


@pytest.mark.parametrize("omega, h, zeta", [(90.8, 2e-3, 0.1), (90.8, 7.4e-5, 0.02), (8.2, 2e-3, 0.02),
                                            (500.0, 1e-4, 0.3)])
def test_rayleigh_damping_makes_up_the_integrators_own_to_the_declared_ratio(omega, h, zeta):
    """Backward Euler damps a mode by about omega h / 2 by itself; beta makes
    the mode's discrete damping ratio exactly the declared one."""
    own = step_damping_ratio(omega, h)
    assert own == pytest.approx(omega * h / 2.0, rel=0.02)
    beta = rayleigh_damping(zeta, omega, h)
    assert 0.0 < beta < 2.0 * zeta / omega
    assert step_damping_ratio(omega, h, beta) == pytest.approx(zeta, rel=1e-9)


def test_discrete_damping_ratio_is_what_a_step_by_step_oscillator_decays_at():
    """step_damping_ratio against an oscillator stepped as MuJoCo's discrete
    integrator does (implicit in stiffness and damping), logarithmic decrement."""
    omega, h, beta = 90.8, 1e-3, 4e-4
    c = beta * omega ** 2
    x, v, peaks = 1.0, 0.0, []
    xs = []
    for _ in range(4000):
        v = (v - h * omega ** 2 * x) / (1.0 + h * c + h * h * omega ** 2)
        x = x + h * v
        xs.append(x)
    xs = np.array(xs)
    k = np.flatnonzero((xs[1:-1] > xs[:-2]) & (xs[1:-1] >= xs[2:])) + 1
    delta = np.log(xs[k[0]] / xs[k[10]]) / 10
    assert delta / np.sqrt(4 * np.pi ** 2 + delta ** 2) == pytest.approx(step_damping_ratio(omega, h, beta), rel=0.02)


def test_the_damping_step_leaves_the_integrator_at_most_the_declared_ratio():
    h = damping_step(0.02, 90.8)
    assert step_damping_ratio(90.8, h) == pytest.approx(0.02, rel=1e-9)
    assert h == pytest.approx(2 * 0.02 / 90.8, rel=0.01)
    assert damping_step(0.0, 90.8) == np.inf


def test_edge_impedance_width_is_four_percent_of_the_longest_element():
    straight = np.zeros((5, 3))
    straight[:, 0] = np.cumsum([0.0, 0.02, 0.05, 0.02, 0.02])
    d0, dw, width, mid, power = map(float, edge_solimp(SimpleNamespace(straight=straight)).split())
    assert (d0, dw, mid, power) == (EDGE_IMPEDANCE, EDGE_YIELD, 0.5, 6.0)
    assert width == pytest.approx(0.04 * 0.05, rel=1e-12)
