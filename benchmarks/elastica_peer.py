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

ELEMENTS = dict(frequency=80, hose=80, buckling=80, catenary=80)
"""PyElastica's elements per case. Its clamp holds the first element's directors, so a clamped rod
bends from about half an element in: its cantilever frequency comes out 5.1 / 2.4 / 1.2 % high at
20 / 40 / 80 elements, and its hose tip path 6.6 / 3.0 / 1.3 % of the length from the cable
model's (measured 2026-11-28); 80 keeps each case under about 40 s CPU. The cable model runs at
its cases' own counts (`CABLE_ELEMENTS`, the hose its default)."""

CABLE_ELEMENTS = dict(frequency=20, buckling=None, catenary=reference.CATENARY["elements"])
"""The cable model's elements: the ring-down rows' 20, the buckled rod's default (20), the catenary's 40."""

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

    class Pushed(ea.ConstraintBase):
        """Start clamped; end clamped and moved along -x at `speed` until `push`."""

        def __init__(self, p0, p1, d0, d1, **kw):
            super().__init__(**kw)
            self.p0, self.p1, self.d0, self.d1 = p0, p1, d0, d1

        def constrain_values(self, system, time):
            system.position_collection[:, 0] = self.p0
            system.position_collection[:, -1] = self.p1 - np.array([speed * min(time, push), 0.0, 0.0])
            system.director_collection[..., 0] = self.d0
            system.director_collection[..., -1] = self.d1

        def constrain_rates(self, system, time):
            system.velocity_collection[:, 0] = 0.0
            system.velocity_collection[:, -1] = (-speed if time < push else 0.0, 0.0, 0.0)
            system.omega_collection[..., 0] = 0.0
            system.omega_collection[..., -1] = 0.0

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
    # the damping ratio on the clamped rod's first mode, as the cable model holds it
    scene = cases._scene({"scene": {"name": "b", "units": "m", "duration": 0.1, "settle": 0.0, "timestep": 0.002},
                          "effects": {"gravity": False},
                          "cables": [{"name": "rod", "radius": cases.ROD["radius"], "start": {"pos": [0, 0, 1]},
                                      "end": {"pos": [cases.ROD["length"], 0, 1]}, "young": cases.ROD["young"],
                                      "density": cases.ROD["density"]}]})
    zeta, omega = _first_mode(build(scene, detect=False))
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


def rows(elements: dict = ELEMENTS) -> list[PeerRow]:
    return [frequency_row(elements), hose_row(elements), buckling_row(elements), catenary_row(elements)]
