"""Cables whose initial shape runs through a part they collide with, found before anything is simulated.

A route drawn through a part (a hose routed through an arm's elbow, a
via point inside a bracket) starts the simulation with the cable inside a
solid it collides with: the first steps push it out violently, the run
crawls and its strain and events are nonsense, and nothing says why. With
`cable-structure` contact on, :func:`route_warnings` measures every vertex of
every cable's routed shape at t = 0, and every element between two of
them (a plate or a ring an element passes through between its ends),
against each part it collides with
(`cablecheck.build.obstacles.Obstacles`: scene parts that are not keep-outs, the mjcf
model's colliding geoms) and names each part a cable's centreline enters:
the cable, the part, the stretch of arc length (scene units) and how deep.

Vertices within `check.attach_zone` radii of arc length of a held vertex are
left out: an end sits in the part it is fastened to by design.

This module only measures and words; `cablecheck check` and `run` print
what it finds (a run also lists it in the report's `physics_warnings`).
"""

from __future__ import annotations

import numpy as np

from cablecheck.build.cableplan import CablePlan
from cablecheck.build.obstacles import Obstacles
from cablecheck.build.startframes import Frames
from cablecheck.checker.arrays import all_columns
from cablecheck.checker.shapes import segment_signed_distance, signed_distance
from cablecheck.scene.errors import fmt
from cablecheck.scene.records import Scene


def route_warnings(scene: Scene, frames: Frames, meshes: dict, plans: list[CablePlan]) -> tuple[str, ...]:
    """One sentence per (cable, part) whose routed centreline lies inside the part at t = 0."""
    if "cable-structure" not in scene.effects.contact or not plans:
        return ()
    obstacles = Obstacles(scene, frames, meshes)
    zone = scene.check.attach_zone
    unit = scene.units
    out = []
    for i, plan in enumerate(plans):
        pts = np.asarray(plan.routed, float)
        s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(pts, axis=0), axis=1))])
        radius = plan.cable.radius
        held = np.array([s[h.vertex] for h in plan.held])
        free = np.ones(len(pts), bool) if not len(held) else \
            (np.abs(s[:, None] - held[None, :]) > zone * radius).all(axis=1)
        lo, hi = pts.min(axis=0), pts.max(axis=0)
        near = np.flatnonzero(all_columns((obstacles.lo <= hi) & (obstacles.hi >= lo)))
        free_el = free[:-1] & free[1:]
        for k in near.tolist():     # the parts whose boxes meet the cable's: a few, once per scene
            local = (pts - obstacles.pos[k]) @ obstacles.rot[k]
            shape = obstacles.shape(k)
            d = signed_distance(shape, local, limit=0.0)[0]
            # and between them: an element through a plate or a ring has both ends outside it; the
            # distance changes no faster than along the element, so only one as long as its ends'
            # distances together can reach the part
            d_el, t_el = np.zeros(len(pts) - 1), np.zeros(len(pts) - 1)
            maybe = np.flatnonzero(free_el & (d[:-1] + d[1:] <= (1.0 + 1e-9) * np.diff(s)))
            if len(maybe):
                d_el[maybe], t_el[maybe] = segment_signed_distance(shape, local[maybe], local[maybe + 1])
            inside, crossing = (d < 0.0) & free, (d_el < 0.0) & free_el
            if not inside.any() and not crossing.any():
                continue
            s_el = s[:-1] + t_el * np.diff(s)
            where = np.concatenate([s[inside], s_el[crossing]])
            deepest = float(-min(d[inside].min(initial=0.0), d_el[crossing].min(initial=0.0)))
            # nothing is stepped without dynamics: the route is checked where it lies
            # a contact pushes it out unless the cable is threaded through the part (up through a
            # disc to a clamp on its top): then it stays, a hard static event of the run
            then = ("the simulation starts from it (contact pushes it out where it can; threaded through "
                    "the part, it stays: a hard static event)" if scene.effects.dynamics else
                    "nothing is simulated (dynamics = false): it is checked there, a hard contact")
            out.append(f"cables[{i}] {plan.cable.name!r}: its initial shape runs through part "
                       f"{obstacles.names[k]!r} from s = {fmt(where.min() / scene.scale)} to "
                       f"{fmt(where.max() / scene.scale)} {unit} along the cable (up to "
                       f"{deepest / scene.scale:.3g} {unit} inside); {then}: route it "
                       "around the part (via points, clips)")
    return tuple(out)
