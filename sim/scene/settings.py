"""The scene-wide tables: `[effects]`, `[check]` and `[limits]`, and the
check of a scene's sizes against its limits.

`[scene]` itself is read by `cablecheck.scene.load`, which calls these in order;
nothing here reads parts, cables or motions (only their sizes, in
`within_limits`).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from cablecheck.scene.errors import describe, fmt
from cablecheck.scene.format import (
    CHECK_KEYS,
    DEFAULT_CLEARANCE,
    EFFECTS_KEYS,
    INTERACTIONS,
    LIMIT_KEYS,
    METHODS,
)
from cablecheck.scene.reader import Reader
from cablecheck.scene.records import CableDef, CheckSettings, Effects, Limits


def read_effects(r: Reader, value: Any) -> Effects:
    """The `[effects]` table."""
    t = r.table(value, "effects", EFFECTS_KEYS)
    contact = t.get("contact", [])
    if not isinstance(contact, list):
        raise r.error("effects.contact", f"expected an array of strings, "
                                         f"got {describe(contact)}")
    names = frozenset(r.string(c, f"effects.contact[{i}]", INTERACTIONS)
                      for i, c in enumerate(contact))
    return Effects(dynamics=r.boolean(t.get("dynamics", True), "effects.dynamics"),
                   gravity=r.boolean(t.get("gravity", True), "effects.gravity"),
                   contact=names)


def read_check(r: Reader, value: Any) -> CheckSettings:
    """The `[check]` table (clearance in metres)."""
    t = r.table(value, "check", CHECK_KEYS)
    clearance = (r.length(t["clearance"], "check.clearance", nonnegative=True)
                 if "clearance" in t else DEFAULT_CLEARANCE)
    return CheckSettings(
        method=r.string(t.get("method", "points"), "check.method", METHODS),
        spacing=r.number(t.get("spacing", 2.0), "check.spacing", positive=True),
        clearance=clearance,
        every=r.integer(t.get("every", 1), "check.every", 1),
        validate=r.boolean(t.get("validate", True), "check.validate"),
        attach_zone=r.number(t.get("attach_zone", 5.0), "check.attach_zone",
                             nonnegative=True),
        attach_links=r.integer(t.get("attach_links", 0), "check.attach_links", 0))


def read_limits(r: Reader, value: Any) -> Limits:
    """The `[limits]` table."""
    t = r.table(value, "limits", LIMIT_KEYS)
    return Limits(**{k: r.integer(t[k], f"limits.{k}", 1) for k in LIMIT_KEYS if k in t})


def within_limits(r: Reader, limits: Limits, seconds: float, timestep: float,
                  check: CheckSettings, cables: tuple[CableDef, ...]) -> None:
    """Refuse sizes above `limits`, naming the key, the size and how to raise the limit."""
    steps = seconds / timestep
    if steps > limits.steps:
        raise r.error("scene.duration", f"{fmt(seconds)} s (settle and duration) at a timestep "
                      f"of {fmt(timestep)} s is {steps:.3g} steps, above the limit of "
                      f"{limits.steps:,} (raise it with [limits] steps = ...)")
    for i, c in enumerate(cables):
        if c.segments is not None and c.segments > limits.elements:
            raise r.error(f"cables[{i}].segments", f"{c.segments:,} elements, above the limit "
                          f"of {limits.elements:,} per cable (raise it with [limits] "
                          "elements = ...)")
    if check.method != "points" or not cables:
        return
    lengths = np.array([c.length or c.route_length for c in cables])
    radii = np.array([c.radius for c in cables])
    points = lengths / (check.spacing * radii) + 1.0
    if points.sum() > limits.points:
        k = int(np.argmax(points))
        raise r.error(f"cables[{k}].radius", f"the cables need {points.sum():.3g} discrete points "
                      f"per check ({points[k]:.3g} for {cables[k].name!r}: "
                      f"{fmt(lengths[k] / r.scale)} {r.unit_name()} at a spacing of "
                      f"{fmt(check.spacing)} radii of {fmt(radii[k] / r.scale)} {r.unit_name()}), "
                      f"above the limit of {limits.points:,}; check the radius and units "
                      "(raise the limit with [limits] points = ...)")
