"""Cables the simulation holds on a concave part's convex hull, off its surface.

MuJoCo collides a mesh geom as its convex hull, in the simulation model as
anywhere: a cable pressed towards a concave part's pocket or notch rests on
the hull, where the real cable would go on towards the surface. The
detection model sees such a part's own triangles (`cablecheck.detection.mesh`), so
MuJoCo's contacts there agree with the checker, and neither shows that the
simulated cable lies where the real one would not. `HullGaps` does: at every
checked state it compares the simulation model's contacts of each cable with
the hulls of those parts against the detection model's distances to their
surfaces, element by element, and names each (cable, part) where the
surface lies farther than the hull by more than `GAP_TOLERANCE`.

In contact means a simulation contact with `dist <= includemargin`. Since
MuJoCo 4 a contact's margin is the inflation of the surfaces (changelog,
"margin and gap"): contact forces act, on `dist - margin`, once the distance
is below the margin, and only contacts in the `margin + gap` buffer beyond
are passive; `includemargin` is the pair's margin as MuJoCo sums it. So a
cable resting on a hull sits at about the margin, and it is that contact,
not a zero distance, that holds it up.

The simulation's contacts are those of its last collision pass (the start
of the state's last substep) while the detection model sees the state
itself; the tolerance covers that step and MuJoCo's convex collider. A
cable element whose surface is beyond the detection model's margin (the
clearance) has no detection contact: its gap is then known only to exceed
the clearance minus the hull distance, and is reported as "at least" that.

Only with validation on (the detection model exists) and cable-structure
contact in the simulation; this module neither changes the simulation (a
convex decomposition of the part would, with physics of its own) nor
decides interference (the checker does).
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np

from cablecheck.build.built import Built, mesh_parts
from cablecheck.checker.arrays import first_least
from cablecheck.checker.validation import shared_codes
from cablecheck.detection.contacts import Contacts
from cablecheck.detection.mesh import surface_geoms

GAP_TOLERANCE = 0.1
"""Hull-to-surface gaps up to this fraction of the clearance are not
reported: smaller ones move the cable by less than the check resolves, and
cover one substep of relative motion and MuJoCo's convex tolerance."""


@dataclass(frozen=True)
class HullRows:
    """One state's simulation contacts of cable elements with mesh parts'
    hulls (`HullReader.rows`): the cable's index, the part's index in
    `Built.parts`, the cable's element, and MuJoCo's distance (metres)."""

    cable: np.ndarray
    part: np.ndarray
    elem: np.ndarray
    dist: np.ndarray


@dataclass(frozen=True)
class HullRaw:
    """One state's simulation contacts as MuJoCo lists them (`HullReader.raw`):
    (n, 2) int32 flex, geom and element of both sides (-1 for none), (n,)
    distance and includemargin."""

    flex: np.ndarray
    geom: np.ndarray
    elem: np.ndarray
    dist: np.ndarray
    margin: np.ndarray


@dataclass(frozen=True)
class HullGap:
    """A (cable, part) the simulation held on the part's hull: the largest
    gap to the surface (metres; `bounded`: the surface was beyond the
    clearance there, the gap at least this) and the first and last time."""

    cable: str
    part: str
    gap: float
    bounded: bool
    t_start: float
    t_end: float


class HullReader:
    """Reads a state's simulation contacts of cables with mesh parts' hulls
    (`rows`); which of those parts are watched (`watched`) is decided by
    `HullGaps`, from the detection model, which the simulation does not
    need (a run steps it while the detection model is still being built)."""

    def __init__(self, flex_cable: np.ndarray, geom_part: np.ndarray):
        self._flex_cable, self._geom_part = flex_cable, geom_part

    @classmethod
    def of(cls, built: Built) -> HullReader | None:
        """The reader for `built`'s simulation model, or None when no hull can
        hold a cable (`could_hold`)."""
        if not could_hold(built):
            return None
        m = built.model
        meshes = mesh_parts(built)
        if not len(meshes):
            return None
        flex_cable = np.full(m.nflex + 1, -1, np.int64)          # the last entry: "no flex" (-1)
        flex_cable[[c.flex_id for c in built.cables]] = np.arange(len(built.cables))
        geom_part = np.full(m.ngeom + 1, -1, np.int64)           # the last entry: "no geom" (-1)
        geom_part[[built.parts[i].geom_id for i in meshes]] = meshes
        return cls(flex_cable, geom_part)

    @staticmethod
    def raw(data: mujoco.MjData) -> HullRaw:
        """The simulation's contacts as they are in `data` (copied, as
        `cablecheck.detection.contacts.ContactReader.raw` copies them), for `rows_many` later:
        the simulation's thread only copies them."""
        con = data.contact                  # as many as data.ncon
        return HullRaw(con.flex.copy(), con.geom.copy(), con.elem.copy(), con.dist.copy(), con.includemargin.copy())

    def rows(self, data: mujoco.MjData) -> HullRows:
        """The active contacts (dist <= includemargin) of `data` between a
        cable element and a mesh part's geom (its hull); `part` indexes
        `Built.parts`."""
        state, *rows = self.rows_many([self.raw(data)])
        return HullRows(*rows)

    def rows_many(self, raws: list[HullRaw | None]) -> tuple[np.ndarray, ...]:
        """`rows` of many states' `raw` contacts (None: none) at once: the
        state index of each row, then the `HullRows` fields, concatenated."""
        counts = [0 if r is None else len(r.dist) for r in raws]
        present = [r for r in raws if r is not None]
        if not present or not sum(counts):
            empty = np.zeros(0, np.int64)
            return empty, empty, empty, empty, np.zeros(0)
        state = np.repeat(np.arange(len(raws)), counts)
        flex, geom, elem = (np.concatenate([getattr(r, f) for r in present]).astype(np.int64)
                            for f in ("flex", "geom", "elem"))
        dist = np.concatenate([r.dist for r in present])
        margin = np.concatenate([r.margin for r in present])
        cable = self._flex_cable[flex]                # -1 indexes the "no flex" entry
        part = self._geom_part[np.where(flex >= 0, -1, geom)]
        side = (cable[:, 0] < 0).astype(np.int64)    # the cable's side
        row = np.arange(len(dist))
        c, p, e = cable[row, side], part[row, 1 - side], elem[row, side]
        keep = (c >= 0) & (p >= 0) & (e >= 0) & (dist <= margin)
        return state[keep], c[keep], p[keep], e[keep], dist[keep]


def could_hold(built: Built) -> bool:
    """Whether the simulation can hold a cable on a part's hull at all: it
    is stepped with cable-structure contact and has cables."""
    scene = built.scene
    return bool(built.cables) and scene.effects.dynamics and "cable-structure" in scene.effects.contact


def watched(built: Built) -> np.ndarray:
    """Indices into `built.parts` of the parts whose hull can hold a cable
    off their surface: those the detection model sees as their surface,
    when the simulation is stepped with cable-structure contact; none
    without a detection model (validation off) or without cables."""
    if built.detect is None or not could_hold(built) or not built.parts:
        return np.zeros(0, np.int64)
    geoms = np.array([p.geom_id for p in built.parts])
    return np.flatnonzero(np.isin(geoms, surface_geoms(built.detect)[1]))


class HullGaps:
    """The run's hull-held cables, gathered batch by batch (`take`)."""

    def __init__(self, built: Built):
        self._scene = built.scene
        self.cables = [c.name for c in built.cables]
        parts = watched(built)
        self.parts = [built.parts[i].name for i in parts]
        self._watched = np.full(len(built.parts) + 1, -1, np.int64)   # Built.parts index -> watched index
        self._watched[parts] = np.arange(len(parts))
        self._reader = HullReader.of(built)
        self._cable_names, self._cable_ids = _table(self.cables)
        self._part_names, self._part_ids = _table(self.parts)
        self._by_code: tuple | None = None      # (name table, cable and part per code)
        self.clearance = built.scene.check.clearance
        self.tolerance = GAP_TOLERANCE * self.clearance
        self._elems = max([c.count for c in built.cables], default=1)
        n = len(self.cables) * len(self.parts)     # per (cable, part): the largest gap, ...
        self._gap = np.full(n, -np.inf)
        self._bounded = np.zeros(n, bool)
        self._t0, self._t1 = np.full(n, np.inf), np.full(n, -np.inf)

    def take(self, times: np.ndarray, hulls: list[HullRaw | None], detected: list[Contacts]) -> None:
        """Compare a batch of states: their simulation contacts (`HullReader.raw`,
        None: none) with the detection model's named contacts at the same states."""
        if not self.parts or self._reader is None:
            return
        hs, hc, hp, he, hd = self._reader.rows_many(hulls)
        if not len(hd):
            return
        ncab, npart, nel = len(self.cables), len(self.parts), self._elems + 1

        def keys(state, cable, part, elem):
            return ((state * ncab + cable) * npart + part) * nel + elem

        # the detection model's least surface distance per (state, cable, part, element)
        state = np.repeat(np.arange(len(detected)), [len(c.dist) for c in detected])
        cable, part = self._ids(detected)
        elem = np.concatenate([c.elem_a for c in detected]).astype(np.int64)
        dist = np.concatenate([c.dist for c in detected]).astype(float)
        ok = (cable >= 0) & (part >= 0) & (elem >= 0)
        state, own, dist = state[ok], keys(0, cable[ok], part[ok], elem[ok]), dist[ok]   # own: the key in a state
        least = first_least(state, own, dist, ncab * npart * nel)     # in key order
        k, surface = np.r_[keys(state[least], 0, 0, 0) + own[least], -1], np.r_[dist[least], np.nan]   # -1: found by none

        hp = self._watched[hp]                        # the rows' parts (Built.parts) as watched parts
        mine = hp >= 0
        hs, hc, hp, he, hd = hs[mine], hc[mine], hp[mine], he[mine], hd[mine]
        hk = keys(hs, hc, hp, he)
        at = np.minimum(np.searchsorted(k[:-1], hk), len(k) - 1)
        seen = k[at] == hk
        gap = np.where(seen, surface[at], self.clearance) - hd
        held = gap > self.tolerance
        if not held.any():
            return
        pair = hc[held] * npart + hp[held]
        gap, bounded, t = gap[held], ~seen[held], np.asarray(times, float)[hs[held]]
        np.minimum.at(self._t0, pair, t)
        np.maximum.at(self._t1, pair, t)
        best = np.full(len(self._gap), -np.inf)
        np.maximum.at(best, pair, gap)
        top = (gap == best[pair])                     # the batch's largest gap of each pair
        bigger = best > self._gap
        self._bounded[bigger] = False
        np.logical_or.at(self._bounded, pair[top & bigger[pair]], bounded[top & bigger[pair]])
        self._gap = np.maximum(self._gap, best)

    def _ids(self, detected: list[Contacts]) -> tuple[np.ndarray, np.ndarray]:
        """The cable and watched part (-1: none) of every contact of the
        batch, by side a and b: through their codes when the contacts share
        one name table (`cablecheck.detection.contacts.ContactReader`), else by name."""
        shared = shared_codes(detected)
        if shared is not None:
            table, codes = shared
            if self._by_code is None or self._by_code[0] is not table:
                names = np.asarray(table.names, dtype=object)
                self._by_code = (table, _lookup(self._cable_names, self._cable_ids, names),
                                 _lookup(self._part_names, self._part_ids, names))
            return self._by_code[1][codes[:, 1]], self._by_code[2][codes[:, 2]]
        return (_lookup(self._cable_names, self._cable_ids, np.concatenate([c.a for c in detected])),
                _lookup(self._part_names, self._part_ids, np.concatenate([c.b for c in detected])))

    def found(self) -> list[HullGap]:
        """The (cable, part) pairs held on a hull so far, in cable then part order."""
        npart = len(self.parts)
        return [HullGap(self.cables[i // npart], self.parts[i % npart], float(self._gap[i]), bool(self._bounded[i]),
                        float(self._t0[i]), float(self._t1[i])) for i in np.flatnonzero(np.isfinite(self._gap))]

    def warnings(self) -> list[str]:
        """One physics warning per (cable, part) held on a hull (scene units)."""
        unit, k = self._scene.units, self._scene.scale
        return [f"cable {g.cable!r} rests on the convex hull of part {g.part!r} in the simulation "
                f"(MuJoCo collides a mesh as its hull) from t = {g.t_start:.3f} to {g.t_end:.3f} s, where the "
                f"part's surface lies {'more than' if g.bounded else 'up to'} {g.gap / k:.4g} {unit} beyond "
                f"the hull: the simulated cable is held off where the real one could come closer to the part"
                for g in self.found()]


def _table(names: list[str]) -> tuple[np.ndarray, np.ndarray]:
    """Names sorted, and each one's index in `names` (for `_lookup`)."""
    order = np.argsort(np.array(names, dtype=object)) if names else np.zeros(0, np.int64)
    return np.array(names, dtype=object)[order], order.astype(np.int64)


def _lookup(names: np.ndarray, ids: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Index of each of `x` in the table (`_table`), -1 for a name not in it."""
    if len(x) == 0 or len(names) == 0:
        return np.full(len(x), -1, np.int64)
    at = np.minimum(np.searchsorted(names, x), len(names) - 1)
    return np.where(names[at] == x, ids[at], -1)
