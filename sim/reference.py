"""Analytic references for the cable model: catenary sag and cantilever deflection.

Shared by the physics tests (tests/test_physics.py) and `cablecheck bench`
(physics resolution table), so both measure against one implementation:

- `catenary_sag(span, length)`: sag of a uniform, perfectly limp chain of
  `length` hung between two points `span` apart at one height,
  a (cosh(D / 2a) - 1) with 2 a sinh(D / 2a) = L.
- `cantilever_tip(length, radius, density, young)`: small-deflection tip
  deflection of a clamped round rod under its own weight, w L^4 / (8 E I) with
  I = pi r^4 / 4 and w = rho g pi r^2.
- `catenary_scene` / `cantilever_scene`: the one-cable scenes both are
  measured on, parsed by the real scene parser.
- `free_end(built)`: switches off the connect equalities that hold each
  cable's end to its body (the scene format has no free end), turning the
  builder's own model into a cantilever.

This module does not step or measure anything; callers build, settle and
compare (see `sim.bench.physics_table`).
"""

from __future__ import annotations

from pathlib import Path

import mujoco
import numpy as np
from scipy.optimize import brentq

from sim.scene import Scene, parse_scene

G = 9.81
"""Gravity used by the references, m/s^2 (MuJoCo's default magnitude)."""

CATENARY = dict(span=0.8, length=1.0, height=1.0, radius=0.004, elements=40)
"""The limp cable of the catenary reference (metres; young 1 Pa, density 1500)."""

CANTILEVER = dict(length=0.2, radius=0.004, density=1500.0, young=4e8, height=1.0)
"""The clamped rod of the cantilever reference (metres, kg/m^3, Pa)."""


def catenary_sag(span: float, length: float) -> float:
    """Sag of a uniform chain of `length` hung between two points `span` apart at one height."""
    a = brentq(lambda a: 2.0 * a * np.sinh(span / (2.0 * a)) - length, 1e-3 * span, 1e3 * span)
    return float(a * (np.cosh(span / (2.0 * a)) - 1.0))


def cantilever_tip(length: float, radius: float, density: float, young: float, g: float = G) -> float:
    """Tip deflection w L^4 / (8 E I) of a clamped round rod under its own weight."""
    w = density * g * np.pi * radius ** 2
    inertia = np.pi * radius ** 4 / 4.0
    return float(w * length ** 4 / (8.0 * young * inertia))


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


def cantilever_scene(elements: int, timestep: float = 0.002, settle: float = 1.0) -> Scene:
    """The rod of `CANTILEVER`, routed straight; build it and call `free_end` for the cantilever."""
    p = CANTILEVER
    return one_cable_scene(f"cantilever{elements}", {
        "name": "rod", "radius": p["radius"], "start": {"body": "world", "pos": [0, 0, p["height"]]},
        "end": {"body": "world", "pos": [p["length"], 0, p["height"]]},
        "segments": elements, "young": p["young"], "density": p["density"]},
        settle=settle, timestep=timestep)


def free_end(built) -> None:
    """Switch off the connect equalities that hold each cable's end vertices to their body."""
    m = built.model
    for c in built.cables:
        ends = {int(m.flex_vertbodyid[c.vert_adr + a.vertex])
                for a in c.attachments if a.kind == "end"}
        if not ends:
            raise ValueError(f"cable {c.name!r}: the builder holds every cable end; "
                             "expected end attachments")
        for i in range(m.neq):
            if m.eq_type[i] != mujoco.mjtEq.mjEQ_CONNECT:
                continue
            bodies = set()
            for obj, oid in ((m.eq_objtype[i], m.eq_obj1id[i]), (m.eq_objtype[i], m.eq_obj2id[i])):
                if obj == mujoco.mjtObj.mjOBJ_SITE:
                    bodies.add(int(m.site_bodyid[oid]))
                elif obj == mujoco.mjtObj.mjOBJ_BODY:
                    bodies.add(int(oid))
            if bodies & ends:
                m.eq_active0[i] = 0
