"""A held point of a cable pressed into a part of another body, read from MuJoCo's own contacts.

A cable end or clip held by one body (a dress-pack end clamped on a robot's
wrist) whose held vertex, or a vertex within `PINCH_ELEMENTS` elements of it,
MuJoCo finds inside a part of another body (a mesh as its convex hull, as
MuJoCo collides it): the hold and the contact fight until the cable gives.
`held_pinch` words the deepest such contact at a state (`contacts_at`). The build warns of
one at t = 0 (`cablecheck.build.stages`); a diverged run names it as its
likely cause (`cablecheck.run.divergence`).

This module runs MuJoCo's collision pass on the simulation model at one
state; it steps nothing and decides no interference.
"""

from __future__ import annotations

import mujoco
import numpy as np

from cablecheck.build.built import Built
from cablecheck.scene.errors import written

PINCH_ELEMENTS = 3
"""Elements between where a cable diverged, a held vertex and a penetrating contact for `held_pinch`."""


def contacts_at(built: Built, qpos: np.ndarray) -> mujoco.MjData | None:
    """The simulation's data at `qpos` after MuJoCo's position stage (kinematics, flexes and
    collision: the contacts as simulated); None without a MuJoCo model or with a non-finite state."""
    m = built.model
    if not isinstance(m, mujoco.MjModel) or not np.isfinite(qpos).all():
        return None
    d = mujoco.MjData(m)
    d.qpos[:] = qpos
    mujoco.mj_fwdPosition(m, d)
    return d


def held_pinch(built: Built, d: mujoco.MjData | None, cable: int, vertex: int | None) -> str | None:
    """Why a cable diverged near a held vertex, when it did: at the state `d` (`contacts_at` the last
    sound one) MuJoCo's collision pass finds the cable pressed into a part of another body within
    `PINCH_ELEMENTS` elements of a vertex held by a body (and of `vertex`, where it diverged, when
    known); the deepest such contact in words (who holds what, where, how deep, in which part), else None."""
    if d is None:
        return None
    m = built.model
    c = built.cables[cable]
    parts = {p.geom_id: p for p in built.parts}
    ends = m.flex_elem[m.flex_elemdataadr[c.flex_id]:].reshape(-1, 2)   # a 1-D flex: two vertices an element
    best = None
    for con in d.contact[:d.ncon]:
        side = 0 if con.flex[0] == c.flex_id else 1 if con.flex[1] == c.flex_id else -1
        if side < 0 or con.geom[1 - side] not in parts or con.dist >= 0.0:
            continue
        part = parts[int(con.geom[1 - side])]
        verts = ([int(con.vert[side])] if con.vert[side] >= 0 else ends[int(con.elem[side])].tolist())
        for a in c.attachments:
            if a.body == part.body or min(abs(v - a.vertex) for v in verts) > PINCH_ELEMENTS:
                continue
            if vertex is not None and abs(vertex - a.vertex) > 2 * PINCH_ELEMENTS:
                continue
            if best is None or con.dist < best[0]:
                best = (float(con.dist), part, a, min(verts, key=lambda v: abs(v - a.vertex)))
    if best is None:
        return None
    depth, part, a, v = best
    scene = built.scene
    hull = " (as its convex hull: MuJoCo collides a mesh as its hull)" if part.shape == "mesh" else ""
    at = "there" if v == a.vertex else f"{abs(v - a.vertex)} element(s) from it"
    return (f"cable {c.name!r} is held at vertex {a.vertex} (its {a.window or a.kind} on {a.body!r}) and "
            f"{at} pressed {written(scene, -depth)} into part "
            f"{part.name!r}{hull}")


