"""Interference records: what the checker reports for one scene state.

One :class:`Interference` per (type, a, b) pair that came below the clearance,
with the SPEC's signed distance (negative means overlap), its severity and the
worst place along cable ``a``. The enums name the pair types and severities
used throughout the report (string enums: their text is the report's), and
:func:`severity_of` is the one place a distance is classed hard, soft or
clear against the clearance: records, events and the comparison with the
simulator all take their severity from it.

Deliberately not here: events over time, MuJoCo comparison, JSON writing;
those consume these records.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import StrEnum

import numpy as np


class PairType(StrEnum):
    """What kind of pair interferes; the values are the report's ``type``."""

    SELF = "self"
    CABLE_CABLE = "cable-cable"
    CABLE_STRUCTURE = "cable-structure"
    KEEPOUT = "keepout"
    PART_PART = "part-part"
    BEND = "bend"
    TAUT = "taut"


PART_TYPES = (PairType.CABLE_STRUCTURE, PairType.KEEPOUT)
"""The pair types measured against a part (a cable and a part or keep-out zone); as a
`StrEnum`'s members, the report's strings compare equal to them."""


class Severity(StrEnum):
    """``hard``: min_distance < 0; ``soft``: 0 <= min_distance < clearance."""

    HARD = "hard"
    SOFT = "soft"


def severity_of(min_distance: float | None, clearance: float) -> Severity | None:
    """Severity of a signed distance against the clearance, None when clear
    (a distance of None, a pair not seen at all, is clear)."""
    if min_distance is None:
        return None
    if min_distance < 0.0:
        return Severity.HARD
    if min_distance < clearance:
        return Severity.SOFT
    return None


@dataclass(frozen=True)
class Interference:
    """One interfering pair in one scene state.

    Attributes:
        type: the pair type.
        a: cable name (the first of two cables in input order; for self, bend
            and taut the only cable).
        b: the other cable's or the part's name (``a`` again for self, bend,
            taut).
        min_distance: signed distance in scene units (SPEC "Report"): cable to
            part, centreline distance to the surface minus r; cable to cable,
            centreline distance minus r1 + r2; self, minus 2r; bend, bend
            radius minus the limit; taut, the 1 % stretch allowance minus the
            stretch.
        severity: hard or soft.
        where: (3,) world point on cable a's centreline at the worst place.
        s: arc length along cable a at that point.
        s_b: arc length on cable b at the worst place (self and cable-cable),
            else None.
    """

    type: PairType
    a: str
    b: str
    min_distance: float
    severity: Severity
    where: np.ndarray
    s: float
    s_b: float | None = None


@dataclass(frozen=True)
class NearMiss:
    """A cable-part pair method ``points`` reads at or past the clearance by
    less than its own error (:func:`~cablecheck.checker.interference.discrete.points_error`)
    at one scene state: no record, but one an exact measure may find inside
    the clearance (:func:`cablecheck.checker.refine.near_miss_records`).

    Attributes:
        type: cable-structure or keep-out.
        a, b: the cable and the part.
        min_distance: the points' least value (at or past the clearance).
        s_lo, s_hi: the arc lengths along the cable between which its points
            read below the clearance plus the error: only there can an
            element come inside the clearance.
    """

    type: PairType
    a: str
    b: str
    min_distance: float
    s_lo: float
    s_hi: float

