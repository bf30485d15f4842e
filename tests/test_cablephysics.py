"""A cable's material as MuJoCo's parameters (sim.cablephysics), against the
beam's closed forms: the clamped-clamped first mode, the Rayleigh damping
ratio it sets, and the edge impedance's width."""

from __future__ import annotations

import dataclasses
from types import SimpleNamespace

import numpy as np
import pytest
from buildscenes import slider_scene
from scipy.optimize import brentq

from sim.cablephysics import (
    EDGE_IMPEDANCE,
    EDGE_YIELD,
    FIRST_BENDING_MODE,
    edge_solimp,
    first_bending_frequency,
    rayleigh_damping,
)
from sim.scene import parse_scene


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
    beta = rayleigh_damping(c, length)
    assert beta * omega / 2.0 == pytest.approx(0.3, rel=1e-12)   # zeta = beta omega / 2
    assert rayleigh_damping(dataclasses.replace(c, damping=0.0), length) == 0.0


def test_edge_impedance_width_is_four_percent_of_the_longest_element():
    straight = np.zeros((5, 3))
    straight[:, 0] = np.cumsum([0.0, 0.02, 0.05, 0.02, 0.02])
    d0, dw, width, mid, power = map(float, edge_solimp(SimpleNamespace(straight=straight)).split())
    assert (d0, dw, mid, power) == (EDGE_IMPEDANCE, EDGE_YIELD, 0.5, 6.0)
    assert width == pytest.approx(0.04 * 0.05, rel=1e-12)
