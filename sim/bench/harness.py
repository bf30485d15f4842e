"""A harness-like scene of any size, for benchmarks and tests of scale.

:func:`harness_scene` returns the dict a scene TOML file parses to (through
:func:`cablecheck.scene.parse_scene` like any scene file; :func:`write_scene` writes
it as TOML): ``n_cables`` cables of ``segments`` elements threaded along x
through ``n_parts`` non-overlapping rigid parts, in mm.

Layout. Parts sit on a lattice of slices across x (pitch ``PITCH``), each
slice a square of ``(m + 1) x (m + 1)`` sites in y and z with ``m =
ceil(sqrt(n_cables))``; cables run along the ``m x m`` channels between the
sites, weaving by a few mm from slice to slice (``via`` points). A part's
bounding sphere is at most ``MAX_RADIUS`` (boxes, cylinders, capsules,
spheres and ellipsoids at random orientations), so neighbours never overlap
and a channel keeps a gap of several cable radii around its cable. A few
parts (one in ``NEAR_EVERY``) are moved towards their nearest channel, so
that they come within the clearance of that cable, and a few pairs of
neighbouring parts are moved to within the clearance of each other. Every
cable starts clamped on the world side (x < 0) and ends on a ``carriage``
body past the last slice, which rises and falls by ``CARRIAGE_TRAVEL`` over
the run; the carriage carries one plate part. The routes droop between their
via points and nothing holds a cable there: a run that does not settle
(``settle`` 0, the default) starts with every cable falling into its sag.

Not here: building, running, timing (``benchmarks/bench_scale.py``).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from scipy.spatial import cKDTree

PITCH = 60.0
"""Distance between neighbouring part sites, mm."""

MAX_RADIUS = 20.0
"""Largest bounding-sphere radius of a part, mm (sites are ``PITCH`` apart)."""

RADIUS = 3.0
"""Cable radius, mm."""

CLEARANCE = 2.0
"""Soft clearance, mm."""

NEAR_EVERY = 50
"""One part in this many is moved to within the clearance of a cable."""

CARRIAGE_TRAVEL = 30.0
"""The carriage's rise, mm."""

SETTLE = 1.0
"""Seconds of settling (``scene.settle``) that bring the 64 x 1,000 harness to
rest before t = 0: its cables (spans of 840 mm, 5 % longer than their
routes) sag by about 120 mm, and the settling's kinetic damping
(:meth:`cablecheck.run.loop.Simulation.settle`) has them still (under 0.3 mm per 0.1 s)
by 0.7 s. Longer spans (few cables among many parts) sag more and need more."""

KINDS = ("box", "cylinder", "capsule", "sphere", "ellipsoid")


def bounding_radius(kind: str, size: np.ndarray) -> float:
    """The radius of a sphere about a primitive part's origin holding it (its size as the scene gives it)."""
    if kind == "box":
        return float(np.linalg.norm(size))
    if kind in ("cylinder",):
        return float(math.hypot(size[0], size[1]))
    if kind == "capsule":
        return float(size[0] + size[1])
    return float(np.max(size))


def harness_scene(n_cables: int = 64, n_parts: int = 1000, segments: int = 40, duration: float = 1.0,
                  seed: int = 0, dynamics: bool = True, method: str = "points", settle: float = 0.0) -> dict:
    """The scene dict (see the module docstring).

    Args:
        n_cables: cables (>= 1).
        n_parts: rigid parts besides the carriage's plate (>= 0).
        segments: MuJoCo elements per cable (more where its route has more
            points: one per slice of parts it threads).
        duration: simulated seconds (the carriage rises over the first half
            and falls back over the second).
        seed: random sizes, orientations and near parts.
        dynamics: simulate the cables (False: a static check of the routes).
        method: the check method ("points" or "exact").
        settle: seconds settled before t = 0 (`scene.settle`). The routes
            droop between their via points and nothing holds a cable there,
            so without settling (0) the run starts with every cable falling
            into its sag and swinging; :data:`SETTLE` brings them to rest first.
    """
    if n_cables < 1 or n_parts < 0 or segments < 1:
        raise ValueError("need n_cables >= 1, n_parts >= 0, segments >= 1")
    rng = np.random.default_rng(seed)
    m = math.ceil(math.sqrt(n_cables))
    per_slice = (m + 1) ** 2
    slices = max(1, math.ceil(n_parts / per_slice))
    # cables at least 2.5 radii per element (MuJoCo's flex wants elements longer than r)
    length_x = max((slices + 1) * PITCH, 2.5 * RADIUS * segments * 1.02)
    x0 = 0.5 * (length_x - (slices - 1) * PITCH)          # first slice, cables start at x = 0
    x_end = length_x
    parts = []
    sites = [(s, a, b) for s in range(slices) for a in range(m + 1) for b in range(m + 1)][:n_parts]
    near = set(rng.choice(len(sites), size=max(1, len(sites) // NEAR_EVERY), replace=False).tolist()) \
        if sites else set()
    for k, (s, a, b) in enumerate(sites):
        kind = KINDS[k % len(KINDS)]
        raw = rng.uniform(4.0, 12.0, size=3)
        size = {"box": raw, "ellipsoid": raw, "sphere": raw[:1], "cylinder": raw[:2],
                "capsule": raw[:2]}[kind]
        rho = bounding_radius(kind, size)
        if rho > MAX_RADIUS:
            size = size * (MAX_RADIUS / rho)
            rho = MAX_RADIUS
        pos = np.array([x0 + s * PITCH, a * PITCH, b * PITCH])
        euler = rng.uniform(-180.0, 180.0, size=3)
        if k in near and m > 0:
            # towards the nearest channel centre (a cable's rest line), a sphere so
            # the gap is exact whatever the orientation: gap = CLEARANCE / 2
            kind, size, euler = "sphere", np.array([rho]), np.zeros(3)
            ca = min(max(a - 0.5, 0.5), m - 0.5)
            cb = min(max(b - 0.5, 0.5), m - 0.5)
            chan = np.array([pos[0], ca * PITCH, cb * PITCH])
            u = pos - chan
            u[0] = 0.0
            dist = float(np.linalg.norm(u))
            target = rho + RADIUS + 0.5 * CLEARANCE
            pos = chan + u * (target / dist)
        parts.append({"name": f"frame/slice{s:02d}/part{k}", "shape": kind,
                      "size": [float(x) for x in size], "pos": [float(x) for x in pos],
                      "euler": [float(x) for x in euler]})
    # a few neighbouring pairs within the clearance of each other: two spheres
    # of MAX_RADIUS, the second moved along z towards the first, gap CLEARANCE / 2
    for k in range(NEAR_EVERY // 2, len(sites) - 1, 4 * NEAR_EVERY):
        if sites[k][2] == m or k in near or k + 1 in near:
            continue
        p, q = parts[k], parts[k + 1]
        p.update(shape="sphere", size=[MAX_RADIUS], euler=[0.0, 0.0, 0.0])
        q.update(shape="sphere", size=[MAX_RADIUS], euler=[0.0, 0.0, 0.0])
        q["pos"] = [p["pos"][0], p["pos"][1], p["pos"][2] + 2 * MAX_RADIUS + 0.5 * CLEARANCE]
    parts = _drop_overlaps(parts)
    cables = []
    for c in range(n_cables):
        a, b = divmod(c, m)
        y, z = (a + 0.5) * PITCH, (b + 0.5) * PITCH
        via = []
        for s in range(slices):
            # between slices: weave by a fifth of a radius, well inside the channel
            w = 0.2 * RADIUS * (1 if (s + c) % 2 else -1)
            via.append([x0 + (s + 0.5) * PITCH, y + w, z - w])
        route = np.array([[0.0, y, z]] + via + [[x_end, y, z]])
        path = float(np.linalg.norm(np.diff(route, axis=0), axis=1).sum())
        # every route point is a vertex: a long cable (few cables among many parts) gets more elements
        cables.append({"name": f"c{c:02d}", "radius": RADIUS, "segments": max(segments, len(route)),
                       "length": round(1.05 * path, 6),
                       "start": {"body": "world", "pos": [0.0, y, z]},
                       "end": {"body": "carriage", "pos": [x_end, y, z]},
                       "via": via, "young": 2.0e7, "density": 1500.0})
    top = m * PITCH
    parts.append({"name": "carriage/plate", "body": "carriage", "shape": "box",
                  "size": [5.0, 0.5 * top + 20.0, 0.5 * top + 20.0],
                  "pos": [x_end + 5.0 + RADIUS + 1.0, 0.5 * top, 0.5 * top]})
    half = 0.5 * duration
    motion = [{"body": "carriage",
               "keys": [{"t": 0.0, "pos": [0.0, 0.0, 0.0]},
                        {"t": half, "pos": [0.0, 0.0, CARRIAGE_TRAVEL]},
                        {"t": duration, "pos": [0.0, 0.0, 0.0]}]}] if duration > 0 else []
    return {
        "scene": {"name": f"harness-{n_cables}x{n_parts}", "units": "mm", "duration": duration,
                  "settle": settle},
        "effects": {"dynamics": dynamics, "gravity": dynamics,
                    "contact": ["cable-structure"] if dynamics else []},
        "check": {"method": method, "clearance": CLEARANCE},
        "bodies": [{"name": "carriage", "pos": [0.0, 0.0, 0.0]}],
        "parts": parts,
        "cables": cables,
        "motion": motion,
    }


def _drop_overlaps(parts: list[dict]) -> list[dict]:
    """Parts whose bounding spheres (grown by a quarter of the clearance) meet an earlier
    part's are dropped; the layout above never makes any (a safety net, tested)."""
    if not parts:
        return parts
    c = np.array([p["pos"] for p in parts], float)
    r = np.array([bounding_radius(p["shape"], np.array(p["size"])) for p in parts])
    pairs = cKDTree(c).query_pairs(2 * float(r.max()) + CLEARANCE, output_type="ndarray")
    if not len(pairs):
        return parts
    i, j = pairs[:, 0], pairs[:, 1]
    meet = np.linalg.norm(c[i] - c[j], axis=1) < r[i] + r[j] + 0.25 * CLEARANCE
    drop = set(np.maximum(i, j)[meet].tolist())
    return [p for k, p in enumerate(parts) if k not in drop]


def write_scene(data: dict, path: str | Path) -> Path:
    """Write the scene dict as a TOML file (the scene format's own subset: tables, arrays of
    tables, inline tables, numbers, strings, booleans)."""
    path = Path(path)
    lines: list[str] = []

    def value(v) -> str:
        if isinstance(v, bool):
            return "true" if v else "false"
        if isinstance(v, (int, np.integer)):
            return str(int(v))
        if isinstance(v, (float, np.floating)):
            return repr(float(v))
        if isinstance(v, str):
            return '"' + v.replace("\\", "\\\\").replace('"', '\\"') + '"'
        if isinstance(v, dict):
            return "{ " + ", ".join(f"{k} = {value(x)}" for k, x in v.items()) + " }"
        return "[" + ", ".join(value(x) for x in v) + "]"

    for key, table in data.items():
        if isinstance(table, list):
            for row in table:
                lines.append(f"[[{key}]]")
                lines += [f"{k} = {value(v)}" for k, v in row.items()]
                lines.append("")
        else:
            lines.append(f"[{key}]")
            lines += [f"{k} = {value(v)}" for k, v in table.items()]
            lines.append("")
    path.write_text("\n".join(lines))
    return path
