"""The analytic references (cablecheck.bench.reference) against independent computations:
a discrete chain of many links (catenary and hanging-chain modes), a
numerically integrated Euler-Bernoulli beam (cantilever) and a shooting
method (elastica), each solved another way than the module does."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st
from scipy.integrate import cumulative_trapezoid, solve_ivp
from scipy.linalg import eigh_tridiagonal
from scipy.optimize import brentq

from cablecheck.bench import reference as ref


def _discrete_catenary_sag(span: float, length: float, links: int = 4000) -> float:
    """Sag of a chain of `links` equal rigid links with its weight lumped at
    the joints (an even count). With horizontal tension H, each joint's
    weight turns the chain by a fixed step of vertical tension, so the
    slopes are tan(theta_k) = c ((N - 1) / 2 - k); c is found from the span."""
    n = links
    step = length / n
    k = (n - 1) / 2.0 - np.arange(n)

    def span_of(c):
        return step * np.sum(1.0 / np.sqrt(1.0 + (c * k) ** 2))

    c = brentq(lambda c: span_of(c) - span, 0.0, 1e6, xtol=1e-15, rtol=1e-15)
    theta = np.arctan(c * k[: n // 2])
    return float(step * np.sum(np.sin(theta)))


@settings(max_examples=40, deadline=None)
@given(span=st.floats(0.01, 50.0), slack=st.floats(1.0005, 4.0))
def test_catenary_sag_is_the_limit_of_a_chain_of_links(span, slack):
    length = span * slack
    assert ref.catenary_sag(span, length) == pytest.approx(_discrete_catenary_sag(span, length), rel=1e-5)


def test_catenary_sag_limits():
    """Little slack: the shallow parabola s = sqrt(3 D (L - D) / 8); a chain
    whose ends nearly meet hangs as two halves, sag -> L / 2."""
    d = 1.0
    for slack in (1e-4, 1e-3):
        parabola = np.sqrt(3.0 * d * (d * slack) / 8.0)
        assert ref.catenary_sag(d, d * (1 + slack)) == pytest.approx(parabola, rel=2 * slack)
    assert ref.catenary_sag(1e-3, 1.0) == pytest.approx(0.5, rel=2e-3)
    p = ref.CATENARY
    assert ref.catenary_sag(p["span"], p["length"]) == pytest.approx(_discrete_catenary_sag(p["span"], p["length"]),
                                                                     rel=1e-6)


def _beam_tip(length: float, w: float, ei: float, n: int = 20001) -> float:
    """Small-deflection tip of a clamped beam under load w per length: the
    moment w (L - s)^2 / 2 integrated twice (curvature -> slope -> deflection)."""
    s = np.linspace(0.0, length, n)
    curvature = w * (length - s) ** 2 / (2.0 * ei)
    slope = cumulative_trapezoid(curvature, s, initial=0.0)
    return float(cumulative_trapezoid(slope, s, initial=0.0)[-1])


rod_length = st.floats(0.02, 3.0)
rod_radius = st.floats(2e-4, 0.02)
density = st.floats(500.0, 8000.0)
young = st.floats(1e5, 2e11)


@settings(max_examples=40, deadline=None)
@given(rod_length, rod_radius, density, young)
def test_cantilever_tip_is_the_integrated_beam(length, radius, rho, e):
    w = rho * ref.G * np.pi * radius ** 2
    ei = e * np.pi * radius ** 4 / 4.0
    assert ref.cantilever_tip(length, radius, rho, e) == pytest.approx(_beam_tip(length, w, ei), rel=1e-6)


def _shooting_elastica_tip(length: float, w: float, ei: float) -> float:
    """The elastica EI theta'' = -w (L - s) cos(theta), theta(0) = 0,
    theta'(L) = 0, by shooting on theta'(0) (an initial value problem per
    guess; the linear beam's w L^2 / 2EI bounds it from above)."""
    def shoot(k):
        sol = solve_ivp(lambda s, y: [y[1], -w * (length - s) * np.cos(y[0]) / ei, np.sin(y[0])],
                        (0.0, length), [0.0, k, 0.0], rtol=1e-11, atol=1e-13, method="DOP853")
        return sol.y[:, -1]

    k = brentq(lambda k: shoot(k)[1], 0.0, 1.001 * w * length ** 2 / (2.0 * ei), xtol=1e-14, rtol=1e-13)
    return float(shoot(k)[2])


@settings(max_examples=12, deadline=None)
@given(length=st.floats(0.05, 2.0), ei=st.floats(1e-4, 10.0), load=st.floats(0.01, 8.0))
def test_elastica_tip_matches_shooting(length, ei, load):
    """Any rod and any load w L^3 / EI up to 8 (tips well past the linear
    range): collocation and shooting agree; the tip lies above the linear
    beam's and within the rod's length."""
    w = load * ei / length ** 3
    tip = ref.elastica_tip(length, w, ei)
    assert tip == pytest.approx(_shooting_elastica_tip(length, w, ei), rel=1e-6)
    assert tip < min(length, w * length ** 4 / (8.0 * ei))


def test_elastica_meets_the_linear_beam_at_small_loads_and_the_stated_tip():
    length, ei = 0.5, 1.0
    w = 1e-3 * ei / length ** 3
    assert ref.elastica_tip(length, w, ei) == pytest.approx(w * length ** 4 / (8.0 * ei), rel=1e-4)
    p = ref.ELASTICA
    w = p["density"] * ref.G * np.pi * p["radius"] ** 2
    ei = p["young"] * np.pi * p["radius"] ** 4 / 4.0
    assert w * p["length"] ** 3 / ei == pytest.approx(3.07, abs=0.005)             # the constant's docstring
    assert ref.elastica_tip(p["length"], w, ei) / p["length"] == pytest.approx(0.346, abs=0.0005)
    assert ref.cantilever_tip(p["length"], p["radius"], p["density"], p["young"]) / p["length"] == pytest.approx(
        0.383, abs=0.0005)


def _chain_modes(length: float, g: float, n: int) -> tuple[float, np.ndarray]:
    """First-mode period and shape (at the n nodes, top first below the
    fixed point) of n equal point masses on massless links: the tension of
    a link carries the nodes below it, T_i = m g (n - i + 1), and small
    sideways motion is the tridiagonal eigenproblem K x = omega^2 x."""
    step = length / n
    tension = g * (n - np.arange(1, n + 1) + 1.0)
    below = np.r_[tension[1:], 0.0]
    w2, v = eigh_tridiagonal((tension + below) / step, -below[:-1] / step, select="i", select_range=(0, 0))
    return 2.0 * np.pi / np.sqrt(w2[0]), v[:, 0] / v[-1, 0]


@settings(max_examples=20, deadline=None)
@given(length=st.floats(0.05, 20.0), g=st.floats(1.0, 30.0))
def test_chain_period_is_the_limit_of_many_masses(length, g):
    """The discrete chain converges as 1/n: the Richardson extrapolation of
    n and 2n masses gives the continuous chain's period."""
    p1, _ = _chain_modes(length, g, 1000)
    p2, _ = _chain_modes(length, g, 2000)
    assert ref.chain_period(length, g) == pytest.approx(2.0 * p2 - p1, rel=2e-6)


def test_chain_mode_is_the_discrete_shape():
    length = 2.0
    n = 2000
    _, shape = _chain_modes(length, ref.G, n)
    height = length - np.arange(1, n + 1) * length / n     # above the free end
    assert np.abs(shape - ref.chain_mode(height, length)).max() < 3e-5
    assert ref.chain_mode(0.0, length) == pytest.approx(1.0)                      # free end
    assert ref.chain_mode(length, length) == pytest.approx(0.0, abs=1e-12)        # fixed top: J0's first zero
    assert ref.J0_FIRST_ZERO == pytest.approx(2.404825557695773, abs=1e-14)


def test_scenes_are_the_stated_cables():
    cat = ref.catenary_scene(elements=20)
    (c,) = cat.cables
    assert cat.units == "m" and cat.duration == 0.0 and c.young == 1.0
    assert np.allclose(c.start.pos, [0, 0, 1.0]) and np.allclose(c.end.pos, [ref.CATENARY["span"], 0, 1.0])
    rod = ref.cantilever_scene(None)
    (r,) = rod.cables
    assert r.end.hold == "free" and r.young == ref.CANTILEVER["young"]
    chain = ref.chain_scene(30, duration=0.5)
    (ch,) = chain.cables
    assert chain.duration == 0.5 and chain.settle == 0.0 and ch.end.hold == "free"
    assert np.allclose(ch.end.pos, [0, 0, ref.CHAIN["top"] - ref.CHAIN["length"]])
