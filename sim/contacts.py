"""MuJoCo's contacts mapped back to the scene's names.

Each contact in `mjData.contact` names two geoms, or a flex element and a
geom, or two flex elements. `read_contacts` turns the whole contact array
into one `Contacts` record of parallel arrays (no per-contact Python
objects): the kind of pair, the cable or part names on both sides, the
element index along a cable (-1 for a part), MuJoCo's signed distance and the
contact point.

This module does not decide what a contact means for interference (expected
attachment contact, near neighbours of a self contact): the checker and the
validation compare that.
"""

from __future__ import annotations

import mujoco
import numpy as np

from checker.validation import SimContacts
from sim.build import Built


Contacts = SimContacts
"""MuJoCo contacts of one step as parallel arrays: `checker.validation.SimContacts`.

kind: "cable-structure", "keepout", "cable-cable", "self" or "part-part";
a, b: names (for contacts with a cable, a is the cable); elem_a, elem_b:
element index along cable a / b, -1 for a part; dist: signed surface
distance, metres; pos: (n, 3) contact points, world metres."""


class ContactReader:
    """Maps contacts of a model built by `sim.build` to names."""

    def __init__(self, built: Built):
        m = built.model
        self.flex_cable = np.full(max(m.nflex, 1), "", dtype=object)
        for c in built.cables:
            self.flex_cable[c.flex_id] = c.name
        self.geom_name = np.full(max(m.ngeom, 1), "", dtype=object)
        self.geom_keepout = np.zeros(max(m.ngeom, 1), bool)
        for p in built.parts:
            self.geom_name[p.geom_id] = p.name
            self.geom_keepout[p.geom_id] = p.keepout

    def read(self, data: mujoco.MjData, origin: np.ndarray) -> Contacts:
        """All contacts of `data` (after mj_collision) with names; contact
        points are moved from model coordinates to the scene world by `origin`."""
        n = int(data.ncon)
        con = data.contact
        geom = np.asarray(con.geom[:n], int).reshape(n, 2)
        flex = np.asarray(con.flex[:n], int).reshape(n, 2)
        elem = np.asarray(con.elem[:n], int).reshape(n, 2)
        dist = np.asarray(con.dist[:n], float).copy()
        pos = np.asarray(con.pos[:n], float).reshape(n, 3) + origin
        # Put the flex side first so a is always the cable.
        swap = (flex[:, 0] < 0) & (flex[:, 1] >= 0)
        for arr in (geom, flex, elem):
            arr[swap] = arr[swap][:, ::-1]
        is_flex_a = flex[:, 0] >= 0
        is_flex_b = flex[:, 1] >= 0
        a = np.where(is_flex_a, self.flex_cable[np.maximum(flex[:, 0], 0)],
                     self.geom_name[np.maximum(geom[:, 0], 0)])
        b = np.where(is_flex_b, self.flex_cable[np.maximum(flex[:, 1], 0)],
                     self.geom_name[np.maximum(geom[:, 1], 0)])
        keepout = (~is_flex_b) & self.geom_keepout[np.maximum(geom[:, 1], 0)]
        kind = np.full(n, "part-part", dtype=object)
        kind[is_flex_a & ~is_flex_b] = "cable-structure"
        kind[is_flex_a & ~is_flex_b & keepout] = "keepout"
        kind[is_flex_a & is_flex_b] = "cable-cable"
        kind[is_flex_a & is_flex_b & (flex[:, 0] == flex[:, 1])] = "self"
        keep_pp = ~is_flex_a & ~is_flex_b
        kind[keep_pp & (self.geom_keepout[np.maximum(geom[:, 0], 0)] | keepout)] = "keepout"
        elem_a = np.where(is_flex_a, elem[:, 0], -1)
        elem_b = np.where(is_flex_b, elem[:, 1], -1)
        # Contacts with geoms that are not parts (none are built today) are dropped.
        valid = (a != "") & (b != "")
        return Contacts(kind[valid], a[valid], b[valid], elem_a[valid], elem_b[valid],
                        dist[valid], pos[valid])
