"""Many parts drawn as one entity: a harness's hundreds of clips, brackets and
obstacles in the review recording.

A part is an entity of its own (`world/parts/<assembly path>`) unless
:data:`BATCH_PARTS` or more parts of one kind (boxes; spheres and
ellipsoids; capsules; cylinders) sit under the same assembly level and
either all stay put or all move: those are drawn as the instances of one
entity, `<root>/<assembly level>/_<kind>` (`world/parts/frame/_boxes`;
`_moving_boxes` for those that move), and so are the rest of a kind
where they number as many, under the levels they share
(`world/parts/frame/_boxes` for a harness's 300 brackets
`frame/bracket017/base`, `.../arm`; `world/parts/_boxes` for parts of no
assembly), each instance labelled
with its part's name (shown on hover and in the selection, not drawn). A chunk of the recording
costs kilobytes whatever it holds: 1,000 parts as entities of their own
took 5.5 MB before any of them moved, batched 43 kB (measured with rerun
0.41, 1,000 boxes and their colour timelines). Meshes, planes and
keep-outs stay entities of their own.

Each instance is placed by its own pose (centre and turn, a capsule by the
centre of its first end sphere): static for parts that stay put, one row
per recorded frame for those that move.

Not here: which parts there are, their colours or when they are drawn
(`cablecheck.record.scene`, `cablecheck.record.wearview`).
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import rerun as rr
from scipy.spatial.transform import Rotation

from cablecheck.build.built import PartModel
from cablecheck.record.columns import Column, column, floats, quats, strings, vec3
from cablecheck.record.style import escape

BATCH_PARTS = 32
"""Parts of one kind under one assembly level from which they are drawn as
one entity (fewer read better one by one in the entity tree)."""

_KIND = {"box": rr.Boxes3D, "sphere": rr.Ellipsoids3D, "ellipsoid": rr.Ellipsoids3D,
         "capsule": rr.Capsules3D, "cylinder": rr.Cylinders3D}
"""The archetype that draws many parts of a shape as its instances."""
_LEAF = {rr.Boxes3D: "_boxes", rr.Ellipsoids3D: "_ellipsoids", rr.Capsules3D: "_capsules",
         rr.Cylinders3D: "_cylinders"}


@dataclass(frozen=True)
class Batch:
    """Parts drawn as the instances of one entity.

    Attributes:
      path: the entity's path.
      archetype: the rerun archetype drawing them.
      members: (n,) indices of the parts in the list given to :func:`batches`.
      moving: whether they ride moving bodies (their poses given per frame).
    """

    path: str
    archetype: type
    members: np.ndarray
    moving: bool


def batches(parts: Sequence[PartModel], moving: np.ndarray, root: str) -> list[Batch]:
    """The batches among `parts` (`moving` (n,) bool: each rides a moving
    body), their entities under `root`: of each kind, those that stay put
    and those that move apart, first per assembly level
    (`<root>/<level>/_boxes`, `_moving_boxes`, ...), then the rest of the
    kind together under the levels they share (`<root>/frame/_boxes` for
    `frame/bracket07/base` and the like; `<root>/_boxes` for parts of no
    assembly), wherever there are :data:`BATCH_PARTS` or more. A part in
    none is drawn on its own."""
    groups: dict[tuple, list[int]] = {}
    for k, part in enumerate(parts):
        kind = _KIND.get(part.shape)
        if kind is None or part.keepout:
            continue
        groups.setdefault((tuple(part.name.split("/")[:-1]), kind, bool(moving[k])), []).append(k)
    found: dict[tuple, list[int]] = {}
    rest: dict[tuple, list[int]] = {}
    for (level, kind, go), members in groups.items():
        if level and len(members) >= BATCH_PARTS:
            found[level, kind, go] = members
        else:
            rest.setdefault((kind, go), []).extend(members)
    for (kind, go), members in rest.items():
        if len(members) >= BATCH_PARTS:
            # under the assembly levels its parts share (a batch already there takes them in)
            level = tuple(os.path.commonprefix([parts[k].name.split("/")[:-1] for k in members]))
            found[level, kind, go] = sorted(found.get((level, kind, go), []) + members)
    return [Batch("/".join([root, *(escape(p) for p in level), ("_moving" if go else "") + _LEAF[kind]]), kind,
                  np.array(members), go) for (level, kind, go), members in found.items()]


def static_columns(batch: Batch, parts: Sequence[PartModel], poses: np.ndarray, unit: float) -> list[Column]:
    """A batch's one static row: its instances' sizes and names (:func:`shapes`)
    and, for parts that stay put, their poses (`poses` (n, 4, 4) of all
    `parts`, metres; :func:`placement`); a moving batch's poses come per frame."""
    members = [parts[k] for k in batch.members]
    at = [] if batch.moving else placement(batch.archetype, members, poses[None, batch.members], unit)
    return shapes(batch.archetype, members, unit) + at


def alone(count: int, found: Sequence[Batch]) -> np.ndarray:
    """(count,) bool: the parts in none of the batches `found`, drawn as entities of their own."""
    mask = np.ones(count, bool)
    for b in found:
        mask[b.members] = False
    return mask


def _sizes(kind: type, parts: Sequence[PartModel], unit: float) -> np.ndarray:
    """(n, 3) each part's MuJoCo size as the archetype's half-sizes, or (n, 2) radius and half-length."""
    size = np.array([np.resize(np.asarray(p.size, float), 3) for p in parts]) / unit
    if kind is rr.Ellipsoids3D:
        sphere = np.array([p.shape == "sphere" for p in parts])
        size[sphere] = size[sphere, :1]
    return size if kind in (rr.Boxes3D, rr.Ellipsoids3D) else size[:, :2]


def placement(kind: type, parts: Sequence[PartModel], poses: np.ndarray, unit: float) -> list[Column]:
    """The instances' poses, one row per frame: `poses` (F, n, 4, 4) in
    metres, as the archetype's centres (a capsule: its first end sphere's
    centre, the capsule running along its +z) and turns (x, y, z, w)."""
    frames, n = poses.shape[:2]
    rot = poses[..., :3, :3].reshape(-1, 3, 3)
    centre = poses[..., :3, 3].reshape(-1, 3) / unit
    turns = Rotation.from_matrix(rot).as_quat()                         # x, y, z, w
    if kind is rr.Capsules3D:
        half = np.tile(_sizes(kind, parts, unit)[:, 1], frames)
        at = column(kind.descriptor_translations(), vec3(centre - rot[:, :, 2] * half[:, None]), np.full(frames, n))
    else:
        at = column(kind.descriptor_centers(), vec3(centre), np.full(frames, n))
    return [at, column(kind.descriptor_quaternions(), quats(turns), np.full(frames, n))]


def shapes(kind: type, parts: Sequence[PartModel], unit: float) -> list[Column]:
    """The instances' sizes, filled, and names (labels, not drawn), in one row."""
    n = len(parts)
    size = _sizes(kind, parts, unit)
    if kind in (rr.Boxes3D, rr.Ellipsoids3D):
        sized = [column(kind.descriptor_half_sizes(), vec3(size), [n])]
    else:
        sized = [column(kind.descriptor_lengths(), floats(2.0 * size[:, 1], np.float32), [n]),
                 column(kind.descriptor_radii(), floats(size[:, 0], np.float32), [n])]
    solid = rr.components.FillModeBatch([rr.components.FillMode.Solid]).as_arrow_array()
    return [*sized, column(kind.descriptor_fill_mode(), solid, [1]),
            column(kind.descriptor_labels(), strings([p.name for p in parts]), [n]),
            column(kind.descriptor_show_labels(), rr.components.ShowLabelsBatch([False]).as_arrow_array(), [1])]
