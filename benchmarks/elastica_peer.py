"""PyElastica (Cosserat rods) as a peer of the cable model: the shared problems run on both.

Imported by benchmarks/physics_validation.py (its peer table) and
tests/test_elastica_peer.py. PyElastica is optional (`pip install -e '.[peer]'`);
without it every peer value is "not installed" and the cable model's own
columns are still measured.

Cases, each the validation case of `cablecheck.bench.physics_cases` (or the
hose below) run as it is there, and the same rod built in PyElastica from
the same definition (geometry, material, gravity, duration, damping ratio):

- `frequency`: the 0.2 m cantilever of `reference.CANTILEVER`, gravity off,
  started in its first bending mode (1 % of its length at the tip) and let
  go (`physics_cases.ring_down`); its first frequency against
  beta_1^2 / L^2 sqrt(EI / rho A), and the damping ratio of both.
- `hose`: a polymer hose (`HOSE`; the scene's default modulus, density and
  damping) clamped level at one end, its other end free, released straight
  under gravity; the RMS distance between the two tips' paths over the run.
- `buckling`: the straight rod of `physics_cases.ROD` clamped at both ends,
  its end pushed in 3 % over 0.2 s and held (`physics_cases.straight_buckling`);
  mid deflection against the clamped elastica, end forces in the note.
- `catenary`: the limp cable of `reference.CATENARY` between two points
  (`physics_cases.catenary`); sag against the catenary.
- `twisted_buckling`: the buckled rod above, then its pushed end turned three
  turns about the chord (`physics_cases.twisted_buckling`); the angle about
  the chord between the bow's deflections at L/4 and 3L/4.
- `twisted_hose`: the hose (`HOSE`) clamped level at both ends 20 % slack,
  settled under gravity, then one end turned four turns about the chord
  (`physics_cases.twisted_hose`); the same angle of its sag.

Both twisted problems use PyElastica's shear modulus, G = E / 3 (its Poisson
ratio 0.5), for the twist in both models: the cable's `twist_stiffness` is
set to E / 3 (the cable model's own default is E / 2). A turned clamp in
PyElastica is a constraint of our own (`_turned_ends`) that turns the end
element's directors about the chord and sets its omega to match.

How PyElastica is set up: `CosseratRod.straight_rod` (Poisson ratio 0.5, its
default), `OneEndFixedBC` or `FixedConstraint` for clamps and pins (a
constraint of our own for the pushed end), `GravityForces`,
`AnalyticalLinearDamper` with a uniform constant 2 zeta omega_1 (the cable's
declared damping ratio `zeta` on the first bending mode as the cable model
holds it, `cablecheck.build.stages.cable_damping`), `PositionVerlet` at a
step below the rod's fastest axial and bending waves (`_step`). The cable
model is inextensible (edge equalities) and bends with `young`; a rod of
`young` 1 Pa (the limp catenary) would stretch several times over in
PyElastica, so there its stretch and shear take `STIFF` and only its bending
`young`. CPU seconds are process time of the whole case: the cable model's
build, settle and run; PyElastica's setup and run after a warm-up that
compiles its numba kernels (`warm_up`, timed apart).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from cablecheck.bench import physics_cases as cases
from cablecheck.bench import reference
from cablecheck.build.stages import build, cable_damping
from cablecheck.run.loop import Simulation
from cablecheck.scene.format import DEFAULT_YOUNG
from cablecheck.scene.load import parse_scene

try:
    import elastica as ea
except ImportError:  # the optional `peer` extra
    ea = None

NOT_INSTALLED = "not installed"
AVAILABLE = ea is not None

HOSE = dict(length=0.5, radius=0.004, height=1.0, duration=1.0)
"""The released hose (metres, seconds): young, density and damping are the scene defaults."""

STIFF = 1e8
"""Stretch and shear modulus (Pa) of the limp catenary in PyElastica (its 1 Pa `young` only bends it):
under its largest tension, about 0.5 N, it stretches 1e-4."""

ELEMENTS = dict(frequency=80, hose=80, buckling=80, catenary=80, twisted_buckling=80, twisted_hose=80)
"""PyElastica's elements per case. Its clamp holds the first element's directors, so a clamped rod
bends from about half an element in: its cantilever frequency comes out 5.1 / 2.4 / 1.2 % high at
20 / 40 / 80 elements, and its hose tip path 6.6 / 3.0 / 1.3 % of the length from the cable
model's (measured 2026-11-28); 80 keeps each case under about 40 s CPU. The cable model runs at
its cases' own counts (`CABLE_ELEMENTS`, the hose its default)."""

CABLE_ELEMENTS = dict(frequency=20, buckling=None, catenary=reference.CATENARY["elements"], twisted_buckling=None,
                      twisted_hose=None)
"""The cable model's elements: the ring-down rows' 20, the buckled rod's default (20), the catenary's 40,
the twisted rod's and hose's defaults (20)."""

CFL = 0.4
"""PyElastica's step as a fraction of the rod's fastest wave's (`_step`)."""


def version() -> str:
    if ea is None:
        return NOT_INSTALLED
    from importlib.metadata import version as v
    return v("pyelastica")


# ----------------------------------------------------------------------------- PyElastica side

def _system():
    class Rods(ea.BaseSystemCollection, ea.Constraints, ea.Forcing, ea.Damping):
        pass
    return Rods()


def _rod(n: int, length: float, radius: float, density: float, young: float, start=(0.0, 0.0, 1.0),
         direction=(1.0, 0.0, 0.0), normal=(0.0, 0.0, 1.0), stretch: float | None = None):
    """A straight CosseratRod bending with `young`, stretching and shearing with `stretch` (Pa, default
    `young`; the limp catenary's 1 Pa would let it stretch where the cable model holds its length)."""
    stretch = young if stretch is None else stretch
    rod = ea.CosseratRod.straight_rod(n, np.array(start, float), np.array(direction, float), np.array(normal, float),
                                      length, radius, density, youngs_modulus=stretch)
    if stretch != young:
        rod.bend_matrix[...] *= young / stretch
    return rod


def _step(n: int, length: float, radius: float, density: float, young: float, stretch: float | None = None) -> float:
    """A PositionVerlet step below the rod's fastest waves: axial (dx / c, c = sqrt(E / rho), E the
    stretch modulus), bending (2 / omega_max, omega_max = (pi / dx)^2 sqrt(E r^2 / 4 rho)) and an
    element turning against its shear (2 / omega, omega = 2 sqrt(G / rho) / r, G = E / 3 at
    PyElastica's Poisson ratio 0.5)."""
    stretch = young if stretch is None else stretch
    dx = length / n
    axial = dx / np.sqrt(stretch / density)
    bending = 2.0 / ((np.pi / dx) ** 2 * np.sqrt(young * radius ** 2 / (4.0 * density)))
    shear = radius / np.sqrt(stretch / 3.0 / density)
    return CFL * min(axial, bending, shear)


def _shape(rod, pts: np.ndarray) -> None:
    """Put the rod's nodes at `pts` (n + 1, 3) and turn each element's directors to its edge
    (d3 along it, d1 the rod's normal made square to it): a bent start without shear strain."""
    rod.position_collection[...] = pts.T
    for k in range(pts.shape[0] - 1):
        t = pts[k + 1] - pts[k]
        t /= np.linalg.norm(t)
        d1 = rod.director_collection[0, :, k]
        d1 = d1 - (d1 @ t) * t
        d1 /= np.linalg.norm(d1)
        rod.director_collection[:, :, k] = np.array([d1, np.cross(t, d1), t])


def _damp(system, rod, zeta: float, omega: float, dt: float) -> None:
    if zeta > 0.0:
        system.dampen(rod).using(ea.AnalyticalLinearDamper, uniform_damping_constant=2.0 * zeta * omega,
                                 time_step=dt)


def _run(system, dt: float, duration: float, every: int, sample) -> None:
    """PositionVerlet over `duration`, calling `sample(t)` at the start and every `every` steps."""
    stepper = ea.PositionVerlet()
    steps = int(round(duration / dt))
    t = np.float64(0.0)
    sample(float(t))
    for i in range(1, steps + 1):
        t = stepper.step(system, t, dt)
        if i % every == 0:
            sample(float(t))


def _clamped(system, rod) -> None:
    system.constrain(rod).using(ea.OneEndFixedBC, constrained_position_idx=(0,), constrained_director_idx=(0,))


def _gravity(system, rod) -> None:
    system.add_forcing_to(rod).using(ea.GravityForces, acc_gravity=np.array([0.0, 0.0, -reference.G]))


def _sampling(dt: float, period: float) -> tuple[float, int]:
    """A step dividing `period` (the cable model's sampling) no longer than `dt`, and steps per sample."""
    every = max(1, int(np.ceil(period / dt)))
    return period / every, every


def cantilever_omega(p: dict = reference.CANTILEVER) -> float:
    """First bending frequency of the clamped rod `p`, rad/s: beta_1^2 / L^2 sqrt(E r^2 / 4 rho)."""
    return float(cases.CANTILEVER_MODE ** 2 / p["length"] ** 2 * np.sqrt(p["young"] * p["radius"] ** 2 / (4.0 * p["density"])))


def elastica_frequency(n: int, zeta: float, omega_damped: float, cycles: int = 8, amplitude: float = 0.01,
                       p: dict = reference.CANTILEVER):
    """`physics_cases.ring_down` with gravity off in PyElastica (the rod `p`, started in its first
    mode, `amplitude` of its length at the tip): (omega rad/s, damping ratio, CPU s)."""
    omega = cantilever_omega(p)
    duration = (cycles + 1.5) * 2.0 * np.pi / omega
    c0 = time.process_time()
    system = _system()
    rod = _rod(n, p["length"], p["radius"], p["density"], p["young"], start=(0, 0, p["height"]))
    s = np.linspace(0.0, 1.0, n + 1)
    pts = rod.position_collection.T.copy()
    pts[:, 2] += amplitude * p["length"] * cases.cantilever_mode(s)
    _shape(rod, pts)
    system.append(rod)
    _clamped(system, rod)
    dt, every = _sampling(_step(n, p["length"], p["radius"], p["density"], p["young"]), 2e-4)
    _damp(system, rod, zeta, omega_damped, dt)
    system.finalize()
    t, x = [], []
    _run(system, dt, duration, every, lambda tt: (t.append(tt), x.append(rod.position_collection[2, -1] - p["height"])))
    z, w = cases.decrement(np.array(t), np.array(x), cycles)
    return w, z, time.process_time() - c0


def elastica_hose(n: int, hose: dict, young: float, density: float, zeta: float, omega: float, sample: float):
    """The released hose in PyElastica: (times, tip positions (k, 3), CPU s)."""
    c0 = time.process_time()
    system = _system()
    rod = _rod(n, hose["length"], hose["radius"], density, young, start=(0, 0, hose["height"]))
    system.append(rod)
    _clamped(system, rod)
    _gravity(system, rod)
    dt, every = _sampling(_step(n, hose["length"], hose["radius"], density, young), sample)
    _damp(system, rod, zeta, omega, dt)
    system.finalize()
    t, tip = [], []
    _run(system, dt, hose["duration"], every, lambda tt: (t.append(tt), tip.append(rod.position_collection[:, -1].copy())))
    return np.array(t), np.array(tip), time.process_time() - c0


def elastica_buckling(n: int, shortening: float, zeta: float, omega: float, push: float = 0.2,
                      duration: float = 0.6, rod_def: dict = cases.ROD, average: float = 0.1):
    """`physics_cases.straight_buckling` in PyElastica: the rod clamped at both ends, bowed by the
    cable model's imperfection (a half sine of 1e-6 of its length towards -z), its end pushed in
    `shortening` over `push` s at constant speed and held, gravity off.
    Returns (mid deflection m, end force N (the middle element's axial stress), CPU s), each the mean
    over the last `average` s (sampled every 0.1 ms): the push leaves axial waves ringing in the
    force, which the cable model's inextensible edges do not carry."""
    r = rod_def
    length = r["length"]
    c0 = time.process_time()
    system = _system()
    rod = _rod(n, length, r["radius"], r["density"], r["young"], start=(0, 0, 1.0))
    pts = rod.position_collection.T.copy()
    pts[:, 2] -= 1e-6 * length * np.sin(np.pi * np.linspace(0.0, 1.0, n + 1))
    _shape(rod, pts)
    system.append(rod)
    speed = shortening * length / push
    # start clamped; end clamped, not turned, moved along -x at `speed` until `push`
    Pushed = _turned_ends(rod.position_collection[:, 0].copy(), rod.position_collection[:, -1].copy(),
                          rod.director_collection[..., 0].copy(), rod.director_collection[..., -1].copy(),
                          lambda t: 0.0, lambda t: 0.0, lambda t: (speed * min(t, push), speed if t < push else 0.0))
    system.constrain(rod).using(Pushed, constrained_position_idx=(0, -1), constrained_director_idx=(0, -1))
    dt = _step(n, length, r["radius"], r["density"], r["young"])
    _damp(system, rod, zeta, omega, dt)
    system.finalize()
    sizes, forces = [], []

    def sample(tt):
        if tt >= duration - average - 1e-12:
            sizes.append(cases._deflection(rod.position_collection.T)[0])
            forces.append(-float(rod.internal_stress[2, n // 2]))

    _run(system, dt, duration, max(1, int(round(1e-4 / dt))), sample)
    return float(np.mean(sizes)), float(np.mean(forces)), time.process_time() - c0


def elastica_catenary(n: int, settle: float = 3.0, damping: float = 5.0):
    """The limp cable of `reference.CATENARY` in PyElastica: pinned at both ends (positions held,
    directors free), started as the cable model routes it, settled `settle` s with a uniform
    damping constant `damping` (1/s; a static answer). Returns (sag m, CPU s)."""
    p = reference.CATENARY
    density = 1500.0
    scene = reference.catenary_scene(n)
    young = scene.cables[0].young
    built = build(scene, detect=False)
    start = Simulation(built)
    start.reset()
    route = next(start.steps(contacts=False)).cables[0]
    c0 = time.process_time()
    system = _system()
    rod = _rod(n, p["length"], p["radius"], density, young, start=(0, 0, p["height"]), stretch=STIFF)
    # the route resampled at the rod's nodes, evenly by arc length
    arc = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(route, axis=0), axis=1))])
    u = np.linspace(0.0, arc[-1], n + 1)
    pts = np.stack([np.interp(u, arc, route[:, k]) for k in range(3)], axis=1)
    pts[0], pts[-1] = route[0], route[-1]
    _shape(rod, pts)
    system.append(rod)
    system.constrain(rod).using(ea.FixedConstraint, constrained_position_idx=(0, -1))
    _gravity(system, rod)
    dt = _step(n, p["length"], p["radius"], density, young, STIFF)
    system.dampen(rod).using(ea.AnalyticalLinearDamper, uniform_damping_constant=damping, time_step=dt)
    system.finalize()
    _run(system, dt, settle, 10 ** 9, lambda tt: None)
    sag = p["height"] - float(rod.position_collection[2].min())
    return sag, time.process_time() - c0


def _turn_x(angle: float) -> np.ndarray:
    """The rotation by `angle` (rad) about world x."""
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def _shear_modulus(rod, shear: float, young: float) -> None:
    """Set the rod's shear modulus G (twist G J, shear G A) from PyElastica's E / 3 to `shear` (Pa)."""
    f = shear / (young / 3.0)
    rod.bend_matrix[2, 2, :] *= f
    rod.shear_matrix[0, 0, :] *= f
    rod.shear_matrix[1, 1, :] *= f


def _turned_ends(p0, p1, d0, d1, angle, rate, moved=lambda t: (0.0, 0.0)):
    """A constraint class: start clamped at `p0`, `d0`; end clamped at `p1` less `moved(t)`[0] along
    x (speed `moved(t)`[1]) with its directors `d1` turned by `angle(t)` about world x (the chord)
    at `rate(t)` rad/s: PyElastica's directors are rows (lab to material), so turned Q = Q0 R^T,
    and omega is in the material frame, Q [rate, 0, 0]."""

    class Turned(ea.ConstraintBase):
        def constrain_values(self, system, time):
            system.position_collection[:, 0] = p0
            system.position_collection[:, -1] = p1 - np.array([moved(time)[0], 0.0, 0.0])
            system.director_collection[..., 0] = d0
            system.director_collection[..., -1] = d1 @ _turn_x(angle(time)).T

        def constrain_rates(self, system, time):
            system.velocity_collection[:, 0] = 0.0
            system.velocity_collection[:, -1] = (-moved(time)[1], 0.0, 0.0)
            system.omega_collection[..., 0] = 0.0
            system.omega_collection[..., -1] = system.director_collection[..., -1] @ np.array([rate(time), 0.0, 0.0])

    return Turned


def _ramp(start: float, length: float, total: float):
    """`total` spread evenly over [start, start + length]: (value(t), rate(t))."""
    rate = total / length
    return (lambda t: rate * min(max(t - start, 0.0), length),
            lambda t: rate if start <= t < start + length else 0.0)


def elastica_twist(rod) -> float:
    """The rod's twist end to end, radians: its material twist kappa_3 over the interior nodes'
    Voronoi lengths (PyElastica's kappa is per rest length)."""
    return float(np.sum(rod.kappa[2] * rod.rest_voronoi_lengths))


def elastica_twisted_buckling(n: int, zeta: float, omega: float, turns: float = 3.0, shortening: float = 0.03,
                              push: float = 0.2, hold: float = 0.4, turn: float = cases.TWIST_TURN,
                              settle: float = 0.4, rod_def: dict = cases.ROD, shear: float | None = None):
    """`physics_cases.twisted_buckling` in PyElastica: `elastica_buckling`'s rod and push (the same
    imperfection), held to `hold`, then its end element's directors turned `turns` full turns about
    the chord (world x) at constant rate over `turn` s (omega set to match), held `settle` s.
    `shear` the shear modulus (Pa; None: PyElastica's E / 3). Returns (the quarters' angle at the
    end (degrees, `physics_cases.twist_shape`), a dict: `mid_angle` (degrees: the mid-span
    deflection's turn from before the turns), `largest` quarters' angle, `deflection_before`,
    `deflection` (m), `twist` end to end (degrees), `writhe` (turns x 360 less twist), CPU s)."""
    r = rod_def
    length = r["length"]
    c0 = time.process_time()
    system = _system()
    rod = _rod(n, length, r["radius"], r["density"], r["young"], start=(0, 0, 1.0))
    if shear is not None:
        _shear_modulus(rod, shear, r["young"])
    pts = rod.position_collection.T.copy()
    pts[:, 2] -= 1e-6 * length * np.sin(np.pi * np.linspace(0.0, 1.0, n + 1))
    _shape(rod, pts)
    system.append(rod)
    speed = shortening * length / push
    angle, rate = _ramp(hold, turn, 2.0 * np.pi * turns)
    Turned = _turned_ends(rod.position_collection[:, 0].copy(), rod.position_collection[:, -1].copy(),
                          rod.director_collection[..., 0].copy(), rod.director_collection[..., -1].copy(), angle, rate,
                          lambda t: (speed * min(t, push), speed if t < push else 0.0))
    system.constrain(rod).using(Turned, constrained_position_idx=(0, -1), constrained_director_idx=(0, -1))
    dt = _step(n, length, r["radius"], r["density"], r["young"], None if shear is None else max(r["young"], 3 * shear))
    _damp(system, rod, zeta, omega, dt)
    system.finalize()
    seen = {"quarters": []}

    def sample(tt):
        shape = cases.twist_shape(rod.position_collection.T)
        if tt <= hold + 1e-12:
            seen["bow"] = shape["mid"]
        seen["quarters"].append(shape["quarters"])
        seen["last"] = shape

    _run(system, dt, hold + turn + settle, max(1, int(round(0.01 / dt))), sample)
    p = rod.position_collection.T
    last, twist = seen["last"], np.degrees(elastica_twist(rod))
    quarters = np.degrees(np.unwrap(seen["quarters"]))
    mid = np.degrees(cases._angle_about(p[-1] - p[0], seen["bow"], last["mid"]))
    extra = dict(mid_angle=float(mid), largest=float(np.abs(quarters).max()),
                 deflection_before=float(np.linalg.norm(seen["bow"])), deflection=float(np.linalg.norm(last["mid"])),
                 twist=float(twist), writhe=float(360.0 * turns - twist))
    return float(quarters[-1]), extra, time.process_time() - c0


def elastica_twisted_hose(n: int, young: float, density: float, zeta: float, omega: float, route: np.ndarray,
                          turns: float = 4.0, turn: float = cases.HOSE_TURN, hold: float = 3.0, settle: float = 1.0,
                          hose: dict = cases.HOSE, shear: float | None = None):
    """`physics_cases.twisted_hose` in PyElastica: the hose started in `route` (the cable model's
    settled shape, resampled evenly by arc length, its end elements put level along the chord as the
    cable model clamps them), clamped at both ends, gravity on, settled `settle` s with a
    uniform damping constant 2 omega (the first mode critically damped; the cable model settles by
    kinetic damping: both to the static sag), then its end's directors turned `turns` full turns
    about the chord (x) at constant rate over `turn` s with the declared damping 2 zeta omega and
    held `hold` s. `shear` the shear modulus (Pa; None: PyElastica's E / 3).
    Returns (the whirl at the end (degrees, `physics_cases.twisted_hose`'s: the angle about the
    chord from the sag at L/4 to that at 3L/4), a dict: `whirl` (the mid-span sag's angle from straight
    down at the end) and `largest_whirl` (over the run), `largest` |quarters' angle|, `sag_before`,
    `sag` (m), `twist`, `writhe` (degrees), `trace` (times from the turn's start, s, quarters' angle
    and mid-span whirl, degrees, every 10 ms), CPU s)."""
    c0 = time.process_time()
    system = _system()
    rod = _rod(n, hose["length"], hose["radius"], density, young, start=tuple(route[0]))
    if shear is not None:
        _shear_modulus(rod, shear, young)
    arc = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(route, axis=0), axis=1))])
    u = np.linspace(0.0, arc[-1], n + 1)
    pts = np.stack([np.interp(u, arc, route[:, k]) for k in range(3)], axis=1)
    # the clamped end elements level, along the chord, as the cable model's clamps hold them: resampled,
    # they would follow the sag down a few degrees, and turning such an end about the chord swings its
    # tangent round a cone, which drags the sag round with it
    dx = hose["length"] / n
    pts[1] = pts[0] + dx * np.array([1.0, 0.0, 0.0])
    pts[-2] = pts[-1] - dx * np.array([1.0, 0.0, 0.0])
    _shape(rod, pts)
    system.append(rod)
    angle, rate = _ramp(settle, turn, 2.0 * np.pi * turns)
    Turned = _turned_ends(pts[0].copy(), pts[-1].copy(), rod.director_collection[..., 0].copy(),
                          rod.director_collection[..., -1].copy(), angle, rate)
    system.constrain(rod).using(Turned, constrained_position_idx=(0, -1), constrained_director_idx=(0, -1))
    _gravity(system, rod)
    dt = _step(n, hose["length"], hose["radius"], density, young, None if shear is None else max(young, 3 * shear))
    fast, slow = np.exp(-2.0 * omega * dt), np.exp(-2.0 * zeta * omega * dt)

    class Settling(ea.DamperBase):
        """Uniform damping: 2 omega while settling, then 2 zeta omega (`AnalyticalLinearDamper`'s)."""

        def dampen_rates(self, system, time):
            k = fast if time < settle else slow
            system.velocity_collection *= k
            system.omega_collection *= k

    system.dampen(rod).using(Settling)
    system.finalize()
    down = np.array([0.0, 0.0, -1.0])
    seen = {"whirl": [], "quarters": [], "t": []}

    def sample(tt):
        p = rod.position_collection.T
        shape = cases.twist_shape(p)
        if tt <= settle + 1e-12:
            seen["before"] = shape["mid"]
        if tt >= settle - 1e-12:
            seen["t"].append(tt - settle)
            seen["whirl"].append(cases._angle_about(p[-1] - p[0], down, shape["mid"]))
            seen["quarters"].append(shape["quarters"])
        seen["mid"] = shape["mid"]

    _run(system, dt, settle + turn + hold, max(1, int(round(0.01 / dt))), sample)
    whirl = np.degrees(np.unwrap(seen["whirl"]))
    quarters = np.degrees(np.unwrap(seen["quarters"]))
    twist = np.degrees(elastica_twist(rod))
    extra = dict(whirl=float(whirl[-1]), largest_whirl=float(np.abs(whirl).max()), largest=float(np.abs(quarters).max()),
                 sag_before=float(np.linalg.norm(seen["before"])), sag=float(np.linalg.norm(seen["mid"])),
                 twist=float(twist), writhe=float(360.0 * turns - twist), trace=(np.array(seen["t"]), quarters, whirl))
    return float(quarters[-1]), extra, time.process_time() - c0


def warm_up() -> float:
    """Compile PyElastica's numba kernels on a tiny rod; CPU s."""
    c0 = time.process_time()
    system = _system()
    rod = _rod(4, 0.1, 0.002, 1000.0, 1e6)
    system.append(rod)
    _clamped(system, rod)
    _gravity(system, rod)
    _damp(system, rod, 0.1, 10.0, 1e-5)
    system.finalize()
    _run(system, 1e-5, 1e-4, 1, lambda tt: None)
    return time.process_time() - c0


# ----------------------------------------------------------------------------- cable model side

def hose_scene(hose: dict = HOSE):
    """The released hose as a scene: clamped level at the world, its end free, no settling."""
    data = {"scene": {"name": "hose", "units": "m", "duration": hose["duration"], "settle": 0.0, "timestep": 0.002},
            "cables": [{"name": "hose", "radius": hose["radius"], "start": {"body": "world", "pos": [0, 0, hose["height"]]},
                        "end": {"pos": [hose["length"], 0, hose["height"]], "hold": "free"}}]}
    return parse_scene(data, Path("/virtual/hose.toml"))


def cable_hose(hose: dict = HOSE):
    """The released hose in the cable model: (scene, built, times, tip positions, CPU s)."""
    c0 = time.process_time()
    scene = hose_scene(hose)
    built = build(scene, detect=False)
    sim = Simulation(built)
    sim.reset()
    t, tip = [], []
    for s in sim.steps(contacts=False):
        t.append(s.t)
        tip.append(s.cables[0][-1].copy())
    return scene, built, np.array(t), np.array(tip), time.process_time() - c0


def _first_mode(built) -> tuple[float, float]:
    return cable_damping(built)[built.cables[0].flex_id]


# ----------------------------------------------------------------------------- the table

@dataclass
class PeerRow:
    """One shared problem: the closed form (None where there is none), the cable model's and
    PyElastica's answers (PyElastica's `NOT_INSTALLED` without it), differences in %, CPU s."""

    case: str
    quantity: str
    closed_form: float | None
    cablecheck: float
    elastica: float | str
    cpu_cablecheck: float
    cpu_elastica: float | str
    vs_closed_pct: float | None = None
    vs_elastica_pct: float | str | None = None
    note: str = ""
    extra: dict = field(default_factory=dict)


def _pct(a, b):
    """a / b - 1 in %; None without b, b itself where it is a word (`NOT_INSTALLED`)."""
    return None if b is None else b if isinstance(b, str) else 100.0 * (a / b - 1.0)


def frequency_row(elements: dict = ELEMENTS) -> PeerRow:
    c0 = time.process_time()
    r = cases.ring_down(CABLE_ELEMENTS["frequency"], gravity=False)
    cpu = time.process_time() - c0
    closed = cantilever_omega()
    zeta = r.reference
    if AVAILABLE:
        w, z, cpu_e = elastica_frequency(elements["frequency"], zeta, r.extra["first_mode"])
    else:
        w = z = cpu_e = NOT_INSTALLED
    note = (f"0.2 m cantilever r 4 mm 400 MPa, gravity off, 1 % tip start; {r.elements} / {elements['frequency']} "
            f"elements; damping ratio declared {zeta:g}: cablecheck {r.measured:.4f}, PyElastica "
            f"{z if isinstance(z, str) else f'{z:.4f}'}")
    return PeerRow("cantilever first frequency", "rad/s", closed, r.extra["omega"], w, cpu, cpu_e,
                   _pct(r.extra["omega"], closed), _pct(r.extra["omega"], w), note,
                   dict(zeta=r.measured, zeta_elastica=z))


def hose_row(elements: dict = ELEMENTS, hose: dict = HOSE) -> PeerRow:
    scene, built, t, tip, cpu = cable_hose(hose)
    d = scene.cables[0]
    zeta, omega = _first_mode(built)
    low = float(hose["height"] - tip[:, 2].min())
    if AVAILABLE:
        te, tipe, cpu_e = elastica_hose(elements["hose"], hose, d.young, d.density, zeta, omega,
                                        float(np.median(np.diff(t))))
        k = min(len(t), len(te))
        gap = np.linalg.norm(tip[:k] - tipe[:k], axis=1)
        rms = float(np.sqrt(np.mean(gap ** 2)))
        low_e = float(hose["height"] - tipe[:, 2].min())
        diff = 100.0 * rms / hose["length"]
        extra = dict(rms=rms, worst=float(gap.max()), lag=float(np.abs(t[:k] - te[:k]).max()))
        note_e = f"tip paths {1000 * rms:.1f} mm RMS apart ({diff:.2f} % of L), at most {1000 * gap.max():.1f} mm"
    else:
        low_e = cpu_e = NOT_INSTALLED
        diff, extra, note_e = NOT_INSTALLED, {}, "PyElastica not installed"
    note = (f"{hose['length']:g} m hose r {1000 * hose['radius']:g} mm, {d.young:.3g} Pa, {d.density:g} kg/m3, damping "
            f"{d.damping:g} (first mode {omega:.1f} rad/s), released level, {hose['duration']:g} s; "
            f"{built.cables[0].elements} / {elements['hose']} elements; lowest tip drop m; vs PyElastica: RMS of "
            f"the tip-path distance over L; {note_e}")
    return PeerRow("released hose", "m", None, low, low_e, cpu, cpu_e, None, diff, note, extra)


def buckling_row(elements: dict = ELEMENTS, shortening: float = 0.03) -> PeerRow:
    c0 = time.process_time()
    r = cases.straight_buckling(shortening, CABLE_ELEMENTS["buckling"])
    cpu = time.process_time() - c0
    zeta, omega = _clamped_mode()   # the damping ratio on the clamped rod's first mode, as the cable model holds it
    if AVAILABLE:
        size, force, cpu_e = elastica_buckling(elements["buckling"], shortening, zeta, omega)
        fe = f"{force:.4g}"
    else:
        size = cpu_e = fe = NOT_INSTALLED
    e = r.extra
    note = (f"0.5 m rod r 3 mm 2 GPa clamped, end pushed in {100 * shortening:g} % over 0.2 s, held to 0.6 s, "
            f"gravity off; {r.elements} / {elements['buckling']} elements; mid deflection m; end force N: "
            f"elastica {e['force_ref']:.4g}, cablecheck {e['force']:.4g}, PyElastica {fe}")
    return PeerRow(f"buckled rod {100 * shortening:g} %", "m", r.reference, r.measured, size, cpu, cpu_e,
                   _pct(r.measured, r.reference), _pct(r.measured, size), note,
                   dict(force=e["force"], force_ref=e["force_ref"], force_elastica=fe))


def catenary_row(elements: dict = ELEMENTS) -> PeerRow:
    c0 = time.process_time()
    r = cases.catenary(CABLE_ELEMENTS["catenary"])
    cpu = time.process_time() - c0
    if AVAILABLE:
        sag, cpu_e = elastica_catenary(elements["catenary"])
    else:
        sag = cpu_e = NOT_INSTALLED
    note = (f"limp 1 m over 0.8 m, r 4 mm; {r.elements} / {elements['catenary']} elements; sag m; PyElastica "
            f"bends at 1 Pa, stretches at {STIFF:.0e} Pa, settled 3 s")
    return PeerRow("catenary sag", "m", r.reference, r.measured, sag, cpu, cpu_e, _pct(r.measured, r.reference),
                   _pct(r.measured, sag), note)


def _clamped_mode(rod: dict = cases.ROD) -> tuple[float, float]:
    """The damping ratio and first mode (rad/s) of `rod` clamped straight at both ends, gravity off,
    as the cable model holds them (`cable_damping`)."""
    scene = cases._scene({"scene": {"name": "b", "units": "m", "duration": 0.1, "settle": 0.0, "timestep": 0.002},
                          "effects": {"gravity": False},
                          "cables": [{"name": "rod", "radius": rod["radius"], "start": {"pos": [0, 0, 1]},
                                      "end": {"pos": [rod["length"], 0, 1]}, "young": rod["young"],
                                      "density": rod["density"]}]})
    return _first_mode(build(scene, detect=False))


def _num(v, fmt: str = ".1f") -> str:
    return v if isinstance(v, str) else format(v, fmt)


def twisted_buckling_row(elements: dict = ELEMENTS, turns: float = 3.0, shortening: float = 0.03) -> PeerRow:
    """`physics_cases.twisted_buckling` on both, at PyElastica's shear modulus (E / 3, its Poisson
    ratio 0.5): the cable's `twist_stiffness` is set to it."""
    rod = cases.ROD
    shear = rod["young"] / 3.0
    c0 = time.process_time()
    r = cases.twisted_buckling(turns, shortening, CABLE_ELEMENTS["twisted_buckling"], twist_stiffness=shear)
    cpu = time.process_time() - c0
    zeta, omega = _clamped_mode(rod)
    if AVAILABLE:
        angle, e_el, cpu_e = elastica_twisted_buckling(elements["twisted_buckling"], zeta, omega, turns, shortening)
    else:
        angle = cpu_e = NOT_INSTALLED
        e_el = {k: NOT_INSTALLED for k in ("mid_angle", "deflection", "twist", "writhe")}
    e = r.extra
    mm = (lambda v: v if isinstance(v, str) else f"{1000 * v:.1f}")
    note = (f"0.5 m rod r 3 mm 2 GPa, G = E / 3 in both, clamped, end pushed in {100 * shortening:g} % over 0.2 s, "
            f"held to {e['hold']:g} s, turned {turns:g} turns about the chord over {e['turn']:g} s, held "
            f"{e['settle']:g} s, gravity off; {r.elements} / {elements['twisted_buckling']} elements; degrees about "
            f"the chord from the deflection at L/4 to that at 3L/4 (0: in the buckling plane); cablecheck / "
            f"PyElastica: mid deflection {mm(e['deflection'])} / {mm(e_el['deflection'])} mm (before the turns "
            f"{1000 * e['deflection_before']:.1f}), twist {e['twist']:.0f} / {_num(e_el['twist'], '.0f')} deg, writhe "
            f"{e['writhe']:.1f} / {_num(e_el['writhe'])} deg; mid-span deflection turned out of the buckling plane "
            f"{e['mid_angle']:.1f} / {_num(e_el['mid_angle'])} deg (not set by the statics: the problem is the same "
            f"turned about the chord)")
    return PeerRow(f"twisted buckled rod {turns:g} turns", "deg", None, r.measured, angle, cpu, cpu_e, None,
                   _pct(r.measured, angle), note, dict(cable=e, elastica=e_el))


APPROACH = 0.01
"""The slack `twisted_hose_row`'s second cable-model run starts its end at (`physics_cases.twisted_hose`'s
`approach`). At commit 6074e19 MuJoCo kept no twist state (`mjData.plastic` stayed 0) for a rod
clamped at both ends and routed with more than a few % of slack along its chord (above about 4 %
at 20 elements, 3 % at 40; measured 2026-11-28), so its turned end wound nothing; routed with 1 %
it keeps the state as its ends then close in. The row reads both runs."""


def twisted_hose_row(elements: dict = ELEMENTS, turns: float = 4.0, slack: float = 0.2) -> PeerRow:
    """`physics_cases.twisted_hose` on both, at PyElastica's shear modulus (E / 3): the cable's
    `twist_stiffness` is set to it; PyElastica starts from the cable model's settled shape. The
    cable model runs twice: as the problem is set (routed slack, settled, turned) and with its end
    moved in from `APPROACH` slack before the turns; the row's value is the first, the note gives
    the second (and says so where the first carries no twist)."""
    c0 = time.process_time()
    shear = DEFAULT_YOUNG / 3.0
    r = cases.twisted_hose(turns, slack, CABLE_ELEMENTS["twisted_hose"], twist_stiffness=shear)
    cpu = time.process_time() - c0
    moved = cases.twisted_hose(turns, slack, CABLE_ELEMENTS["twisted_hose"], twist_stiffness=shear, approach=APPROACH)
    e, m = r.extra, moved.extra
    if AVAILABLE:
        whirl, e_el, cpu_e = elastica_twisted_hose(elements["twisted_hose"], e["young"], e["density"], e["damping"],
                                                   e["first_mode"], e["rest"], turns, e["turn"], e["hold"])
    else:
        whirl = cpu_e = NOT_INSTALLED
        e_el = {k: NOT_INSTALLED for k in ("whirl", "sag", "twist", "writhe")}
    mm = (lambda v: v if isinstance(v, str) else f"{1000 * v:.1f}")
    vs = _pct(moved.measured, whirl)
    note = (f"{HOSE['length']:g} m hose r {1000 * HOSE['radius']:g} mm, {e['young']:.3g} Pa, G = E / 3 in both, "
            f"{e['density']:g} kg/m3, damping {e['damping']:g} (first mode {e['first_mode']:.1f} rad/s), clamped level "
            f"{e['span']:.4g} m apart ({100 * slack:g} % slack), gravity on, settled, turned {turns:g} turns about the "
            f"chord over {e['turn']:g} s, held {e['hold']:g} s; {r.elements} / {elements['twisted_hose']} elements; "
            f"degrees about the chord from the sag at L/4 to that at 3L/4 (0: hanging in one plane); cablecheck / "
            f"PyElastica: sag {mm(e['sag'])} / {mm(e_el['sag'])} mm (settled {1000 * e['sag_before']:.1f}), twist "
            f"{e['twist']:.0f} / {_num(e_el['twist'], '.0f')} deg (PyElastica's writhe {_num(e_el['writhe'], '.0f')} "
            f"deg), mid-span sag from straight down {e['whirl']:.1f} / "
            f"{_num(e_el['whirl'])} deg (0 or 180 for a hose symmetric end for end). "
            + ("The cable model's rod carries no twist here: MuJoCo keeps no twist state for it as it is routed. "
               if abs(e["twist"]) < 0.01 * 360.0 * abs(turns) else "")
            + f"Its end moved in from {100 * APPROACH:g} % slack after settling: {moved.measured:.1f} deg "
            f"({_num(vs)} % from PyElastica), sag {mm(m['sag'])} mm, twist {m['twist']:.0f} deg, writhe "
            f"{m['writhe']:.0f} deg")
    return PeerRow(f"twisted hose {turns:g} turns", "deg", None, r.measured, whirl, cpu, cpu_e, None,
                   _pct(r.measured, whirl), note, dict(cable=e, moved=m, moved_vs_elastica_pct=vs, elastica=e_el))


def rows(elements: dict = ELEMENTS) -> list[PeerRow]:
    return [frequency_row(elements), hose_row(elements), buckling_row(elements), catenary_row(elements),
            twisted_buckling_row(elements), twisted_hose_row(elements)]
