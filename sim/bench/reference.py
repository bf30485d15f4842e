"""Analytic references for the cable model, and the one-cable scenes they are measured on.

Shared by the physics tests (tests/test_physics.py), `cablecheck bench`
(physics resolution table) and the validation table
(benchmarks/physics_validation.py, through `cablecheck.bench.physics_cases`), so all
measure against one implementation:

- `catenary_sag(span, length)`: sag of a uniform, perfectly limp chain of
  `length` hung between two points `span` apart at one height,
  a (cosh(D / 2a) - 1) with 2 a sinh(D / 2a) = L.
- `cantilever_tip(length, radius, density, young)`: small-deflection tip
  deflection of a clamped round rod under its own weight, w L^4 / (8 E I) with
  I = pi r^4 / 4 and w = rho g pi r^2.
- `elastica_tip(length, w, EI)`: the same rod at large deflection, the
  elastica EI theta'' = -w (L - s) cos(theta), theta(0) = 0, theta'(L) = 0,
  solved as a boundary value problem (scipy's collocation `solve_bvp`).
- `chain_period(length)`: first-mode period of a uniform hanging chain with
  a free lower end, 2 pi / ((j_0,1 / 2) sqrt(g / L)), j_0,1 = 2.4048 the
  first zero of the Bessel function J0 (Bernoulli, Euler): 1.2024 sqrt(g/L).
- `clamped_elastica(length, shortening, EI)`: a rod clamped at both ends
  whose ends are `shortening` of its length closer than its length (Euler's
  elastica): end force 4 (2 K(m) / pi)^2 pi^2 EI / L^2 and mid deflection
  k L / K(m), with 2 (1 - E(m) / K(m)) = shortening (m = k^2; the pinned
  elastica on half the length, twice over).
- `catenary_scene` / `cantilever_scene` / `elastica_scene` /
  `chain_scene`: the one-cable scenes, parsed by the real scene parser;
  the cantilevers and the chain have a free end (`hold = "free"`).

This module does not step or measure anything; callers build, settle and
compare (see `cablecheck.bench.physics_cases`, `cablecheck.bench.sim_tables.physics_table`).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from scipy.integrate import solve_bvp
from scipy.optimize import brentq
from scipy.special import ellipe, ellipk, j0, jn_zeros

from cablecheck.scene.load import parse_scene
from cablecheck.scene.records import Scene

G = 9.81
"""Gravity used by the references, m/s^2 (MuJoCo's default magnitude)."""

CATENARY = dict(span=0.8, length=1.0, height=1.0, radius=0.004, elements=40)
"""The limp cable of the catenary reference (metres; young 1 Pa, density 1500)."""

CANTILEVER = dict(length=0.2, radius=0.004, density=1500.0, young=4e8, height=1.0)
"""The clamped rod of the cantilever reference (metres, kg/m^3, Pa)."""

ELASTICA = dict(length=0.5, radius=0.004, density=1500.0, young=1.5e8, height=1.0)
"""The clamped rod of the large-deflection reference: w L^3 / EI = 3.07, tip
0.346 of its length below the clamp where w L^4 / 8EI says 0.383 (metres, kg/m^3, Pa)."""

CHAIN = dict(length=1.0, radius=0.004, density=1500.0, young=1.0, top=1.0, amplitude=0.02)
"""The hanging chain: limp (1 Pa), clamped at the top, free lower end;
started in its first mode with `amplitude` at the free end (metres)."""

J0_FIRST_ZERO = float(jn_zeros(0, 1)[0])
"""2.404825557695773: the first zero of J0."""


def catenary_sag(span: float, length: float) -> float:
    """Sag of a uniform chain of `length` hung between two points `span` apart at one height."""
    a = brentq(lambda a: 2.0 * a * np.sinh(span / (2.0 * a)) - length, 1e-3 * span, 1e3 * span)
    return float(a * (np.cosh(span / (2.0 * a)) - 1.0))


def cantilever_tip(length: float, radius: float, density: float, young: float, g: float = G) -> float:
    """Tip deflection w L^4 / (8 E I) of a clamped round rod under its own weight."""
    w = density * g * np.pi * radius ** 2
    inertia = np.pi * radius ** 4 / 4.0
    return float(w * length ** 4 / (8.0 * young * inertia))


def elastica_tip(length: float, w: float, bending_stiffness: float) -> float:
    """Tip deflection of a clamped rod of weight per length `w` at any deflection (the elastica).

    theta(s) is the slope below the horizontal; with x' = cos(theta) the
    moment of the weight beyond s gives EI theta'' = -w (L - s) cos(theta),
    theta(0) = 0 (clamped) and theta'(L) = 0 (free, no moment); the tip
    deflection is the integral of sin(theta)."""
    def rhs(s, y):
        theta, dtheta, z = y
        return np.vstack([dtheta, -w * (length - s) * np.cos(theta) / bending_stiffness, np.sin(theta)])

    def bc(ya, yb):
        return np.array([ya[0], yb[1], ya[2]])

    s = np.linspace(0.0, length, 201)
    sol = solve_bvp(rhs, bc, s, np.zeros((3, s.size)), tol=1e-8, max_nodes=100000)
    if not sol.success:
        raise RuntimeError(f"elastica did not converge: {sol.message}")
    return float(sol.sol(length)[2])


def clamped_elastica(length: float, shortening: float, bending_stiffness: float) -> tuple[float, float]:
    """End force (N) and mid deflection (m) of a rod clamped at both ends
    `shortening` (a fraction) of its `length` closer than its length.

    The buckled clamped rod is a pinned elastica of half its length between
    its inflection points (at L / 4 and 3 L / 4), with the same shortening
    fraction: 2 (1 - E(m) / K(m)) = shortening, force 4 (2 K / pi)^2 pi^2
    EI / L^2 (4 times the pinned rod's), mid deflection twice the pinned
    half's, 2 k (L / 2) / K."""
    m = brentq(lambda m: 2.0 * (1.0 - ellipe(m) / ellipk(m)) - shortening, 1e-14, 0.999999)
    force = 4.0 * (2.0 * ellipk(m) / np.pi) ** 2 * np.pi ** 2 * bending_stiffness / length ** 2
    return float(force), float(np.sqrt(m) * length / ellipk(m))


def chain_period(length: float, g: float = G) -> float:
    """First-mode period of a uniform hanging chain with a free lower end, seconds."""
    return float(2.0 * np.pi / (0.5 * J0_FIRST_ZERO * np.sqrt(g / length)))


def chain_mode(height_above_end, length: float) -> np.ndarray:
    """First-mode shape of the hanging chain at heights above its free end: J0(j01 sqrt(z / L))."""
    return j0(J0_FIRST_ZERO * np.sqrt(np.clip(np.asarray(height_above_end, float), 0.0, None) / length))


def one_cable_scene(name: str, cable: dict, settle: float, timestep: float = 0.002) -> Scene:
    """A scene in metres with one cable, no motion (duration 0) and `settle` seconds of settling."""
    data = {"scene": {"name": name, "units": "m", "duration": 0.0, "settle": settle,
                      "timestep": timestep},
            "cables": [cable]}
    return parse_scene(data, Path(f"/virtual/{name}.toml"))


def catenary_scene(elements: int = CATENARY["elements"], timestep: float = 0.002,
                   settle: float = 3.0) -> Scene:
    """The limp cable (young 1 Pa) of `CATENARY` between two world points."""
    p = CATENARY
    return one_cable_scene(f"catenary{elements}", {
        "name": "limp", "radius": p["radius"], "start": {"body": "world", "pos": [0, 0, p["height"]]},
        "end": {"body": "world", "pos": [p["span"], 0, p["height"]]}, "length": p["length"],
        "segments": elements, "young": 1.0, "density": 1500}, settle=settle, timestep=timestep)


def cantilever_scene(elements: int | None, timestep: float = 0.002, settle: float = 1.0,
                     rod: dict = CANTILEVER) -> Scene:
    """The rod of `rod` (`CANTILEVER` or `ELASTICA`), routed straight, clamped at
    the start, its end free; `elements` None: the builder's default count."""
    p = rod
    cable = {"name": "rod", "radius": p["radius"], "start": {"body": "world", "pos": [0, 0, p["height"]]},
             "end": {"pos": [p["length"], 0, p["height"]], "hold": "free"},
             "young": p["young"], "density": p["density"]}
    if elements is not None:
        cable["segments"] = elements
    return one_cable_scene(f"cantilever{elements}", cable, settle=settle, timestep=timestep)


def chain_scene(elements: int, duration: float, timestep: float = 0.002) -> Scene:
    """The hanging chain of `CHAIN`, routed straight down, no settling (the
    caller starts it in its mode)."""
    p = CHAIN
    data = {"scene": {"name": f"chain{elements}", "units": "m", "duration": duration, "settle": 0.0,
                      "timestep": timestep},
            "cables": [{"name": "chain", "radius": p["radius"], "start": {"pos": [0, 0, p["top"]]},
                        "end": {"pos": [0, 0, p["top"] - p["length"]], "hold": "free"},
                        "segments": elements, "young": p["young"], "density": p["density"]}]}
    return parse_scene(data, Path(f"/virtual/chain{elements}.toml"))
