"""Where each cable lies at t = 0 and which of its vertices are held.

A cable's routed shape (`cablecheck.build.route`) has every route point and clip as a
vertex and droops to make up the cable's length, clear of the parts it
collides with when those are handed in (`cablecheck.build.obstacles`). A clamp holds a
short edge (`clamp_edges`) along its `tangent`, else the route's direction
(`route_direction`), a pin one vertex, a free anchor nothing. The
rest shape is straight along the route's first element: MuJoCo's rod keeps
as rest curvature whatever bend its qpos0 has, so the cable is built
straight and put into the routed shape through qpos, and bending energy is
stored where a real cable would have it.

This module is numpy on the scene alone: it neither builds nor reads a
MuJoCo model (see `cablecheck.build.mjspec`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from cablecheck.build.built import Attachment, CableModel
from cablecheck.build.route import initial_shape, polyline_length, route_lengths, run_elements
from cablecheck.build.startframes import Frames
from cablecheck.scene.errors import SceneError
from cablecheck.scene.format import ROUTE_TOLERANCE, Hold
from cablecheck.scene.records import CableDef, Scene

if TYPE_CHECKING:
    from cablecheck.build.obstacles import Obstacles


CLAMP_EDGE = 0.05
"""Length of the held edge a clamp puts at its end or clip, as a fraction of
the cable's element length (see `clamp_edges`): short enough that the rigid
piece it adds changes a cantilever's deflection by about 4 x 0.05 / N."""


def default_segments(length: float, radius: float) -> int:
    """Elements for a cable: about 25 mm each, at least 4 radii, 8 to 80 elements.

    Elements longer than 2 r keep MuJoCo's self-collision from touching
    elements two apart along a straight cable (SPEC); 80 bounds the cost of
    long cables (a flex's cost per step grows with its points)."""
    target = max(0.025, 4.0 * radius)
    return int(np.clip(round(length / target), 8, 80))


@dataclass(frozen=True)
class Held:
    """One held vertex: which end or clip, the body, the vertex, the hold kind,
    the window's name ("start", "end", "clip N": the cable's Nth clip, from 1,
    as listed in the scene) and the parts the scene says it is fastened to."""

    kind: str      # "start", "end" or "clip"
    body: str
    vertex: int
    hold: Hold
    window: str = ""
    parts: tuple[str, ...] = ()


@dataclass
class CablePlan:
    cable: CableDef
    routed: np.ndarray    # (n, 3) routed shape at t = 0, model coordinates
    straight: np.ndarray  # (n, 3) rest shape: straight along the first element
    held: list[Held]     # held vertices, by vertex


def _closest_arc(route: np.ndarray, point: np.ndarray) -> tuple[int, float]:
    """(segment index, arc length) of the point of `route` closest to `point`."""
    a, b = route[:-1], route[1:]
    ab = b - a
    denom = np.maximum(np.einsum("ij,ij->i", ab, ab), 1e-300)
    t = np.clip(np.einsum("ij,ij->i", point - a, ab) / denom, 0.0, 1.0)
    dist = np.linalg.norm(a + t[:, None] * ab - point, axis=1)
    k = int(np.argmin(dist))
    seglen = np.sqrt(denom)
    return k, float(seglen[:k].sum() + t[k] * seglen[k])


def plan_cable(cable: CableDef, frames: Frames, where: str, scene: Scene,
                depth: Obstacles | None = None, shaped: bool = True) -> CablePlan | None:
    """Routed shape through start, via or points, clips and end, with the cable's length
    (`shaped` False: only the checks that raise SceneError, no shape, None).

    Every waypoint (start, each via or given point, each clip, end) is a
    vertex (`cablecheck.build.route`): each clip is inserted where the route passes
    closest to it, the elements are shared among the straight runs between
    waypoints in proportion to their lengths (`segments`, or the default
    element count raised to one element per run; with slack and no run of
    two elements, two per run), and the runs droop to make up the length,
    away from the parts the cable collides with when `depth` is given."""
    route = np.asarray(cable.route if cable.route is not None else cable.points, float) - frames.origin
    route[0] = frames.to_world(cable.start.body, cable.start.pos)
    route[-1] = frames.to_world(cable.end.body, cable.end.pos)
    clips = []
    for n, clip in enumerate(cable.clips, 1):
        point = frames.to_world(clip.body, clip.pos)
        k, s = _closest_arc(route, point)
        clips.append((s, k, point, clip, f"clip {n}"))
    clips.sort(key=lambda c: c[0])
    # Insert clip points (from the last, so earlier segment indices stay valid).
    for s, k, point, clip, _ in sorted(clips, key=lambda c: (c[1], c[0]), reverse=True):
        route = np.insert(route, k + 1, point, axis=0)
    keep = np.concatenate([[True], np.linalg.norm(np.diff(route, axis=0), axis=1) > 0])
    route = route[keep]
    runs = np.linalg.norm(np.diff(route, axis=0), axis=1)
    total = float(runs.sum())
    if cable.length is not None and cable.length < total * (1.0 - ROUTE_TOLERANCE):
        raise SceneError(scene.path, f"{where}.length",
                         f"{cable.length / scene.scale:.6g} {scene.units} is shorter than the route through "
                         f"its clips at t = 0 ({total / scene.scale:.6g} {scene.units}); lengthen the cable "
                         "or move the clips")
    length = max(cable.length if cable.length is not None else total, total)   # within the tolerance: taut
    slack = length > total * (1.0 + 1e-9)
    if cable.segments is not None:
        if cable.segments < len(runs) + (1 if slack else 0):
            need = len(runs) + (1 if slack else 0)
            raise SceneError(scene.path, f"{where}.segments",
                             f"{cable.segments} elements cannot pass through all {len(runs) + 1} "
                             f"route points and clips{' and droop to the length' if slack else ''}; "
                             f"give at least {need}")
        counts = run_elements(runs, cable.segments)
    else:
        counts = run_elements(runs, max(default_segments(length, cable.radius), len(runs)))
        if slack and counts.max() < 2:
            counts = np.full(len(runs), 2)
    measure = None if (depth is None or not slack) else depth.measure(cable.radius)
    cuts = [int(np.argmin(np.linalg.norm(route - c[2], axis=1))) for c in clips]
    clip_vertices = np.concatenate([[0], np.cumsum(counts)])[cuts]
    waypoints = [0] + cuts + [len(route) - 1]
    anchors = ([(0, "start", cable.start, "start")]
               + [(int(v), "clip", c[3], c[4]) for c, v in zip(clips, clip_vertices)]
               + [(int(counts.sum()), "end", cable.end, "end")])
    given = {}
    for w, (_, _, anchor, _) in zip(waypoints, anchors):
        if anchor.hold == Hold.CLAMP and anchor.tangent is not None:
            given[w] = np.asarray(frames.poses[anchor.body][1], float) @ np.asarray(anchor.tangent, float)
    directions = [given.get(w, route_direction(route, w)) for w in waypoints]
    anchors = [a + (t,) for a, t in zip(anchors, directions)]
    # the droop leaves a clamp along the run's chord where that is the
    # clamp's direction: at a clip on a corner (the bisector) it keeps the
    # half sine, as a clamp given another direction bends the run to it
    clamped = np.zeros(len(route), bool)
    for w, (_, _, anchor, _, t) in zip(waypoints, anchors):
        if anchor.hold == Hold.CLAMP:
            ahead = route[min(w + 1, len(route) - 1)] - route[min(w, len(route) - 2)]
            behind = route[max(w, 1)] - route[max(w - 1, 0)]
            clamped[w] = w in given or all(np.dot(t, c) > (1.0 - 1e-12) * np.linalg.norm(c) for c in (ahead, behind))
    # the route leaving its clamps along given tangents is longer than its
    # chords; a `points` route is the centreline as given: its held edges
    # alone turn to the tangents
    if cable.points is not None:
        given = {}
    needed = float(route_lengths(route, counts, given).sum())
    if cable.length is None:
        length = max(length, needed)
    elif length < needed * (1.0 - 1e-9):
        raise SceneError(scene.path, f"{where}.length",
                         f"{length / scene.scale:.6g} {scene.units} is shorter than the route leaving "
                         f"its clamps along their tangents ({needed / scene.scale:.6g} {scene.units}); "
                         "lengthen the cable or change the tangents")
    if not shaped:      # every SceneError a plan raises is above
        return None
    droop = length
    for _ in range(6):
        # A clamp's held edge along its tangent leaves the drooped shape by a
        # little (most at a clip on a corner, or a coarse run drooping
        # steeply); with slack the next pass droops that much less, so the
        # cable keeps its length (each pass to second order in the clamp edge).
        drooped = initial_shape(route, droop, counts, depth=measure, clamped=clamped, tangents=given)
        shortest = float(np.linalg.norm(np.diff(drooped, axis=0), axis=1).min())
        routed, held = clamp_edges(drooped, anchors, CLAMP_EDGE * shortest)
        excess = polyline_length(routed) - length
        if not (slack or given) or abs(excess) <= 1e-12 * length or droop - excess < needed:
            break
        droop -= excess
    if scene.effects.dynamics:      # nothing pushes a cable that is not simulated: the route as given
        routed = imperfect(routed, [h.vertex for h in held])
    seg = np.linalg.norm(np.diff(routed, axis=0), axis=1)
    tangent = (routed[1] - routed[0]) / seg[0]
    s = np.concatenate([[0.0], np.cumsum(seg)])
    straight = routed[0] + s[:, None] * tangent[None, :]
    straight[2:] += STRAIGHT_KINK * (s[2:] - s[1])[:, None] * _side(tangent)[None, :]
    return CablePlan(cable, routed, straight, held)


STRAIGHT_KINK = 1e-6
"""Radians: the rest shape turns by this much at its second vertex.

The rest shape runs along the first element; a slack cable clamped at both
ends without via points leaves along its chord, so its rest line runs
through its end point and on past it. Compiled on that line and then held
where it is routed (`cablecheck.build.mjspec.move_held`), the model's shape
at qpos0 folds exactly back at the end, and MuJoCo then keeps no twist
state for the rod at all (`mjData.plastic` stays 0: a turned end winds
nothing; measured on a turntable's slack cable, and on drawer.toml). Any
turn off the line avoids it (1e-6 rad did); MuJoCo takes a rest shape bent
under 1e-4 rad at a vertex as straight (rest curvature 0), so this one is
still straight at rest. Deterministic: the same every run."""


def _side(axis: np.ndarray) -> np.ndarray:
    """A unit vector square to unit `axis`: towards world -z, or +x where `axis` is vertical."""
    side = np.array([0.0, 0.0, -1.0]) - (-axis[2]) * axis
    if np.linalg.norm(side) < 1e-6:
        side = np.array([1.0, 0.0, 0.0]) - axis[0] * axis
    return side / np.linalg.norm(side)


IMPERFECTION = 1e-6
"""Amplitude of the half sine given to a perfectly straight run between two
held vertices, as a fraction of the run's length (see `imperfect`)."""


def imperfect(routed: np.ndarray, held: list[int]) -> np.ndarray:
    """`routed` with every perfectly straight run between two held vertices
    bowed by a half sine of `IMPERFECTION` of its length, towards world -z
    (gravity's side) square to the run, or +x where the run is vertical.

    A perfectly straight rod pushed along its length is a symmetric
    equilibrium: every force square to it is exactly 0, so the simulated
    rod never leaves it and carries any load by shortening its edges
    (compressed 1 to 5 % with gravity off it carried 220 times its Euler
    load, 4400 N for 20 N). A real rod is never perfectly straight; this is
    its imperfection, the same every run (deterministic, not random). A
    run is perfectly straight when its vertices lie within `IMPERFECTION`
    of its length of its chord; runs already bent, and runs to a free end
    (which nothing pushes), are left as they are, and so is every cable of
    a scene without dynamics (`plan_cable`). It lengthens the run by about
    2.5e-12 of its length."""
    routed = np.array(routed, float)
    held = sorted(set(int(h) for h in held))
    for a, b in zip(held, held[1:]):
        if b - a < 2:
            continue
        chord = routed[b] - routed[a]
        span = float(np.linalg.norm(chord))
        if span <= 0.0:
            continue
        axis = chord / span
        rel = routed[a + 1:b] - routed[a]
        off = rel - np.outer(rel @ axis, axis)
        if np.linalg.norm(off, axis=1).max() > IMPERFECTION * span:
            continue
        side = _side(axis)
        x = np.clip((rel @ axis) / span, 0.0, 1.0)
        routed[a + 1:b] += IMPERFECTION * span * np.sin(np.pi * x)[:, None] * side[None, :]
    return routed


def route_direction(route: np.ndarray, w: int) -> np.ndarray:
    """The route's direction at waypoint `w` (of travel, start to end): its
    run's chord at an end; at a clip the bisector of the chords either side
    (so a route turning at a clip bends by half the turn on either side of
    the clamp), the outgoing chord where the route turns back on itself."""
    out = route[min(w + 1, len(route) - 1)] - route[min(w, len(route) - 2)]
    out = out / np.linalg.norm(out)
    if w == 0 or w == len(route) - 1:
        return out
    into = route[w] - route[w - 1]
    bisector = out + into / np.linalg.norm(into)
    if np.linalg.norm(bisector) > 1e-9 and np.dot(bisector, out) > 1e-9 * np.linalg.norm(bisector):
        return bisector / np.linalg.norm(bisector)
    return out


def clamp_edges(routed: np.ndarray, anchors: list[tuple],
                 edge: float) -> tuple[np.ndarray, list[Held]]:
    """Insert a short held edge at every clamp; list the held vertices.

    A clamp holds position and tangent. In MuJoCo's discrete elastic rod
    the bending energy of a vertex stands for the rod within half an element
    either side, so holding a whole element (its two vertices) leaves the
    first half element rigid and clamps the rod half an element too far in:
    measured, a cantilever deflected 1.6 / N too little with N elements.
    Instead a clamp holds an edge of length `edge` (CLAMP_EDGE of an
    element) along the clamp's tangent at the held point, inside the cable:
    the next vertex's bending then stands for the rod from the clamp on.
    At the end the edge leads into the end point, at a clip it leaves the
    clip point. The tangent is an anchor's fifth item (unit, of travel from
    start to end: the given `tangent` or the route's, `route_direction`);
    without one, the drooped shape's: its end elements, at a clip the bisector
    of its corner there. A pin holds the one vertex, a free anchor
    nothing."""
    points = [p for p in routed]
    held: list[Held] = []
    shift = 0
    for vertex, kind, anchor, window, *direction in anchors:
        tangent = direction[0] if direction else None
        v = vertex + shift
        if anchor.hold == Hold.FREE:
            continue
        hold = (kind, anchor.body)
        named = dict(hold=anchor.hold, window=window, parts=anchor.parts)
        if anchor.hold == Hold.PIN:
            held.append(Held(*hold, v, **named))
            continue
        if kind == "end":
            t = points[v] - points[v - 1] if tangent is None else tangent
            points.insert(v, points[v] - edge * t / np.linalg.norm(t))
            held += [Held(*hold, v, **named), Held(*hold, v + 1, **named)]
        else:
            out = points[v + 1] - points[v]
            t = out / np.linalg.norm(out)
            if kind == "clip":  # along the route's bisector, so the route's corner splits both sides
                into = points[v] - points[v - 1]
                bisector = t + into / np.linalg.norm(into)
                if np.linalg.norm(bisector) > 1e-9 and np.dot(bisector, out) > edge * np.linalg.norm(bisector):
                    t = bisector / np.linalg.norm(bisector)
            if tangent is not None:
                t = tangent / np.linalg.norm(tangent)
            points.insert(v + 1, points[v] + edge * t)
            held += [Held(*hold, v, **named), Held(*hold, v + 1, **named)]
        shift += 1
    return np.array(points), held


def clamped_clips(held) -> dict[str, list[int]]:
    """Each clamped clip's window ("clip N") -> its held vertices (the two of
    the short edge `clamp_edges` puts there), from a cable's `Held` or
    `cablecheck.build.built.Attachment` records alike."""
    clips: dict[str, list[int]] = {}
    for h in held:
        if h.kind == "clip" and h.hold == Hold.CLAMP:
            clips.setdefault(h.window, []).append(h.vertex)
    return clips


def has_slack(cable: CableDef) -> bool:
    """The cable is longer than its route (clips aside), so its initial shape droops."""
    route = np.asarray(cable.route if cable.route is not None else cable.points, float)
    total = float(np.linalg.norm(np.diff(route, axis=0), axis=1).sum())
    return cable.length is not None and cable.length > total * (1.0 + 1e-9)


def cable_model(plan: CablePlan, flex_id: int, vert_adr: int, origin: np.ndarray) -> CableModel:
    """The built cable of `plan`, whose flex is `flex_id` with its vertices from
    `vert_adr` on; `origin`: the model's origin in the scene's world."""
    c = plan.cable
    n = len(plan.routed)
    seg = np.linalg.norm(np.diff(plan.straight, axis=0), axis=1)
    s = np.concatenate([[0.0], np.cumsum(seg)])
    attachments = [Attachment(h.kind, h.body, h.vertex, float(s[h.vertex]), h.hold, h.window, h.parts)
                   for h in plan.held]
    return CableModel(c.name, c.radius, flex_id, vert_adr, n, float(s[-1]), float(seg.max()),
                      plan.routed + origin, tuple(sorted(attachments, key=lambda a: a.vertex)),
                      c.min_bend_radius, s, n - 1 - sum(h.hold == Hold.CLAMP for h in plan.held) // 2)
