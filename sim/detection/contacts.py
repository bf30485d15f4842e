"""MuJoCo's contacts mapped back to the scene's names.

Each contact in `mjData.contact` names two geoms, or a flex element and a
geom, or two flex elements; a flex is a cable, or in the detection model
the surface of a concave mesh part (`cablecheck.detection.mesh`), named as that
part with its triangles' radius added back to the distance.
`ContactReader.read_many` turns the contact arrays of each step into one
`Contacts` record of parallel arrays (no per-contact Python objects): the kind of pair, the cable or part names on both sides, the
element index along a cable (-1 for a part), MuJoCo's signed distance and the
contact point.

This module does not decide what a contact means for interference (expected
attachment contact, near neighbours of a self contact): the checker and the
validation compare that.
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np

from cablecheck.build.built import Built
from cablecheck.checker.validation import NameTable, SimContacts
from cablecheck.detection.mesh import surface_geoms

Contacts = SimContacts
"""MuJoCo contacts of one step as parallel arrays: `cablecheck.checker.validation.SimContacts`.

kind: "cable-structure", "keepout", "cable-cable", "self" or "part-part";
a, b: names (for contacts with a cable, a is the cable), also as integer
codes (kind, a, b) into the reader's `table`; elem_a, elem_b:
element index along cable a / b, -1 for a part, -2 - v for a contact
MuJoCo puts at vertex v (flex-plane); dist: signed surface
distance, metres; pos: (n, 3) contact points, world metres."""


class ContactReader:
    """Maps contacts of a model built by `cablecheck.build.stages` to names.

    The mapping runs on integer codes (one table of names: the flexes', then
    the geoms'), indexing the names once at the end: a step has few
    contacts, so numpy's per-call cost on string arrays is what reading them
    would otherwise cost."""

    _KINDS = np.array(["part-part", "cable-structure", "keepout", "cable-cable", "self"], dtype=object)

    def __init__(self, built: Built):
        m = built.detect if built.detect is not None else built.model
        self._nflex = max(m.nflex, 1)
        names = np.full(self._nflex + max(m.ngeom, 1), "", dtype=object)
        for c in built.cables:
            names[c.flex_id] = c.name
        keepout = np.zeros(len(names), bool)
        for p in built.parts:
            names[self._nflex + p.geom_id] = p.name
            keepout[self._nflex + p.geom_id] = p.keepout
        # a concave mesh part's surface flex (cablecheck.detection.mesh) is that part
        surface = np.zeros(len(names), bool)
        extra = np.zeros(len(names))
        flexes, geoms = surface_geoms(m)
        names[flexes], keepout[flexes] = names[self._nflex + geoms], keepout[self._nflex + geoms]
        surface[flexes] = True
        extra[flexes] = m.flex_radius[flexes] if len(flexes) else 0.0
        self._names, self._keepout, self._named = names, keepout, names != ""
        self._surface, self._radius = surface, extra
        self.table = NameTable(self._KINDS, names)          # what the contacts' codes index
        self._empty = Contacts(np.zeros(0, dtype=object), np.zeros(0, dtype=object), np.zeros(0, dtype=object),
                               np.zeros(0, int), np.zeros(0, int), np.zeros(0), np.zeros((0, 3)),
                               np.zeros((0, 3), np.int64), self.table)

    @staticmethod
    def raw(data: mujoco.MjData) -> "RawContacts":
        """A copy of the contact arrays of `data` (after mj_collision), to be
        named later (:meth:`read_many`); the data may be reused meanwhile.
        Copies alone: what the fields mean is worked out for a batch at once."""
        con = data.contact                  # as many as data.ncon
        return RawContacts(con.geom.copy(), con.flex.copy(), con.elem.copy(), con.vert.copy(), con.dist.copy(),
                           con.pos.copy())

    def read_many(self, raws: list["RawContacts"], origin: np.ndarray) -> list[Contacts]:
        """The raw contacts of many steps (:meth:`raw`) with names; contact
        points are moved from model coordinates to the scene world by `origin`."""
        counts = np.array([len(r.dist) for r in raws], np.int64)
        if counts.sum() == 0:
            return [self._empty] * len(raws)
        both = RawContacts(*(np.concatenate([getattr(r, f) for r in raws])
                             for f in ("geom", "flex", "elems", "verts", "dist", "pos")))
        geom, flex, elem, dist = both.geom.astype(np.int64), both.flex.astype(np.int64), both.elem, both.dist
        pos = both.pos + origin
        code = np.where(flex >= 0, flex, self._nflex + np.maximum(geom, 0))   # (n, 2) into the name table
        is_flex = (flex >= 0) & ~self._surface[code]                         # a cable's flex
        # Put the cable side first so a is always the cable.
        swap = ~is_flex[:, 0] & is_flex[:, 1]
        if swap.any():
            for arr in (code, is_flex, flex, elem):
                arr[swap] = arr[swap][:, ::-1]
        extra = self._radius.take(code)
        dist = dist + (extra[:, 0] + extra[:, 1])                             # a surface's triangles are the mesh
        ko = self._keepout[code]
        kind = np.where(is_flex[:, 0], np.where(is_flex[:, 1], 3 + (flex[:, 0] == flex[:, 1]), 1 + ko[:, 1]),
                        2 * (ko[:, 0] | ko[:, 1]))                           # codes into _KINDS
        elem = np.where(is_flex, elem, -1)
        # Contacts with geoms that are not parts (none are built today) are dropped.
        valid = self._named[code[:, 0]] & self._named[code[:, 1]]
        if not valid.all():
            step = np.repeat(np.arange(len(raws)), counts)[valid]
            counts = np.bincount(step, minlength=len(raws))
            code, kind, elem, dist, pos = code[valid], kind[valid], elem[valid], dist[valid], pos[valid]
        kinds, a, b = self._KINDS[kind], self._names[code[:, 0]], self._names[code[:, 1]]
        codes = np.concatenate([kind[:, None], code], axis=1).astype(np.int64)
        bounds = np.concatenate([[0], np.cumsum(counts)]).tolist()
        arrays = (kinds, a, b, elem[:, 0], elem[:, 1], dist, pos, codes)
        return [Contacts(*[x[i:j] for x in arrays], self.table) for i, j in zip(bounds[:-1], bounds[1:])]


@dataclass(frozen=True)
class RawContacts:
    """MuJoCo's contact arrays of one step as copied, unnamed (model
    coordinates): geom, flex, elems and verts (n, 2) int32 (-1 for none),
    dist (n,) and pos (n, 3)."""

    geom: np.ndarray
    flex: np.ndarray
    elems: np.ndarray
    verts: np.ndarray
    dist: np.ndarray
    pos: np.ndarray

    @property
    def elem(self) -> np.ndarray:
        """(n, 2) the flex element of each side, -2 - vertex for a flex side
        MuJoCo gives a vertex, not an element (MuJoCo collides a flex with a
        plane vertex by vertex: a capsule chain's distance to a plane is
        reached at a vertex, so it is exact), -1 for a geom side."""
        elem, vert = self.elems.astype(np.int64), self.verts.astype(np.int64)
        return np.where((elem < 0) & (vert >= 0), -2 - vert, elem)
