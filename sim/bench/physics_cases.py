"""Physics validation cases: the cable model run against closed-form answers.

Each case builds a one-cable scene with the real parser and builder, runs
it through the real step loop and returns a frozen record of what it
measured, the reference value and the cost (wall time per simulated
second). tests/test_physics.py asserts on them; benchmarks/
physics_validation.py tabulates them per element count (docs/physics.md).

- `catenary`: a limp cable between two points at one height; sag against
  `cablecheck.bench.reference.catenary_sag`.
- `cantilever`: a rod clamped at one end, the other free; tip deflection
  against w L^4 / 8EI (small) or the elastica (large, `reference.ELASTICA`).
- `chain`: a limp chain hanging from a clamp, started in its first mode;
  period against 2 pi / (1.2024 sqrt(g / L)) and the amplitude left after
  one period.
- `u_swing`: a cable hanging in a U between two clamps, pushed sideways;
  its swing's frequency and damping ratio (logarithmic decrement).
- `ring_down`: a cantilever started in its first bending mode, in the
  plane it sags in under gravity or across it; the mode's damping ratio
  (logarithmic decrement) against the cable's `damping`.
- `fast_ends`: one end moved 0.1 L back and forth at a frequency; largest
  |strain| of the cable and of any element.
- `bowed_rod`: a 200 GPa, 3 mm steel rod of 0.6 m clamped between ends
  0.5 m apart; its length change.
- `bowed`: a rod clamped between ends closer than its length, gravity
  off (buckled by its ends); its least strain over the run, end force and
  mid deflection against the clamped elastica.
- `straight_buckling`: a perfectly straight rod whose end is pushed in past
  its buckling load, gravity off; whether and how it buckles (mid
  deflection and end force against the clamped elastica, least strain).
- `twisted_buckling`: `straight_buckling`'s rod, buckled, then one clamped end
  turned about the chord; how far the bow winds out of its plane (the angle
  about the chord between its deflections at a quarter and three quarters of
  its length), its twist read from the simulated rod.
- `twisted_hose`: a slack hose clamped level at both ends, settled under
  gravity, then one end turned about the chord; how far it whirls about the
  chord (the same angle), its twist read from the simulated rod.
- `plate`: a plate lifted through a sagging cable; whether it carries it.
- `resting`: a cable laid on a floor or over a drum under gravity; its settled
  gap to the surface as a fraction of its radius.

It deliberately holds no thresholds: deciding what passes is the tests'
business.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path

import mujoco
import numpy as np

from cablecheck.bench import reference
from cablecheck.build.built import vertex_body
from cablecheck.build.rodtwist import TwistReader
from cablecheck.build.stages import build, cable_damping
from cablecheck.run.loop import Simulation
from cablecheck.scene.load import parse_scene


@dataclass(frozen=True)
class Result:
    """One measurement.

    Attributes:
      case: the case's name.
      elements: the cable's (regular) elements.
      measured, reference: the quantity and its closed-form answer (None
        where there is none).
      error: measured / reference - 1 (None without a reference).
      wall_per_sim_s: wall seconds per simulated second (mj_step and the loop).
      substeps: simulation steps per scene step.
      extra: further numbers, by name.
      warnings: MuJoCo warnings, by name.
    """

    case: str
    elements: int
    measured: float
    reference: float | None
    error: float | None
    wall_per_sim_s: float
    substeps: int
    extra: dict
    warnings: dict


def _scene(data: dict) -> object:
    return parse_scene(data, Path(f"/virtual/{data['scene']['name']}.toml"))


def settled(scene):
    """Built, settled simulation, its rest state and wall time per settled second."""
    built = build(scene, detect=False)
    sim = Simulation(built)
    sim.reset()
    t0 = time.perf_counter()
    sim.settle()
    wall = time.perf_counter() - t0
    state = next(sim.steps(contacts=False))
    return built, sim, state, wall / max(scene.settle, 1e-12)


def _result(case, elements, measured, ref, wall, built, sim, **extra) -> Result:
    error = None if ref is None else measured / ref - 1.0
    return Result(case, elements, float(measured), None if ref is None else float(ref), error, float(wall),
                  built.substeps.count, extra, sim.warnings())


def catenary(elements: int = 40) -> Result:
    p = reference.CATENARY
    built, sim, state, wall = settled(reference.catenary_scene(elements, settle=3.0))
    pts = state.cables[0]
    sag = p["height"] - pts[:, 2].min()
    strain = float(np.linalg.norm(np.diff(pts, axis=0), axis=1).sum() / built.cables[0].length - 1.0)
    return _result("catenary sag", built.cables[0].elements, sag, reference.catenary_sag(p["span"], p["length"]), wall,
                   built, sim, strain=strain)


def cantilever(elements: int | None = 40, large: bool = False) -> Result:
    """`elements` None: the builder's default count."""
    p = reference.ELASTICA if large else reference.CANTILEVER
    built, sim, state, wall = settled(reference.cantilever_scene(elements, settle=1.5 if large else 1.0, rod=p))
    tip = p["height"] - state.cables[0][-1, 2]
    if large:
        w = p["density"] * reference.G * np.pi * p["radius"] ** 2
        ref = reference.elastica_tip(p["length"], w, p["young"] * np.pi * p["radius"] ** 4 / 4.0)
    else:
        ref = reference.cantilever_tip(p["length"], p["radius"], p["density"], p["young"])
    return _result("elastica tip" if large else "cantilever tip", built.cables[0].elements, tip, ref, wall,
                   built, sim)


def _start_in_shape(sim: Simulation, offsets: np.ndarray, axis: int) -> None:
    """Displace the free vertices of the first cable by `offsets` (count,) along world `axis`."""
    m, d = sim.model, sim.data
    c = sim.built.cables[0]
    for v in range(c.count):
        bid = int(m.flex_vertbodyid[c.vert_adr + v])
        if m.body(bid).name != vertex_body(c.name, v):
            continue  # held by its body
        d.qpos[m.jnt_qposadr[m.body_jntadr[bid]] + axis] += offsets[v]
    mujoco.mj_forward(m, d)


def _crossings(t: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Times where x crosses zero downwards, linearly interpolated."""
    k = np.flatnonzero((x[:-1] > 0.0) & (x[1:] <= 0.0))
    return t[k] + x[k] / (x[k] - x[k + 1]) * (t[k + 1] - t[k])


def chain(elements: int = 40, periods: float = 2.5) -> Result:
    """Hanging chain started in its first mode (J0 shape, amplitude at the free end)."""
    p = reference.CHAIN
    period = reference.chain_period(p["length"])
    scene = reference.chain_scene(elements, duration=periods * period)
    built = build(scene, detect=False)
    sim = Simulation(built)
    sim.reset()
    c = built.cables[0]
    _start_in_shape(sim, p["amplitude"] * reference.chain_mode(p["length"] - c.rest_s, p["length"]), 0)
    t0 = time.perf_counter()
    t, x = [], []
    for state in sim.steps(contacts=False):
        t.append(state.t)
        x.append(state.cables[0][-1, 0])
    wall = (time.perf_counter() - t0) / scene.duration
    t, x = np.array(t), np.array(x)
    measured = float(np.mean(np.diff(_crossings(t, x))))
    one = t <= period
    after = (t > period) & (t <= 2.0 * period)
    left = float(np.abs(x[after]).max() / np.abs(x[one]).max())
    return _result("chain period", elements, measured, period, wall, built, sim, amplitude_left=left)


def u_swing(elements: int = 40, damping: float | None = None, duration: float = 4.0) -> Result:
    """A 1 m cable (defaults) hanging in a U between clamps 0.2 m apart, pushed
    sideways: frequency (Hz, measured) and damping ratio (extra) of its swing."""
    cable = {"name": "u", "radius": 0.004, "start": {"pos": [0, 0, 1]}, "end": {"pos": [0.2, 0, 1]},
             "via": [[0.1, 0, 0.6]], "length": 1.0, "segments": elements}
    if damping is not None:
        cable["damping"] = damping
    scene = _scene({"scene": {"name": "uswing", "units": "m", "duration": duration, "settle": 2.0,
                              "timestep": 0.002}, "cables": [cable]})
    built, sim, state, _ = settled(scene)
    c = built.cables[0]
    _start_in_shape(sim, 0.02 * np.sin(np.pi * c.rest_s / c.length), 1)
    low = int(np.argmin(state.cables[0][:, 2]))
    t0 = time.perf_counter()
    t, y = [], []
    for s in sim.steps(contacts=False):
        t.append(s.t)
        y.append(s.cables[0][low, 1])
    wall = (time.perf_counter() - t0) / duration
    t, y = np.array(t), np.array(y)
    peaks = [i for i in range(1, len(y) - 1) if y[i] > y[i - 1] and y[i] >= y[i + 1] and y[i] > 0]
    amps = y[peaks]
    zeta = float("nan")
    if len(amps) >= 2:
        delta = np.log(amps[0] / amps[-1]) / (len(amps) - 1)
        zeta = float(delta / np.sqrt(4 * np.pi ** 2 + delta ** 2))
    freq = float(1.0 / np.mean(np.diff(_crossings(t, y))))
    return _result("U swing", elements, freq, None, wall, built, sim, damping_ratio=zeta,
                   damping_set=scene.cables[0].damping)


CANTILEVER_MODE = 1.8751040687119611
"""beta_1 L of a cantilever's first bending mode: cos(bL) cosh(bL) = -1."""


def cantilever_mode(x) -> np.ndarray:
    """A cantilever's first bending mode at x = s / L (0 at the clamp), 1 at the free end."""
    b = CANTILEVER_MODE
    sigma = (np.cosh(b) + np.cos(b)) / (np.sinh(b) + np.sin(b))

    def phi(x):
        return np.cosh(b * x) - np.cos(b * x) - sigma * (np.sinh(b * x) - np.sin(b * x))

    return phi(np.asarray(x, float)) / phi(1.0)


def decrement(t: np.ndarray, x: np.ndarray, cycles: int = 8) -> tuple[float, float]:
    """Damping ratio and frequency (rad/s) of a decaying oscillation about 0:
    the logarithmic decrement of its positive peaks (each placed by a parabola
    through the sample and its neighbours), fitted over the first `cycles`."""
    k = np.flatnonzero((x[1:-1] > x[:-2]) & (x[1:-1] >= x[2:]) & (x[1:-1] > 0.0)) + 1
    k = k[:cycles + 1]
    y0, y1, y2 = x[k - 1], x[k], x[k + 1]
    den = y0 - 2.0 * y1 + y2
    off = np.where(den != 0.0, 0.5 * (y0 - y2) / np.where(den != 0.0, den, 1.0), 0.0)
    amp = y1 - 0.25 * (y0 - y2) * off
    tp = t[k] + off * (t[k + 1] - t[k])
    if len(amp) < 3:
        return float("nan"), float("nan")
    delta = -np.polyfit(np.arange(len(amp)), np.log(amp), 1)[0]
    period = float(np.polyfit(np.arange(len(tp)), tp, 1)[0])
    return float(delta / np.sqrt(4.0 * np.pi ** 2 + delta ** 2)), float(2.0 * np.pi / period)


def ring_down(elements: int, damping: float = 0.02, gravity: bool = True, across: bool = False,
              cycles: int = 8, amplitude: float = 0.01, settle: float = 1.0) -> Result:
    """The 0.2 m cantilever of `reference.CANTILEVER` (r 4 mm, 400 MPa, first
    mode 90.8 rad/s) settled, then displaced in its first bending mode by
    `amplitude` of its length at the tip, in the plane it sags in (z) or
    `across` it (y), and let go: the damping ratio of the tip's ringing
    (`decrement`, over `cycles`) against `damping` (no reference for 0);
    `settle` seconds of settling under gravity first. `extra`: its frequency (rad/s), the
    first mode as the builder computes it (`cablecheck.build.cablephysics.first_mode`)
    and MuJoCo's Rayleigh coefficient (s)."""
    p = reference.CANTILEVER
    omega = CANTILEVER_MODE ** 2 / p["length"] ** 2 * np.sqrt(p["young"] * p["radius"] ** 2 / (4.0 * p["density"]))
    duration = (cycles + 1.5) * 2.0 * np.pi / omega
    cable = {"name": "rod", "radius": p["radius"], "start": {"body": "world", "pos": [0, 0, p["height"]]},
             "end": {"pos": [p["length"], 0, p["height"]], "hold": "free"},
             "young": p["young"], "density": p["density"], "segments": elements, "damping": damping}
    data = {"scene": {"name": "ring", "units": "m", "duration": float(duration), "settle": settle if gravity else 0.0,
                      "timestep": 0.002}, "cables": [cable]}
    if not gravity:
        data["effects"] = {"gravity": False}
    scene = _scene(data)
    built, sim, state, _ = settled(scene)
    c = built.cables[0]
    axis = 1 if across else 2
    rest = state.cables[0][-1, axis]
    _start_in_shape(sim, amplitude * p["length"] * cantilever_mode(c.rest_s / c.length), axis)
    t0 = time.perf_counter()
    t, x = [], []
    for s in sim.steps(contacts=False):
        t.append(s.t)
        x.append(s.cables[0][-1, axis] - rest)
    wall = (time.perf_counter() - t0) / duration
    zeta, freq = decrement(np.array(t), np.array(x), cycles)
    mode = cable_damping(built)[c.flex_id][1]
    return _result("ring-down " + ("across the sag" if across else "in the sag plane" if gravity else "no gravity"),
                   elements, zeta, damping or None, wall, built, sim, omega=freq, first_mode=mode,
                   beta=float(built.model.flex_damping[c.flex_id]))


def fast_ends(frequency: float, elements: int | None = None, duration: float = 1.0) -> Result:
    """A 1.2 m cable between ends 1.0 m apart, one end moved 0.12 m (0.1 L) out
    and back at `frequency` (linear interpolation: the speed reverses at once,
    the hardest case; cubic keys would reverse it smoothly)."""
    keys = [{"t": k / (2 * frequency), "pos": [1.0 + (0.12 if k % 2 else 0.0), 0, 1]}
            for k in range(int(2 * frequency * duration) + 1)]
    cable = {"name": "c", "radius": 0.004, "start": {"pos": [0, 0, 1]}, "end": {"body": "b", "pos": [0, 0, 0]},
             "length": 1.2}
    if elements:
        cable["segments"] = elements
    scene = _scene({"scene": {"name": "fast", "units": "m", "duration": duration, "settle": 0.5,
                              "timestep": 0.002},
                    "bodies": [{"name": "b", "pos": [1.0, 0, 1]}],
                    "motion": [{"body": "b", "keys": keys, "interpolation": "linear"}],
                    "cables": [cable]})
    built, sim, state, _ = settled(scene)
    c = built.cables[0]
    rest = np.diff(c.rest_s)
    strain, edge = [], []
    t0 = time.perf_counter()
    for s in sim.steps(contacts=False):
        seg = np.linalg.norm(np.diff(s.cables[0], axis=0), axis=1)
        strain.append(seg.sum() / c.length - 1.0)
        e = seg / rest - 1.0
        edge.append(e[np.argmax(np.abs(e))])
    wall = (time.perf_counter() - t0) / duration
    strain, edge = np.array(strain), np.array(edge)
    worst = float(strain[np.argmax(np.abs(strain))])
    return _result(f"stretch {frequency:g} Hz", c.elements, worst, None, wall, built, sim, edge=float(edge[np.argmax(np.abs(edge))]),
                   stretch=float(strain.max()))


def bowed_rod(elements: int | None = None) -> Result:
    """A 200 GPa steel rod, r 3 mm, 0.6 m long, clamped between ends 0.5 m apart."""
    cable = {"name": "rod", "radius": 0.003, "start": {"pos": [0, 0, 1]}, "end": {"pos": [0.5, 0, 1]},
             "length": 0.6, "young": 2e11, "density": 7850}
    if elements:
        cable["segments"] = elements
    scene = _scene({"scene": {"name": "rod", "units": "m", "duration": 0.5, "settle": 1.0, "timestep": 0.002},
                    "cables": [cable]})
    built, sim, state, _ = settled(scene)
    c = built.cables[0]
    strains = []
    t0 = time.perf_counter()
    for s in sim.steps(contacts=False):
        strains.append(np.linalg.norm(np.diff(s.cables[0], axis=0), axis=1).sum() / c.length - 1.0)
    wall = (time.perf_counter() - t0) / scene.duration
    strains = np.array(strains)
    return _result("bowed steel rod", c.elements, float(strains[np.argmax(np.abs(strains))]), None,
                   wall, built, sim)


ROD = dict(length=0.5, radius=0.003, density=1500.0, young=2e9)
"""The rod of `bowed` and `straight_buckling` (tests/test_tangent.py's):
EI = 0.127 N m^2, clamped Euler load 4 pi^2 EI / L^2 = 20.1 N."""

WIRE = dict(length=0.1, radius=0.0005, density=7850.0, young=2e11)
"""A 0.1 m steel wire of 1 mm diameter: clamped Euler load 38.8 N."""


def _strains(sim: Simulation, length: float, duration: float) -> tuple[list[float], object, float]:
    """Step `sim` to its end: its one cable's strain (length over `length`, less 1) at every step, the
    last state and the wall seconds a simulated second."""
    strains = []
    t0 = time.perf_counter()
    for s in sim.steps(contacts=False):
        strains.append(np.linalg.norm(np.diff(s.cables[0], axis=0), axis=1).sum() / length - 1.0)
    return strains, s, (time.perf_counter() - t0) / duration


def _middle_force(sim: Simulation) -> float:
    """Force of the middle edge's length equality, N (positive: compression).
    At a buckled rod's middle the edge runs along the chord: the end force."""
    d = sim.data
    edges = d.efc_force[d.efc_type == int(mujoco.mjtConstraint.mjCNSTR_EQUALITY)]
    return float(edges[len(edges) // 2])


def _deflection(pts: np.ndarray) -> tuple[float, np.ndarray]:
    """Largest distance of `pts` from the line through its ends, and the unit
    direction from that line to the farthest point."""
    axis = (pts[-1] - pts[0]) / np.linalg.norm(pts[-1] - pts[0])
    rel = pts - pts[0]
    off = rel - np.outer(rel @ axis, axis)
    k = int(np.argmax(np.linalg.norm(off, axis=1)))
    size = float(np.linalg.norm(off[k]))
    return size, off[k] / size if size > 0.0 else off[k]


def bowed(elements: int | None = None, shortening: float = 0.02, damping: float | None = None,
          rod: dict = ROD, duration: float = 0.2, settle: float = 3.0) -> Result:
    """A rod (`rod`) clamped at both ends `shortening` of its length closer
    than its length, gravity off, settled and then held for `duration`:
    measured its least strain over the checked steps (negative: shorter;
    the cable's total length over its rest length, as the run reports it),
    `extra` its end force and mid deflection with the clamped elastica's
    (`reference.clamped_elastica`). `elements` None: the default count."""
    cable = {"name": "rod", "radius": rod["radius"], "start": {"pos": [0, 0, 1]},
             "end": {"pos": [(1.0 - shortening) * rod["length"], 0, 1]}, "length": rod["length"],
             "young": rod["young"], "density": rod["density"]}
    if elements:
        cable["segments"] = elements
    if damping is not None:
        cable["damping"] = damping
    scene = _scene({"scene": {"name": "bowed", "units": "m", "duration": duration, "settle": settle,
                              "timestep": 0.002}, "effects": {"gravity": False}, "cables": [cable]})
    built, sim, state, _ = settled(scene)
    c = built.cables[0]
    strains, s, wall = _strains(sim, c.length, duration)
    ei = rod["young"] * np.pi * rod["radius"] ** 4 / 4.0
    force, deflection = reference.clamped_elastica(rod["length"], shortening, ei)
    return _result("compression strain", c.elements, float(min(strains)), None, wall, built, sim,
                   force=_middle_force(sim), force_ref=force, deflection=_deflection(s.cables[0])[0],
                   deflection_ref=deflection, damping=scene.cables[0].damping,
                   reason=built.substeps.reasons[c.name][0])


def straight_buckling(shortening: float, elements: int | None = None, push: float = 0.2, duration: float = 0.6,
                      rod: dict = ROD, gravity: bool = False) -> Result:
    """A perfectly straight rod (`rod`) clamped at both ends, its end pushed
    in by `shortening` of its length over `push` seconds (at constant speed)
    and held, gravity off: measured its mid deflection at the end against
    the clamped elastica's; `extra` its end force and the elastica's, its
    least strain over the run and at the end, and the direction it buckled
    to (from its chord). Without the route's imperfection (`cablecheck.build.cableplan.
    imperfect`) it would stay straight and shorten instead."""
    length = rod["length"]
    keys = [{"t": 0.0, "pos": [length, 0, 1]}, {"t": push, "pos": [(1.0 - shortening) * length, 0, 1]}]
    cable = {"name": "rod", "radius": rod["radius"], "start": {"pos": [0, 0, 1]},
             "end": {"body": "b", "pos": [0, 0, 0]}, "young": rod["young"], "density": rod["density"]}
    if elements:
        cable["segments"] = elements
    data = {"scene": {"name": "straight", "units": "m", "duration": duration, "settle": 0.0, "timestep": 0.002},
            "bodies": [{"name": "b", "pos": [length, 0, 1]}],
            "motion": [{"body": "b", "keys": keys, "interpolation": "linear"}], "cables": [cable]}
    if not gravity:
        data["effects"] = {"gravity": False}
    scene = _scene(data)
    built = build(scene, detect=False)
    sim = Simulation(built)
    sim.reset()
    c = built.cables[0]
    strains, s, wall = _strains(sim, c.length, duration)
    ei = rod["young"] * np.pi * rod["radius"] ** 4 / 4.0
    force, deflection = reference.clamped_elastica(length, shortening, ei)
    size, side = _deflection(s.cables[0])
    return _result(f"straight rod pushed {100 * shortening:g} %", c.elements, size, deflection, wall, built, sim,
                   force=_middle_force(sim), force_ref=force, least=float(min(strains)), final=float(strains[-1]),
                   side=tuple(float(x) for x in np.round(side, 3)))


def plate(speed: float, half_thickness: float = 0.005, timestep: float = 0.002, radius: float = 0.004) -> Result:
    """A 0.3 m square plate lifted at `speed` from below through the middle of
    a 1 m cable (of `radius`) sagging over 0.8 m; measured 1.0 when the cable
    ends above the plate's mid-plane all along it (carried), else 0.0."""
    z0, z1 = 0.55, 1.1
    duration = (z1 - z0) / speed
    scene = _scene({
        "scene": {"name": "plate", "units": "m", "duration": duration, "settle": 1.0, "timestep": timestep},
        "effects": {"contact": ["cable-structure"]},
        "bodies": [{"name": "lift", "pos": [0.4, 0, z0]}],
        "parts": [{"name": "plate", "body": "lift", "shape": "box", "size": [0.15, 0.15, half_thickness]}],
        "motion": [{"body": "lift", "interpolation": "linear",
                    "keys": [{"t": 0, "pos": [0.4, 0, z0]}, {"t": duration, "pos": [0.4, 0, z1]}]}],
        "cables": [{"name": "c", "radius": radius, "start": {"pos": [0, 0, 1]}, "end": {"pos": [0.8, 0, 1]},
                    "length": 1.0}]})
    built, sim, state, _ = settled(scene)
    t0 = time.perf_counter()
    for s in sim.steps(contacts=False):
        pass
    wall = (time.perf_counter() - t0) / duration
    pts = s.cables[0]
    over = np.abs(pts[:, 0] - 0.4) < 0.15
    carried = bool(pts[over, 2].min() > s.part_poses[0][2, 3])
    return _result(f"plate {speed:g} m/s", built.cables[0].elements, 1.0 if carried else 0.0, None, wall, built, sim,
                   warned=bool(built.warnings))


DRUM = 0.05
"""Radius of the drum of `resting`, metres."""


def resting(radius: float, units: str = "m", shape: str = "box", duration: float = 0.5,
            timestep: float = 0.002) -> Result:
    """A 0.2 m cable of `radius` (metres; free ends, 8 elements) dropped from
    a radius above onto a part, in a scene written in `units`, then left
    under gravity for `duration`: on a floor (`shape` "box", 0.1 m thick, or
    "plane"), lying straight; on a drum ("cylinder", radius `DRUM`, axis
    across the cable), draped over it and held by friction. Measured: the
    gap between the cable's surface and the part's, over the radius: on the
    floor from the body centres' heights (mean; `extra` the least and
    largest), on the drum from each element's nearest place to the axis, of
    the elements that lie on it (within a radius).
    0 is resting on the surface, negative inside it."""
    k = {"m": 1.0, "mm": 1000.0}[units]
    if shape == "cylinder":
        # the straight cable's middle a radius above the drum's top; the drum along y
        z0, part = DRUM + 2.0 * radius, {"name": "drum", "shape": "cylinder", "size": [DRUM * k, 0.05 * k],
                                         "euler": [90, 0, 0]}
    else:
        z0, part = 2.0 * radius, {"name": "floor", "shape": shape}
        if shape == "box":
            part.update(size=[0.3 * k, 0.3 * k, 0.05 * k], pos=[0, 0, -0.05 * k])
    pts = [[x * k, 0.0, z0 * k] for x in (-0.1, 0.0, 0.1)]
    scene = _scene({
        "scene": {"name": "resting", "units": units, "duration": duration, "settle": 0.0, "timestep": timestep},
        "effects": {"contact": ["cable-structure"]}, "parts": [part],
        "cables": [{"name": "c", "radius": radius * k, "points": pts, "segments": 8,
                    "start": {"hold": "free"}, "end": {"hold": "free"}}]})
    built = build(scene, detect=False)
    sim = Simulation(built)
    sim.reset()
    t0 = time.perf_counter()
    for s in sim.steps(contacts=False):
        pass
    wall = (time.perf_counter() - t0) / duration
    pts = s.cables[0]
    if shape == "cylinder":     # each element's nearest place to the drum's axis (y)
        a, d = pts[:-1][:, [0, 2]], np.diff(pts, axis=0)[:, [0, 2]]
        t = np.clip(-(a * d).sum(axis=1) / (d * d).sum(axis=1), 0.0, 1.0)
        gap = (np.linalg.norm(a + t[:, None] * d, axis=1) - DRUM - radius) / radius
        gap = gap[gap < 1.0]
    else:
        gap = (pts[:, 2] - radius) / radius
    return _result(f"resting on a {'drum' if shape == 'cylinder' else shape}", built.cables[0].elements,
                   float(gap.mean()), None, wall, built, sim, least=float(gap.min()), largest=float(gap.max()),
                   radius=radius, units=units, touching=int(len(gap)))


def _twisted_run(scene, every: int, settle: bool) -> tuple:
    """Built, its simulation, its states every `every` steps (settled first if `settle`), wall
    seconds per simulated second of the run (not the settling), and the first cable's twist at
    each state."""
    built = build(scene, detect=False)
    sim = Simulation(built)
    sim.reset()
    if settle:
        sim.settle()
    t0 = time.perf_counter()
    states = list(sim.steps(contacts=False, every=every))
    wall = (time.perf_counter() - t0) / scene.duration
    return built, sim, states, wall, _rod_twist(built, states)


def _rod_twist(built, states: list) -> np.ndarray:
    """The first cable's twist end to end (radians, the sum over its interior vertices as
    `cablecheck.build.rodtwist.TwistReader` reads it from the simulated rod) at each of `states`."""
    reader = TwistReader.of(built)
    twist = reader.read_many([s.rod for s in states], np.stack([np.concatenate(s.cables) for s in states]),
                             np.stack([s.qpos for s in states]))[0]
    return np.zeros(len(states)) if twist is None else twist.sum(axis=1)


def _about_chord(pts: np.ndarray, u: float) -> np.ndarray:
    """The offset from the chord (the line through the ends of `pts`) of the point at `u` of
    the polyline's length (0 start, 1 end; linearly between its points), square to the chord."""
    arc = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(pts, axis=0), axis=1))])
    p = np.array([np.interp(u * arc[-1], arc, pts[:, k]) for k in range(3)])
    axis = (pts[-1] - pts[0]) / np.linalg.norm(pts[-1] - pts[0])
    rel = p - pts[0]
    return rel - (rel @ axis) * axis


def _angle_about(axis: np.ndarray, a: np.ndarray, b: np.ndarray) -> float:
    """Signed angle from `a` to `b` about `axis` (right-handed), radians."""
    axis = axis / np.linalg.norm(axis)
    return float(np.arctan2(np.cross(a, b) @ axis, a @ b))


def twist_shape(pts: np.ndarray) -> dict:
    """What a twisted rod's shape shows about its chord (x of `pts`' ends): `mid` the mid-span
    offset from the chord (m) and `quarters` the angle (radians) about the chord from the offset
    at a quarter of the length to the one at three quarters (0 for a bow in one plane; the same
    whatever the whole shape's turn about the chord)."""
    axis = pts[-1] - pts[0]
    q1, q3 = _about_chord(pts, 0.25), _about_chord(pts, 0.75)
    return dict(mid=_about_chord(pts, 0.5), quarters=_angle_about(axis, q1, q3))


TWIST_TURN = 1.0
"""Seconds `twisted_buckling` turns its end over (three turns: 19 rad/s, well below the buckled rod's
first mode, about 150 rad/s; twice as fast or half changes its angles by well under a degree)."""


def twisted_buckling(turns: float = 3.0, shortening: float = 0.03, elements: int | None = None,
                     push: float = 0.2, hold: float = 0.4, turn: float = TWIST_TURN, settle: float = 0.4,
                     rod: dict = ROD, twist_stiffness: float | None = None, every: int = 5) -> Result:
    """`straight_buckling`'s rod (`rod`, gravity off) with its end pushed in `shortening` of its
    length over `push` s and held until `hold` s (bowed and still by then: the cable model has no
    imperfection to grow from, the route's bends it at once), then the end body turned `turns`
    full turns about the chord (the rod's axis, x) at constant rate over `turn` s, then held
    `settle` s (its shape no longer moves: the turn is slow enough to be quasi-static).
    `twist_stiffness` the rod's shear modulus G (Pa; None: the cable model's E / 2).

    Measured: the bow's out-of-plane angle, degrees: the angle about the chord from the
    deflection (offset from the chord) at a quarter of the length to the one at three quarters,
    at the end (0 in the buckling plane; `twist_shape`; unwrapped from sample to sample). The problem is the same turned about the
    chord (the clamps hold positions and the chord's direction, and a rigid turn of the whole
    shape about the chord changes neither bending nor twist), so how far the mid-span deflection
    turns from the buckling plane is not set by the statics, only by how the motion drifts along
    that free turn; it is in `extra` as `mid_angle` (degrees) but the quarters' angle is the
    shape's own. `extra`: mid-span deflection before the turns and at the end (m), the
    largest over the run of the quarters' angle, the rod's twist end to end (degrees, read
    from the simulated rod) and the writhe left of the ends' link (turns x 360 less the twist),
    the least strain over the run."""
    length = rod["length"]
    end = [(1.0 - shortening) * length, 0, 1]
    keys = [{"t": 0.0, "pos": [length, 0, 1], "euler": [0, 0, 0]}, {"t": push, "pos": end, "euler": [0, 0, 0]},
            {"t": hold, "pos": end, "euler": [0, 0, 0]},
            {"t": hold + turn, "pos": end, "euler": [360.0 * turns, 0, 0]}]
    cable = {"name": "rod", "radius": rod["radius"], "start": {"pos": [0, 0, 1]},
             "end": {"body": "b", "pos": [0, 0, 0]}, "young": rod["young"], "density": rod["density"]}
    if elements:
        cable["segments"] = elements
    if twist_stiffness is not None:
        cable["twist_stiffness"] = twist_stiffness
    duration = hold + turn + settle
    scene = _scene({"scene": {"name": "twisted", "units": "m", "duration": duration, "settle": 0.0,
                              "timestep": 0.002},
                    "effects": {"gravity": False}, "bodies": [{"name": "b", "pos": [length, 0, 1]}],
                    "motion": [{"body": "b", "keys": keys, "interpolation": "linear"}], "cables": [cable]})
    built, sim, states, wall, twist = _twisted_run(scene, every, settle=False)
    c = built.cables[0]
    before = max((s for s in states if s.t <= hold + 1e-9), key=lambda s: s.t)
    bow = twist_shape(before.cables[0])["mid"]
    shapes = [twist_shape(s.cables[0]) for s in states]
    last = shapes[-1]
    quarters = np.degrees(np.unwrap([sh["quarters"] for sh in shapes]))
    axis = states[-1].cables[0][-1] - states[-1].cables[0][0]
    strains = [np.linalg.norm(np.diff(s.cables[0], axis=0), axis=1).sum() / c.length - 1.0 for s in states]
    return _result(f"twisted buckled rod {turns:g} turns", c.elements, quarters[-1], None, wall,
                   built, sim, mid_angle=float(np.degrees(_angle_about(axis, bow, last["mid"]))),
                   largest=float(np.abs(quarters).max()),
                   deflection_before=float(np.linalg.norm(bow)), deflection=float(np.linalg.norm(last["mid"])),
                   twist=float(np.degrees(twist[-1])), writhe=float(360.0 * turns - np.degrees(twist[-1])),
                   least=float(min(strains)), final=float(strains[-1]), turn=turn, hold=hold, settle=settle)


HOSE = dict(length=0.5, radius=0.004)
"""The hose of `twisted_hose` (benchmarks/elastica_peer.py's): young, density and damping the
scene defaults."""

HOSE_TURN = 4.0
"""Seconds `twisted_hose` turns its end over (four turns: 6.3 rad/s; three times slower gives the same
end state, in PyElastica too)."""


def twisted_hose(turns: float = 4.0, slack: float = 0.2, elements: int | None = None, turn: float = HOSE_TURN,
                 hold: float = 3.0, settle: float = 3.0, hose: dict = HOSE, twist_stiffness: float | None = None,
                 approach: float | None = None, wait: float = 2.0, every: int = 5) -> Result:
    """A hose (`hose`; the scene's default modulus, density and damping) clamped level (tangent
    +x) at both ends, its span its length over 1 + `slack`, gravity on, settled `settle` s (the
    scene's settling: kinetic damping to the static sag), then its end body turned `turns` full
    turns about the chord (x) at constant rate over `turn` s and held `hold` s.
    `twist_stiffness` the hose's shear modulus G (Pa; None: the cable model's E / 2).
    `approach` (a slack, e.g. 0.03): the end instead starts at the span of that slack, is settled
    there, moved in to the span over 1 s at constant speed and held `wait` s before the turns
    (a diagnostic: at commit 6074e19 MuJoCo kept no twist state for a rod clamped at both ends
    and routed with more than a few % of slack along its chord, so its turned end wound nothing;
    one routed with less keeps its twist state as its ends close in; tests/test_twisted_rods.py).

    Measured: the hose's whirl about the chord at the end, degrees: the angle about the chord
    (right-handed about +x) from the sag (offset from the chord) at a quarter of the length to
    the one at three quarters (`twist_shape`; 0 while it hangs in one plane; unwrapped from sample
    to sample). `extra`: `whirl`,
    the angle of the mid-span sag from straight down at the end (degrees; a hose symmetric end
    for end can only hang (0) or stand (180) there: turning the whole problem half a turn about
    the vertical through the middle swaps its ends and leaves it the same, so the mid-span's
    sideways offset is 0 unless the symmetry breaks), the largest |whirl| over the run (unwrapped
    from sample to sample), the largest |quarters' angle|, the mid-span sag before the turns and
    at the end (m), the twist end to end read from the simulated rod and the writhe left of the
    link (degrees), the least strain, the first mode as the cable model holds it (rad/s,
    `cable_damping`) and the shape before the turns (`rest`, (count, 3) m)."""
    span = hose["length"] / (1.0 + slack)
    x0 = span if approach is None else hose["length"] / (1.0 + approach)
    t0 = 0.0 if approach is None else 1.0 + wait
    keys = [{"t": 0.0, "pos": [x0, 0, 1], "euler": [0, 0, 0]}]
    if approach is not None:
        keys += [{"t": 1.0, "pos": [span, 0, 1], "euler": [0, 0, 0]}, {"t": t0, "pos": [span, 0, 1], "euler": [0, 0, 0]}]
    keys.append({"t": t0 + turn, "pos": [span, 0, 1], "euler": [360.0 * turns, 0, 0]})
    cable = {"name": "hose", "radius": hose["radius"], "start": {"pos": [0, 0, 1], "tangent": [1, 0, 0]},
             "end": {"body": "b", "pos": [0, 0, 0], "tangent": [1, 0, 0]}, "length": hose["length"]}
    if elements:
        cable["segments"] = elements
    if twist_stiffness is not None:
        cable["twist_stiffness"] = twist_stiffness
    duration = t0 + turn + hold
    scene = _scene({"scene": {"name": "hose", "units": "m", "duration": duration, "settle": settle,
                              "timestep": 0.002},
                    "bodies": [{"name": "b", "pos": [x0, 0, 1]}],
                    "motion": [{"body": "b", "keys": keys, "interpolation": "linear"}], "cables": [cable]})
    built, sim, states, wall, twist = _twisted_run(scene, every, settle=True)
    c = built.cables[0]
    before = max((s for s in states if s.t <= t0 + 1e-9), key=lambda s: s.t)
    turning = [s for s in states if s.t >= t0 - 1e-9]
    down = np.array([0.0, 0.0, -1.0])
    shapes = [twist_shape(s.cables[0]) for s in turning]
    whirl = np.unwrap([_angle_about(s.cables[0][-1] - s.cables[0][0], down, sh["mid"])
                       for s, sh in zip(turning, shapes)])
    strains = [np.linalg.norm(np.diff(s.cables[0], axis=0), axis=1).sum() / c.length - 1.0 for s in states]
    quarters = np.degrees(np.unwrap([sh["quarters"] for sh in shapes]))
    return _result(f"twisted hose {turns:g} turns", c.elements, quarters[-1], None, wall,
                   built, sim, whirl=float(np.degrees(whirl[-1])), largest_whirl=float(np.degrees(np.abs(whirl).max())),
                   largest=float(np.abs(quarters).max()),
                   sag_before=float(np.linalg.norm(twist_shape(before.cables[0])["mid"])),
                   sag=float(np.linalg.norm(shapes[-1]["mid"])), twist=float(np.degrees(twist[-1])),
                   writhe=float(360.0 * turns - np.degrees(twist[-1])), least=float(min(strains)),
                   span=span, young=scene.cables[0].young, density=scene.cables[0].density,
                   damping=scene.cables[0].damping, turn=turn, hold=hold, settle=settle,
                   first_mode=cable_damping(built)[c.flex_id][1], rest=before.cables[0].copy())
