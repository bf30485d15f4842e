"""A second harness layout, unlike :mod:`cablecheck.bench.harness`: cables crossing and resting on each other among parts scattered at random.

:func:`crossing_scene` returns the dict a scene TOML file parses to (write
it with :func:`cablecheck.bench.harness.write_scene`), in mm: half the
cables (the ``trunk``) run along x in a layer, held on ``world`` at x = 0
and on a ``slider`` body past x = ``SPAN`` that rises and falls by
``SLIDER_TRAVEL``; the other half (the ``branch``) run along y a little
above them, held on ``world`` at both ends. Both have a few per cent of
slack, so the branches sag onto the trunk and every branch crosses, and
comes to rest on, every trunk cable: hundreds of cable-cable pairs at or
inside the clearance at every state. ``n_parts`` parts (boxes, cylinders,
spheres, capsules, ellipsoids at random orientations) are scattered at
random through the volume below and around the layers, none overlapping
another or a route (their bounding spheres a millimetre clear); one in
``HUG_EVERY`` is drawn with its bounding sphere within 6 mm of a route, so
that the cables sagging onto them touch many parts. The
:mod:`cablecheck.bench.harness` lattice threads each cable through its
own channel instead: few pairs near, nothing crossing. Cable-cable contact
pushes back. This layout is the benchmark set's check that what is tuned
on the lattice holds on a harness laid out otherwise.

Not here: building, running, timing (``benchmarks/bench_scale.py``).
"""

from __future__ import annotations

import numpy as np

from cablecheck.bench.harness import bounding_radius

SPAN = 1000.0
"""Length of the square the cables cross, mm."""

RADIUS = 2.5
"""Cable radius, mm."""

CLEARANCE = 2.0
"""Soft clearance, mm."""

LIFT = 14.0
"""How far above the trunk layer the branches are routed, mm (they sag onto it)."""

HUG_EVERY = 3
"""One part in this many is drawn with its bounding sphere within 6 mm of a route."""

SLIDER_TRAVEL = 40.0
"""The slider's rise, mm."""

KINDS = ("box", "cylinder", "sphere", "capsule", "ellipsoid")


def crossing_scene(n_cables: int = 64, n_parts: int = 1000, segments: int = 40, duration: float = 1.0,
                   seed: int = 1, settle: float = 0.0) -> dict:
    """The scene dict (see the module docstring): ``n_cables`` (>= 2, half
    each way), ``n_parts`` parts, ``segments`` elements a cable, the slider's
    cycle over ``duration`` s, ``settle`` s of settling before t = 0."""
    if n_cables < 2 or n_parts < 0 or segments < 1:
        raise ValueError("need n_cables >= 2, n_parts >= 0, segments >= 1")
    rng = np.random.default_rng(seed)
    n_trunk = n_cables // 2
    n_branch = n_cables - n_trunk
    z0 = 200.0
    pitch_t, pitch_b = SPAN / (n_trunk + 1), SPAN / (n_branch + 1)
    cables, a, b = [], [], []
    for i in range(n_trunk):
        y = (i + 1) * pitch_t
        p0, p1 = [0.0, y, z0], [SPAN, y, z0]
        cables.append({"name": f"trunk/t{i:02d}", "radius": RADIUS, "segments": segments,
                       "length": round(1.03 * SPAN, 6), "start": {"body": "world", "pos": p0},
                       "end": {"body": "slider", "pos": p1}, "young": 5.0e7, "density": 1400.0})
        a.append(p0)
        b.append(p1)
    for i in range(n_branch):
        x = (i + 1) * pitch_b
        p0, p1 = [x, 0.0, z0 + LIFT], [x, SPAN, z0 + LIFT]
        cables.append({"name": f"branch/b{i:02d}", "radius": RADIUS, "segments": segments,
                       "length": round(1.02 * SPAN, 6), "start": {"body": "world", "pos": p0},
                       "end": {"body": "world", "pos": p1}, "young": 5.0e7, "density": 1400.0})
        a.append(p0)
        b.append(p1)
    parts = _scatter(rng, n_parts, np.array(a), np.array(b))
    parts.append({"name": "slider/plate", "body": "slider", "shape": "box",
                  "size": [4.0, 0.5 * SPAN + 20.0, 40.0], "pos": [SPAN + 10.0, 0.5 * SPAN, z0]})
    half = 0.5 * duration
    motion = [{"body": "slider", "keys": [{"t": 0.0, "pos": [0.0, 0.0, 0.0]},
                                          {"t": half, "pos": [0.0, 0.0, SLIDER_TRAVEL]},
                                          {"t": duration, "pos": [0.0, 0.0, 0.0]}]}] if duration > 0 else []
    return {
        "scene": {"name": f"crossing-{n_cables}x{n_parts}", "units": "mm", "duration": duration,
                  "settle": settle},
        "effects": {"dynamics": True, "gravity": True, "contact": ["cable-structure", "cable-cable"]},
        "check": {"method": "points", "clearance": CLEARANCE},
        "bodies": [{"name": "slider", "pos": [0.0, 0.0, 0.0]}],
        "parts": parts,
        "cables": cables,
        "motion": motion,
    }


def _scatter(rng: np.random.Generator, n_parts: int, a: np.ndarray, b: np.ndarray) -> list[dict]:
    """Parts drawn at random below and around the layers, each clear of
    every route by a millimetre and of every part drawn before it; every
    ``HUG_EVERY``-th within 6 mm of a route. Draws are tried in batches,
    each tested against the routes and the parts kept so far at once."""
    parts: list[dict] = []
    centres = np.zeros((0, 3))
    radii = np.zeros(0)
    d = b - a
    tries = 0
    while len(parts) < n_parts and tries < 400 * max(n_parts, 1):
        batch = 256
        tries += batch
        kinds = [KINDS[(len(parts) + k) % len(KINDS)] for k in range(batch)]
        raw = rng.uniform(3.0, 9.0, (batch, 3))
        sizes = [r[:1] if k == "sphere" else r[:2] if k in ("cylinder", "capsule") else r for k, r in zip(kinds, raw)]
        rho = np.array([bounding_radius(k, x) for k, x in zip(kinds, sizes)])
        pos = rng.uniform([0.0, 0.0, 60.0], [SPAN, SPAN, 260.0], (batch, 3))
        t = np.clip(np.einsum("nri,ri->nr", pos[:, None, :] - a[None], d) / np.einsum("ri,ri->r", d, d), 0.0, 1.0)
        gap = np.linalg.norm(pos[:, None, :] - (a[None] + t[..., None] * d[None]), axis=2).min(axis=1) - rho - RADIUS
        for k in np.flatnonzero(gap >= 1.0):
            if len(parts) >= n_parts:
                break
            hug = len(parts) % HUG_EVERY == 0
            if hug and gap[k] > 6.0:
                continue
            if len(radii) and (np.linalg.norm(centres - pos[k], axis=1) < radii + rho[k] + 0.5).any():
                continue
            parts.append({"name": f"frame/p{len(parts)}", "shape": kinds[k], "size": [float(x) for x in sizes[k]],
                          "pos": [float(x) for x in pos[k]],
                          "euler": [float(x) for x in rng.uniform(-180.0, 180.0, 3)]})
            centres = np.vstack([centres, pos[k]])
            radii = np.r_[radii, rho[k]]
    return parts

