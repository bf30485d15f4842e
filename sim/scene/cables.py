"""`[[cables]]`: a cable's ends, clips, route and material, checked against
the route at t = 0 and the limits of the simulation's elements.

The route (start, via..., end, or `points`) is taken in world coordinates
at t = 0 from the body frames the reader holds (`cablecheck.scene.frames`), so
cables are read after bodies, parts and motions. Nothing here chooses the
elements (`cablecheck.build.stages` does when `segments` is absent).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from cablecheck.scene.allow import covers, unknown_name
from cablecheck.scene.errors import SceneError, describe, fmt
from cablecheck.scene.format import (
    ANCHOR_KEYS,
    CABLE_KEYS,
    DEFAULT_DAMPING,
    DEFAULT_DENSITY,
    DEFAULT_YOUNG,
    DEGENERATE,
    POINTS_LENGTH_TOLERANCE,
    ROUTE_TOLERANCE,
    SELF_CONTACT_ELEMENT,
    ZERO3,
    Hold,
)
from cablecheck.scene.frames import from_world, to_world
from cablecheck.scene.parts import body_ref
from cablecheck.scene.reader import Reader
from cablecheck.scene.records import Anchor, CableDef, Scene


def read_anchor(r: Reader, value: Any, where: str, with_pos: bool = True) -> Anchor:
    """A cable end or clip: the body it rides on, its position there, how it holds."""
    t = r.table(value, where, ANCHOR_KEYS if with_pos else ("body", "hold", "tangent", "part"))
    hold = Hold(r.string(t.get("hold", "clamp"), f"{where}.hold",
                         tuple(h.value for h in Hold)))
    return Anchor(body=body_ref(r, t.get("body", "world"), f"{where}.body"),
                  pos=r.position(t.get("pos", [0, 0, 0]), f"{where}.pos")
                  if with_pos else ZERO3, hold=hold, parts=read_fastened(r, t, where, hold),
                  tangent=read_tangent(r, t, where, hold))


def read_tangent(r: Reader, t: dict, where: str, hold: Hold) -> tuple[float, float, float] | None:
    """An anchor's `tangent`: the direction a clamp holds the cable in, in its
    body's frame, as a unit vector (any length but zero is accepted); None
    when absent (the route's direction, `cablecheck.build.cableplan`)."""
    if "tangent" not in t:
        return None
    key = f"{where}.tangent"
    if hold != Hold.CLAMP:
        raise r.error(key, f"a {'pinned point turns freely' if hold == Hold.PIN else 'free end is not held'}, "
                           "so it holds no direction (use hold = \"clamp\", or drop tangent)")
    v = np.array(r.vector(t["tangent"], key), float)
    if not np.abs(v).max() > 0.0:
        raise r.error(key, "must not be the zero vector (it gives the cable's direction)")
    v /= np.abs(v).max()  # first, so tiny components do not underflow in the norm
    return tuple(float(x) for x in v / np.linalg.norm(v))


def read_fastened(r: Reader, t: dict, where: str, hold: Hold) -> tuple[str, ...]:
    """An anchor's `part`: one part name or assembly path, or a list of them
    (names checked against the parts by `check_fastened_names`)."""
    if "part" not in t:
        return ()
    value = t["part"]
    key = f"{where}.part"
    if hold == Hold.FREE:
        raise r.error(key, "a free end holds nothing, so it is fastened to no part "
                           "(use hold = \"clamp\" or \"pin\", or drop part)")
    if isinstance(value, list):
        if not value:
            raise r.error(key, "expected a part name or a non-empty list of them, got an empty list")
        names = tuple(r.name(v, f"{key}[{i}]") for i, v in enumerate(value))
    else:
        names = (r.name(value, key),)
    return tuple(dict.fromkeys(names))


def read_cable(r: Reader, value: dict, where: str, dynamics: bool = True) -> CableDef:
    """A `[[cables]]` entry, its route at t = 0 checked against length and elements."""
    t = r.table(value, where, CABLE_KEYS, ("name", "radius"))
    name = r.name(t["name"], f"{where}.name")
    radius = r.length(t["radius"], f"{where}.radius", positive=True)
    if "points" in t:
        if "via" in t:
            raise r.error(f"{where}.via", "not allowed with 'points' (the points "
                                          "are the whole route)")
        points = r.point_list(t["points"], f"{where}.points")
        if len(points) < 2:
            raise r.error(f"{where}.points", f"needs at least 2 points, "
                                             f"got {len(points)}")
        route = points
        ends = []
        for key, point in (("start", points[0]), ("end", points[-1])):
            if key in t and isinstance(t[key], dict) and "pos" in t[key]:
                raise r.error(f"{where}.{key}.pos",
                              f"not allowed with 'points': the {key} is "
                              f"points[{0 if key == 'start' else -1}] (give only body)")
            anchor = read_anchor(r, t.get(key, {}), f"{where}.{key}", with_pos=False)
            ends.append(Anchor(anchor.body, from_world(r.frames, anchor.body, point), anchor.hold,
                               anchor.parts, anchor.tangent))
        start, end = ends
        via = np.zeros((0, 3))
        via.setflags(write=False)
        labels = [f"{where}.points[{i}]" for i in range(len(points))]
    else:
        for key in ("start", "end"):
            if key not in t:
                raise r.error(f"{where}.{key}", "missing (required unless "
                                                "'points' gives the route)")
        start = read_anchor(r, t["start"], f"{where}.start")
        end = read_anchor(r, t["end"], f"{where}.end")
        via = r.point_list(t.get("via", []), f"{where}.via")
        points = None
        route = np.vstack([to_world(r.frames, start), via, to_world(r.frames, end)])
        route.setflags(write=False)
        labels = ([f"{where}.start"] + [f"{where}.via[{i}]" for i in range(len(via))]
                  + [f"{where}.end"])
    steps = np.linalg.norm(np.diff(route, axis=0), axis=1)
    short = np.flatnonzero(steps <= DEGENERATE * radius)
    if len(short):
        i = short[0]
        raise r.error(labels[i + 1], f"coincides with the route point before it "
                                     f"({labels[i].rsplit('.', 1)[-1]} at t = 0): "
                                     "a zero-length route segment")
    route_length = float(steps.sum())
    length = None
    if "length" in t:
        length = r.length(t["length"], f"{where}.length", positive=True)
        if length < route_length * (1 - ROUTE_TOLERANCE):
            along = ("along points" if points is not None
                     else "from start through via to end")
            raise r.error(f"{where}.length",
                          f"{fmt(length / r.scale)} {r.unit_name()} is shorter than "
                          f"the route ({fmt(route_length / r.scale)} {r.unit_name()} "
                          f"{along} at t = 0)")
        if (points is not None and not dynamics
                and length > route_length * (1 + POINTS_LENGTH_TOLERANCE)):
            raise r.error(f"{where}.length",
                          f"{fmt(length / r.scale)} {r.unit_name()} is longer than the "
                          f"route along points ({fmt(route_length / r.scale)} "
                          f"{r.unit_name()}): with dynamics = false a points route is "
                          "checked as given, so the cable's length is the route's "
                          "(omit length)")
    clips = t.get("clips", [])
    if not isinstance(clips, list):
        raise r.error(f"{where}.clips", f"expected an array of tables, "
                                        f"got {describe(clips)}")
    clips = tuple(read_anchor(r, c, f"{where}.clips[{i}]") for i, c in enumerate(clips))
    segments = None
    if "segments" in t:
        segments = r.integer(t["segments"], f"{where}.segments", 2)
        slack = length is not None and length > route_length * (1 + ROUTE_TOLERANCE)
        need = len(route) - 1 + len(clips) + (1 if slack else 0)
        if segments < need:
            raise r.error(f"{where}.segments",
                          f"{segments} elements cannot have all {len(route)} route points"
                          f"{' and the clips' if clips else ''} as vertices"
                          f"{' and droop to the length' if slack else ''}: give at least "
                          f"{need} (or omit segments)")
        element = (length or route_length) / segments
        if "self" in r.effects_read.contact and element <= SELF_CONTACT_ELEMENT * radius:
            most = max(2, math.ceil((length or route_length)
                                    / (SELF_CONTACT_ELEMENT * radius)) - 1)
            raise r.error(f"{where}.segments",
                          f"{segments} elements are {fmt(element / r.scale)} "
                          f"{r.unit_name()} long; with 'self' in effects.contact "
                          f"elements two apart along a straight cable would touch "
                          f"unless longer than {fmt(SELF_CONTACT_ELEMENT)} radii "
                          f"({fmt(SELF_CONTACT_ELEMENT * radius / r.scale)} "
                          f"{r.unit_name()}); use at most {most}")
    bend = (r.length(t["min_bend_radius"], f"{where}.min_bend_radius", positive=True)
            if "min_bend_radius" in t else None)
    return CableDef(
        name=name, radius=radius, start=start, end=end, via=via, points=points,
        length=length, clips=clips, segments=segments,
        young=r.number(t.get("young", DEFAULT_YOUNG), f"{where}.young", positive=True),
        density=r.number(t.get("density", DEFAULT_DENSITY), f"{where}.density",
                         positive=True),
        min_bend_radius=bend, route=route,
        twist_stiffness=(r.number(t["twist_stiffness"], f"{where}.twist_stiffness",
                                  positive=True) if "twist_stiffness" in t else None),
        damping=_damping(r, t.get("damping", DEFAULT_DAMPING), f"{where}.damping"),
        friction=(r.number(t["friction"], f"{where}.friction", nonnegative=True)
                  if "friction" in t else None))


def anchors_of(cable: CableDef) -> list[tuple[str, Anchor]]:
    """A cable's anchors with their key names: ("start", ...), ("clips[i]", ...), ("end", ...)."""
    return ([("start", cable.start)] + [(f"clips[{i}]", c) for i, c in enumerate(cable.clips)]
            + [("end", cable.end)])


def check_fastened_names(scene: Scene, part_names, bodies=()) -> None:
    """Raise SceneError when a cable end's or clip's `part` covers none of
    `part_names` (a name or an assembly path prefix). `bodies`: at load
    time, the mjcf model's bodies, whose geoms' part names are the
    builder's: a name beginning with one passes then and is checked again
    against the built parts."""
    names = list(part_names)
    bodies = set(bodies)
    for i, cable in enumerate(scene.cables):
        for key, anchor in anchors_of(cable):
            for k, name in enumerate(anchor.parts):
                if covers(name, names) or (bodies and name.split("/")[0] in bodies):
                    continue
                at = f"cables[{i}].{key}.part" + (f"[{k}]" if len(anchor.parts) > 1 else "")
                raise SceneError(scene.path, at, unknown_name(name, names, "part or assembly path"))


def _damping(r: Reader, value, where: str) -> float:
    """A cable's `damping`: the damping ratio of its first bending mode, at least 0 and below 1."""
    damping = r.number(value, where, nonnegative=True)
    if damping >= 1.0:
        raise r.error(where, f"must be below 1, got {fmt(damping)}: it is the damping ratio of the cable's "
                             "first bending mode, and at 1 (critical) that mode no longer swings, so no ratio "
                             "at or past it can be set (docs/physics.md, Damping)")
    return damping
