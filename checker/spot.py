"""The other side of a clash: the closest point opposite a record's worst place.

An :class:`~cablecheck.checker.records.Interference` carries its worst place on cable
``a`` (``where``, ``s``) and, for cable pairs, the arc length on cable ``b``
(``s_b``). To draw the gap (a segment from one side to the other) a viewer
needs the matching point on the other side; it is found here from the same
geometry, for the few records shown, not carried by every record of every
step:

- against a part: the closest surface point of the part's shape to
  ``where`` (:func:`cablecheck.checker.shapes.signed_distance`, in the part's frame;
  many places of one part in one query);
- against a cable (another one or a loop of the same): the closest point
  to ``where`` on the elements of cable ``b`` next to arc length ``s_b``
  (many places, each on its own copy of the cable, in one query).

This module does not decide what interferes and does not know MuJoCo.
"""

from __future__ import annotations

import numpy as np

from cablecheck.checker.cable import arc_length
from cablecheck.checker.closest import point_segment
from cablecheck.checker.shapes import Shape, signed_distance


def on_part(shape: Shape, pose: np.ndarray, where: np.ndarray) -> np.ndarray:
    """(3,) the point of the part's surface closest to `where` (world), given
    the part's (4, 4) world pose."""
    return on_part_many(shape, np.asarray(pose, float)[None], np.asarray(where, float).reshape(1, 3))[0]


def on_part_many(shape: Shape, poses: np.ndarray, where: np.ndarray) -> np.ndarray:
    """(n, 3) :func:`on_part` for n places at once (each with the part's
    (n, 4, 4) pose at its own time): one query of the shape, not n."""
    poses = np.asarray(poses, float).reshape(-1, 4, 4)
    rot, trans = poses[:, :3, :3], poses[:, :3, 3]
    local = np.einsum("ni,nij->nj", np.asarray(where, float).reshape(-1, 3) - trans, rot)
    _, closest = signed_distance(shape, local)
    return np.einsum("nij,nj->ni", rot, closest) + trans


def on_cable(points: np.ndarray, s_b: float, where: np.ndarray, reach: int = 1) -> np.ndarray:
    """(3,) the point closest to `where` on the elements of a cable's (n, 3)
    centreline within `reach` elements of the one holding arc length `s_b`."""
    p = np.asarray(points, float)
    if len(p) < 2:
        return p[0].copy()
    s = arc_length(p)
    j = int(np.clip(np.searchsorted(s, s_b, side="right") - 1, 0, len(p) - 2))
    lo, hi = max(j - reach, 0), min(j + reach, len(p) - 2) + 1
    q = np.broadcast_to(np.asarray(where, float), (hi - lo, 3))
    d, _, closest = point_segment(q, p[lo:hi], p[lo + 1:hi + 1])
    return closest[int(np.argmin(d))]


def on_cable_many(points: np.ndarray, s_b: np.ndarray, where: np.ndarray, reach: int = 1) -> np.ndarray:
    """(m, 3) :func:`on_cable` for m places at once, each on its own (n, 3)
    centreline of `points` (m, n, 3) (the cable at its own time): one
    vectorised pass, not m."""
    p = np.asarray(points, float)
    m, n = p.shape[:2]
    if n < 2:
        return p[:, 0].copy()
    s = arc_length(p)
    j = np.clip((s <= np.asarray(s_b, float)[:, None]).sum(axis=1) - 1, 0, n - 2)
    # the elements within `reach` of j (clipped at the ends: a repeated element changes no minimum)
    k = np.clip(j[:, None] + np.arange(-reach, reach + 1)[None], 0, n - 2)            # (m, 2 reach + 1)
    rows = np.arange(m)[:, None]
    q = np.repeat(np.asarray(where, float).reshape(m, 3), k.shape[1], axis=0)
    d, _, closest = point_segment(q, p[rows, k].reshape(-1, 3), p[rows, k + 1].reshape(-1, 3))
    best = np.argmin(d.reshape(m, -1), axis=1)
    return closest.reshape(m, -1, 3)[np.arange(m), best]
