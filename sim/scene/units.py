"""Sizes that make no sense in the scene's declared units: refused or warned about, with the likely unit.

A scene in metres written with millimetre numbers (a 4 m hose radius, a 650
m harness in a 300 m cabinet) runs to nonsense; a millimetre scene written in
metres (a 0.004 mm radius) fails inside MuJoCo on masses below its least
value. Each check here compares one kind of size, in metres, with what
cables and cells are made of, and names the key, the value as written and
what the same number would mean in the other unit:

- refused (`SceneError`, exit status 2) where no run can be meaningful:
  a cable radius below :data:`RADIUS_REFUSE`\\[0] or above
  :data:`RADIUS_REFUSE`\\[1], a cable shorter than :data:`LENGTH_REFUSE`\\[0]
  or longer than :data:`LENGTH_REFUSE`\\[1], a part or a motion spanning
  more than :data:`SPAN_REFUSE`;
- warned about (`unit_warnings`) where a run is possible but unlikely to be
  what was meant: a radius or length outside the everyday ranges
  (:data:`RADIUS_USUAL`, :data:`LENGTH_USUAL`), a part or a motion spanning
  more than :data:`SPAN_USUAL`.

Positions are not judged: a cell far from its world origin is legitimate.
This module reads a loaded scene's sizes and nothing else; it does not build
or place anything (a route through a part is `cablecheck.build.routecheck`'s).
"""

from __future__ import annotations

import numpy as np

from cablecheck.scene.errors import SceneError, fmt
from cablecheck.scene.records import Scene

RADIUS_REFUSE = (1e-5, 1.0)
"""Cable radii outside this (metres) are refused: finer than any wire, or a
radius no hose has (MuJoCo cannot simulate the first: masses below its
least value)."""

RADIUS_USUAL = (5e-5, 0.15)
"""Cable radii outside this (metres) are warned about."""

LENGTH_REFUSE = (1e-3, 1e4)
"""Cable lengths outside this (metres) are refused."""

LENGTH_USUAL = (0.01, 2e3)
"""Cable lengths outside this (metres) are warned about."""

SPAN_REFUSE = 1e4
"""A part or a motion spanning more than this (metres) is refused (a plane
is infinite anyway: its drawing size is not judged)."""

SPAN_USUAL = 200.0
"""A part or a motion spanning more than this (metres) is warned about."""


def _other(value_m: float, scene: Scene) -> str:
    """What the number as written would be in the other unit."""
    written = value_m / scene.scale
    if scene.units == "m":
        return f"{fmt(written)} mm = {fmt(written / 1000)} m: did you mean units = \"mm\"?"
    return f"{fmt(written)} m = {fmt(written * 1000)} mm: did you mean units = \"m\"?"


def _likely(value_m: float, lo: float, hi: float, scene: Scene) -> str:
    """The hint for a size outside [lo, hi]: the other unit when it fits, else none."""
    other = value_m * (1000.0 if scene.units == "mm" else 0.001)
    return f"; as written in the other unit: {_other(value_m, scene)}" if lo <= other <= hi else ""


def _sizes(scene: Scene) -> list[tuple[str, float, float, float]]:
    """(key, size in metres, usual limit, refused limit) for every size judged
    against a most: part extents and motion travel."""
    out = []
    for i, p in enumerate(scene.parts):
        if p.shape in ("plane", "mesh") or not p.size:
            continue
        out.append((f"parts[{i}].size", 2.0 * max(p.size), SPAN_USUAL, SPAN_REFUSE))
    for i, m in enumerate(scene.motions):
        pos = np.asarray(m.trajectory.body_pos, float)
        if pos.size:
            travel = float((pos.max(axis=0) - pos.min(axis=0)).max())
            out.append((f"motion[{i}].keys", travel, SPAN_USUAL, SPAN_REFUSE))
    return out


def check_units(scene: Scene) -> tuple[str, ...]:
    """Raise SceneError for the first size no run can make sense of; return
    the warnings for sizes unusual in the scene's units (key, value, the
    likely unit)."""
    warnings = []
    unit = scene.units
    for i, c in enumerate(scene.cables):
        key = f"cables[{i}].radius"
        r = c.radius
        if not RADIUS_REFUSE[0] <= r <= RADIUS_REFUSE[1]:
            raise SceneError(scene.path, key, f"{fmt(r / scene.scale)} {unit} is no cable radius "
                             f"(refused outside {fmt(RADIUS_REFUSE[0] * 1000)} mm to {fmt(RADIUS_REFUSE[1])} m)"
                             + _likely(r, *RADIUS_USUAL, scene))
        if not RADIUS_USUAL[0] <= r <= RADIUS_USUAL[1]:
            warnings.append(f"{key} = {fmt(r / scene.scale)} {unit} is an unusual cable radius "
                            f"(usual {fmt(RADIUS_USUAL[0] * 1000)} mm to {fmt(RADIUS_USUAL[1] * 1000)} mm)"
                            + _likely(r, *RADIUS_USUAL, scene))
        length = c.length if c.length is not None else c.route_length
        key = f"cables[{i}].length" if c.length is not None else f"cables[{i}] (the route's length)"
        if not LENGTH_REFUSE[0] <= length <= LENGTH_REFUSE[1]:
            raise SceneError(scene.path, key, f"{fmt(length / scene.scale)} {unit} is no cable length "
                             f"(refused outside {fmt(LENGTH_REFUSE[0] * 1000)} mm to "
                             f"{fmt(LENGTH_REFUSE[1] / 1000)} km)" + _likely(length, *LENGTH_USUAL, scene))
        if not LENGTH_USUAL[0] <= length <= LENGTH_USUAL[1]:
            warnings.append(f"{key} = {fmt(length / scene.scale)} {unit} is an unusual cable length "
                            f"(usual {fmt(LENGTH_USUAL[0] * 1000)} mm to {fmt(LENGTH_USUAL[1] / 1000)} km)"
                            + _likely(length, *LENGTH_USUAL, scene))
    for key, size, usual, refused in _sizes(scene):
        if size > refused:
            raise SceneError(scene.path, key, f"spans {fmt(size / scene.scale)} {unit}, more than "
                             f"{fmt(refused / 1000)} km" + _likely(size, 0.0, usual, scene))
        if size > usual:
            warnings.append(f"{key} spans {fmt(size / scene.scale)} {unit}, more than a cell's "
                            f"{fmt(usual)} m" + _likely(size, 0.0, usual, scene))
    return tuple(warnings)
