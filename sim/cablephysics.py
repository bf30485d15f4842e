"""A cable's material as MuJoCo's parameters: damping, time constants, impedances.

The rod's Rayleigh damping from the cable's damping ratio at its first
bending mode; the solref time constants of the edge-length equality and of
the cables' contacts, which follow the simulation step; the impedance of
the edge equality, stiff at small strain and yielding beyond a few percent.
docs/physics.md explains the model and its numbers.

This module is pure arithmetic on a cable's definition and a step: it does
not write the model (see `sim.mjspec`) nor choose the step (see `sim.substeps`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from sim.scene import CableDef

if TYPE_CHECKING:
    from sim.cableplan import CablePlan


FIRST_BENDING_MODE = 4.7300407448627040
"""beta_1 L of a beam's first bending mode with both ends clamped (or both
free): cos(bL) cosh(bL) = 1, omega_1 = (beta_1 L)^2 sqrt(EI / (mu L^4))."""


def first_bending_frequency(cable: CableDef, length: float) -> float:
    """omega_1 of the cable as a beam of its length clamped at both ends, rad/s.

    EI / mu = E (pi r^4 / 4) / (rho pi r^2) = E r^2 / (4 rho)."""
    return float(FIRST_BENDING_MODE ** 2 / length ** 2 * np.sqrt(cable.young * cable.radius ** 2 / (4.0 * cable.density)))


def rayleigh_damping(cable: CableDef, length: float) -> float:
    """MuJoCo's flex elasticity `damping` (Rayleigh, stiffness-proportional), seconds.

    MuJoCo damps a rod with the force -beta K v, K its bending (and
    torsion) stiffness; a mode of frequency omega then has the damping ratio
    zeta = beta omega / 2. The cable's `damping` is zeta at its first
    bending mode (`first_bending_frequency`), so beta = 2 zeta / omega_1;
    higher bending modes are damped in proportion to their frequency, and
    what gravity or tension alone restores (a hanging chain's swing) is not
    damped at all: there is no air drag."""
    return float(2.0 * cable.damping / first_bending_frequency(cable, length))


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

    Two steps, the stiffest that MuJoCo's discrete-time constraint resolves
    stably (its default safety clamp). With d = `EDGE_IMPEDANCE` the
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
