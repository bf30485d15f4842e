"""A cable's material as MuJoCo's parameters: damping, time constants, impedances.

The rod's Rayleigh damping from the cable's damping ratio at its own
first bending mode as held, the integrator's own damping accounted for; the solref time constants of the edge-length equality and of
the cables' contacts, which follow the simulation step; the impedance of
the edge equality, stiff at small strain and yielding beyond a few percent.
docs/physics.md explains the model and its numbers.

This module is pure arithmetic on a cable's definition and a step: it does
not write the model (see `cablecheck.build.mjspec`) nor choose the step (see `cablecheck.build.substeps`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from cablecheck.scene.records import CableDef

if TYPE_CHECKING:
    from cablecheck.build.cableplan import CablePlan


FIRST_BENDING_MODE = 4.7300407448627040
"""beta_1 L of a beam's first bending mode with both ends clamped (or both
free): cos(bL) cosh(bL) = 1, omega_1 = (beta_1 L)^2 sqrt(EI / (mu L^4))."""


def shear_modulus(cable: CableDef) -> float:
    """Pa: the shear modulus G of a cable's torsion, its `twist_stiffness`, else
    MuJoCo's default E / (2 (1 + poisson)) = E / 2 (cablecheck sets no Poisson
    ratio; docs/twist.md)."""
    return cable.twist_stiffness if cable.twist_stiffness is not None else cable.young / 2.0


def first_bending_frequency(cable: CableDef, length: float) -> float:
    """omega_1 of the cable as a beam of its length clamped at both ends, rad/s.

    EI / mu = E (pi r^4 / 4) / (rho pi r^2) = E r^2 / (4 rho)."""
    return float(FIRST_BENDING_MODE ** 2 / length ** 2 * np.sqrt(cable.young * cable.radius ** 2 / (4.0 * cable.density)))


def first_mode(rest_s: np.ndarray, held, cable: CableDef) -> float:
    """omega_1 of the cable's own first bending mode as it is held, rad/s.

    The rod as MuJoCo has it: its vertices at arc lengths `rest_s` (a
    clamp's short held edge included), masses lumped per vertex (`rho pi
    r^2` times half the elements meeting there), bending energy `k phi^2`
    at each interior vertex (`k = EI / (l0 + l1)`, phi the turn there),
    with the vertices `held` (indices) fixed: a clamp holds two, a pin
    one, a free end none. The lowest non-zero mode of transverse motion
    (a free-free rod's first elastic mode, 4.730^2 / L^2 sqrt(EI / mu) as
    the element count grows; a cantilever's 1.875^2 / L^2 sqrt(EI / mu)).
    Gravity, tension and sag are left out: they are what this bending mode
    is measured against (docs/physics.md, Damping)."""
    rest_s = np.asarray(rest_s, float)
    n = len(rest_s)
    l = np.diff(rest_s)
    ei = cable.young * np.pi * cable.radius ** 4 / 4.0
    mu = cable.density * np.pi * cable.radius ** 2
    mass = mu * 0.5 * (np.concatenate([[0.0], l]) + np.concatenate([l, [0.0]]))
    k = np.zeros((n, n))
    for i in range(1, n - 1):
        g = np.zeros(n)
        g[i - 1], g[i], g[i + 1] = 1.0 / l[i - 1], -1.0 / l[i - 1] - 1.0 / l[i], 1.0 / l[i]
        k += 2.0 * ei / (l[i - 1] + l[i]) * np.outer(g, g)
    free = np.setdiff1d(np.arange(n), np.asarray(list(held), int))
    if len(free) == 0:
        return float("inf")
    a = k[np.ix_(free, free)] / np.sqrt(np.outer(mass[free], mass[free]))
    eig = np.linalg.eigvalsh(a)
    elastic = eig[eig > 1e-9 * max(float(eig.max()), 1e-300)]
    return float(np.sqrt(elastic.min())) if len(elastic) else float("inf")


def step_damping_ratio(omega: float, step: float, beta: float = 0.0) -> float:
    """Damping ratio of a mode of frequency `omega` under MuJoCo's `discrete`
    integrator at step `step`, with Rayleigh damping `beta` (seconds).

    The step is backward Euler in the stiffness and the damping (MuJoCo's
    effective inertia `M + h D + h^2 K`): with `c = beta omega^2` a mode's
    state is multiplied each step by the roots of
    `(1 + h c + h^2 omega^2) z^2 - (2 + h c) z + 1 = 0`, and its damping
    ratio is `-Re(s) / |s|` with `s = ln(z) / h` (what a logarithmic
    decrement measures). With no damping it is about `omega h / 2`: the
    integrator's own."""
    h, c = step, beta * omega ** 2
    a = 1.0 + h * c + (h * omega) ** 2
    disc = (h * c) ** 2 - 4.0 * (h * omega) ** 2
    if disc >= 0.0:
        return 1.0
    s = np.log(complex(2.0 + h * c, np.sqrt(-disc)) / (2.0 * a)) / h
    return float(-s.real / abs(s))


def rayleigh_damping(damping: float, omega: float, step: float) -> float:
    """MuJoCo's flex elasticity `damping` (Rayleigh, stiffness-proportional), seconds.

    MuJoCo damps a rod with the force -beta K v, K its bending (and
    torsion) stiffness; a mode of frequency omega then has the damping
    ratio beta omega / 2, and the integrator adds its own
    (`step_damping_ratio`). The cable's `damping` is the damping ratio of
    its first bending mode as held (`first_mode`), integrator included:
    beta is the one at which `step_damping_ratio(omega, step, beta)` is
    `damping` (beta = 2 damping / omega as the step goes to 0). Where the
    integrator alone damps that mode as much, beta is 0 (the step's need,
    `damping_step`, keeps that from happening). Higher bending modes are
    damped in proportion to their frequency, and what gravity or tension
    alone restores (a hanging chain's swing) is not damped at all: there
    is no air drag."""
    from scipy.optimize import brentq  # where it runs: start-up leaves scipy.optimize out
    if damping <= 0.0 or not np.isfinite(omega):
        return 0.0
    if step_damping_ratio(omega, step) >= damping:
        return 0.0
    hi = 2.0 * damping / omega
    while step_damping_ratio(omega, step, hi) < damping:
        hi *= 2.0
    return float(brentq(lambda b: step_damping_ratio(omega, step, b) - damping, 0.0, hi, xtol=1e-14 * hi,
                        rtol=1e-12))


DAMPING_SHARE = 1.0
"""Largest share of a cable's declared damping that the integrator's own
may supply (see `damping_step`); `rayleigh_damping` supplies the rest.
All of it may: for modes with omega h << 1 backward Euler damps like
Rayleigh damping of beta = h (ratio omega h / 2, in proportion to the
frequency), so the two are interchangeable and the realised ratio follows
the real mode's frequency the same way whichever supplies it."""


def damping_step(damping: float, omega: float) -> float:
    """Largest step at which the integrator's own damping of the first bending
    mode (`step_damping_ratio` without beta, about omega h / 2) is at most
    `DAMPING_SHARE` of the declared `damping`, seconds (inf for none)."""
    if damping <= 0.0 or not np.isfinite(omega):
        return float("inf")
    from scipy.optimize import brentq  # 0.2 s more start-up: only for a cable with damping
    target = DAMPING_SHARE * damping
    hi = 10.0      # the integrator's own ratio rises towards 1 as omega h grows (0.84 at 10)
    while step_damping_ratio(1.0, hi) < target:
        if hi > 1e12:      # a ratio the integrator never reaches alone (the loader keeps `damping` below 1)
            return float("inf")
        hi *= 10.0
    x = brentq(lambda x: step_damping_ratio(1.0, x) - target, 1e-12, hi, xtol=1e-15, rtol=1e-12)
    return float(x / omega)


CONTACT_SOLIMP = (0.99, 0.999, 0.001, 0.5, 2.0)
"""solimp of the cables' contacts: d from 0.99 at first touch to 0.999 at a
penetration of 1 mm. MuJoCo's default (0.9 to 0.95) lets 5 to 10 % of the
approach speed through each step."""


def contact_time_constant(step: float) -> float:
    """solref time constant of the cables' contacts for simulation step `step`, seconds.

    Two steps: with b = 2 / tc a contact removes the approach speed within
    one step, so a part moving at v into a cable penetrates it by about
    v h before pushing it along. The cables' contacts take priority over
    the parts' (`priority`), whose MuJoCo default (0.02 s) would otherwise
    be averaged in: with 4 ms averaged with it, a 10 mm plate lifted at
    2 m/s into a sagging cable went through it."""
    return 2.0 * step


EDGE_IMPEDANCE = 0.9999
"""solimp d of the edge-length equality at small strain: MuJoCo's largest
(`mjMAXIMP`). A soft constraint's regularisation is (1 - d) / d of the
constraint's inertia, so the edge's axial stiffness is the edge mass times
d / ((1 - d) tc^2): ten times stiffer than with 0.999."""


def edge_time_constant(step: float) -> float:
    """solref time constant of the edge-length equality for simulation step `step`, seconds.

    Two steps. (Under MuJoCo 4's `discrete` integrator an equality row's
    spring is evaluated at the end of the step and is stable at any time
    constant, refsafe clamping only contacts and limits: a smaller one
    makes the edges give less under load, as (tc + h)^2, at most 9 times
    less, `compression_strain`; not taken, as it changes every edge's axial
    response: docs/physics.md, Length in compression.) With d = `EDGE_IMPEDANCE` the
    damping b = 2 / tc removes a velocity error along an edge within one
    step. It must follow the step: a floor of 2 ms (the former setting) kept
    the edges as soft at a 0.25 ms step as at 1 ms, and a cable whose end
    moves 0.12 m at 20 Hz stretched 2.4 % instead of 0.5 %."""
    return 2.0 * step


EDGE_YIELD = 0.995
"""solimp d of the edge-length equality beyond 4 % edge strain (see
`edge_solimp`). Measured with ends pulled 10 % past a 1 m cable's length:
yielding to 0.95 (500 times softer than `EDGE_IMPEDANCE`) gathered the
whole stretch in one edge (198 %); 0.995 spreads it (edges below 60 %) and
the cable still comes to rest."""


def edge_solimp(plan: CablePlan) -> str:
    """Impedance of the edge-length equality: stiff at small strain, yielding beyond a few %.

    d sets the length accuracy (see `EDGE_IMPEDANCE`). But the tension of a
    taut edge acts on the transverse (string) motion explicitly, which goes
    unstable once strain * d / (1 - d) exceeds a constant: with a stiff
    edge at every strain, a cable whose ends are pulled 10 % past its length
    vibrated chaotically (edges at 50 % strain, never settling;
    tests/test_stability.py). So d falls to `EDGE_YIELD` between 0 and 4 %
    edge strain (power 6: flat near 0, still 0.9998 at 1 %), bounding the tension
    of an overstretched cable: it then rests at the strain its ends force,
    reported as taut. Strains that loads and motion cause are kept far below
    the yield by the step (`choose_substeps`), not by the yield. MuJoCo's
    width is a length, hence per cable (the regular element's length)."""
    seg = np.linalg.norm(np.diff(plan.straight, axis=0), axis=1)
    return f"{EDGE_IMPEDANCE!r} {EDGE_YIELD!r} {0.04 * float(seg.max())!r} 0.5 6"


COMPRESSION_TOLERANCE = 1e-3
"""Largest shortening of a cable, as a fraction of its length, that the
model holds to (0.1 %): the edge equality gives under compression
(`compression_strain`), the step is divided to keep that within
`COMPRESSION_SHARE` of this under the cable's buckling load
(`compression_step`), and a run warns where a cable is shorter by more
(`cablecheck.run.runner`, the report's `physics_warnings`)."""

BEND_RESOLUTION = 3.0
"""Fewest regular elements a bend radius must span for the simulated rod to
resolve it. A tighter bend (a hose turned sharply where it leaves a clamp or
clip) is averaged over its elements and read larger than it is: a 7 mm
hose leaving an arm's clip, 0.84 m long, read 24.3, 16.0, 13.4 and 12.4 mm
with 34, 68, 136 and 272 segments (a radius of 1.0, 1.3, 2.2 and 4.0
elements); a hairpin of a 2 mm cable 0.12 m long, 19.1, 15.75 and 15.73 mm
with 6, 60 and 120 (docs/physics.md, Bends the elements cannot resolve).
A run warns where a cable with a bend limit came below this many elements
and below `BEND_READ_FACTOR` times its limit (`cablecheck.run.runner`, the
report's `physics_warnings`)."""

BEND_READ_FACTOR = 2.5
"""How much larger than the bend a reading under `BEND_RESOLUTION` elements
may be, at most, rounded up from what was measured: 2.1 times (26.4 mm at
0.9 elements against 12.4 mm settled, the UR5e hose above). A reading
farther than this above its cable's limit cannot hide a bend past it, and
is not warned of."""

COMPRESSION_SHARE = 0.5
"""Share of `COMPRESSION_TOLERANCE` that the edges may give under the
cable's buckling load (`compression_step`): the rest is left for loads
above it (a bowed elastica's end force rises above the Euler load as it
bows further: 1.0 at the onset, 1.2 at 10 % shortening)."""


def buckling_load(rest_s, held, cable: CableDef) -> float:
    """The largest compression the cable can carry straight, N: the largest
    Euler load of its runs (past it a rod buckles and its end force stays
    near it). A run between two held vertices with a free vertex between
    them, of length a, as a rod clamped at both ends, `4 pi^2 EI / a^2` (a
    clamp's is the largest of the holds; pinned pi^2); a run from a held
    vertex to a free end, pushed at that end, as a cantilever, `pi^2 EI /
    (4 a^2)`; a cable held nowhere, pushed at both ends, as pinned at both,
    `pi^2 EI / L^2`."""
    rest_s = np.asarray(rest_s, float)
    held = sorted(set(int(h) for h in held))
    ei = cable.young * np.pi * cable.radius ** 4 / 4.0
    if not held:
        return float(np.pi ** 2 * ei / (rest_s[-1] - rest_s[0]) ** 2)
    loads = [4.0 * np.pi ** 2 * ei / (rest_s[b] - rest_s[a]) ** 2 for a, b in zip(held, held[1:]) if b - a >= 2]
    if held[0] > 0:                       # a free start
        loads.append(np.pi ** 2 * ei / (4.0 * (rest_s[held[0]] - rest_s[0]) ** 2))
    if held[-1] < len(rest_s) - 1:        # a free end
        loads.append(np.pi ** 2 * ei / (4.0 * (rest_s[-1] - rest_s[held[-1]]) ** 2))
    return float(max(loads)) if loads else 0.0


def compression_strain(load: float, element: float, cable: CableDef, step: float) -> float:
    """An edge's strain under an axial `load` (N), edge length `element`, at
    simulation step `step`: `(1 - d) (tc + h)^2 F / (mu l^2)`.

    MuJoCo's soft constraint rests at a violation `a0 (1 - d) tc^2`
    (modeling chapter, solver parameters; a0 the acceleration the load
    gives in constraint space, here F over one vertex's mass mu l). Under
    the `discrete` integrator the row's spring is evaluated at the end of
    the step, which adds one step to the time constant: measured on a rod
    bowed between clamps (0.5 m, r 3 mm, 2 GPa, 20.3 N) at 10, 20 and 40
    elements and tc from 0.01 h to 2 h, within 2 % of this (docs/physics.md,
    Length in compression). It grows with (elements x step)^2."""
    mu = cable.density * np.pi * cable.radius ** 2
    tc = edge_time_constant(step)
    return float((1.0 - EDGE_IMPEDANCE) * (tc + step) ** 2 * load / (mu * element ** 2))


def compression_step(load: float, element: float, cable: CableDef) -> float:
    """Largest step at which `compression_strain` under `load` is at most
    `COMPRESSION_SHARE` of `COMPRESSION_TOLERANCE`, seconds (inf without load)."""
    if load <= 0.0:
        return float("inf")
    unit = compression_strain(load, element, cable, 1.0)   # strain per step^2 (tc + h = 3 h)
    return float(np.sqrt(COMPRESSION_SHARE * COMPRESSION_TOLERANCE / unit))
