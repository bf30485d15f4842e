"""The wear map in the review recording.

`wear_map/<cable>`: each cable's rest shape coloured per arc-length bin on
one scale for the whole run (:func:`wear_scale`): viridis from nothing to
the most any bin of any cable slid, grey where a bin slid no more than the
noise floor or touched nothing (over contact time instead when nothing in
the run slid more than the floor), and the cable's name at its middle;
`wear_map/legend`: the scale as a colour bar under the cables with its
values and units; `wear_map/parts/<path>`: the parts the cables touch, as
at t = 0 (the rest shapes' time), translucent (many of one kind under one
assembly level: one entity, `cablecheck.record.batches`).
`wear/<cable>/<measure>`: a bar chart per measure (`contact_time`,
`sliding`, `bend_cycles`) over the bins.

Not here: measuring wear (`cablecheck.checker.wear`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from functools import cache

import numpy as np
import pyarrow as pa
import rerun as rr
from rerun.components import TensorDataBatch

from cablecheck.build.built import Built
from cablecheck.record.columns import column, floats, rgba, strips
from cablecheck.record.style import escape

_VIRIDIS = np.array([(68, 1, 84), (59, 82, 139), (33, 145, 140), (94, 201, 98), (253, 231, 37)], float)
_UNWORN = (200, 200, 200)
LABEL_COLOUR = (230, 230, 230)
PART_FADED = (160, 160, 170, 60)
"""The touched parts in the wear view: translucent, so the cables' colours show through."""
LEGEND_STEPS = 24
"""Colours in the legend's bar."""


CHARTED_CABLES = 8
"""Cables whose wear bar charts (and twist chart) the recording holds, the
most worn (most twisted) first: a harness of 64 cables would have 256 chart
tabs, each a view of the layout and kilobytes of recording (a chart's
schema alone), 3.3 MB of 24 on a 64-cable harness. The wear map and the
report cover every cable; the summary says which cables are charted."""


def charted(names: Sequence[str], amounts: Sequence[float]) -> tuple[str, ...]:
    """The :data:`CHARTED_CABLES` names of the largest `amounts` (ties: the
    earlier name), in the order given."""
    order = np.argsort(-np.asarray(amounts, float), kind="stable")[:CHARTED_CABLES]
    return tuple(names[k] for k in sorted(order.tolist()))


def worn_amounts(wear: list, scale: WearScale) -> list[float]:
    """Each cable's most worn bin on the run's scale's measure (sliding, else contact time)."""
    return [float(np.max(w.sliding if scale.measure == "sliding" else w.contact_time, initial=0.0)) for w in wear]


def charts_note(cables: int, worn: Sequence[str], twisted_of: int, twisted: Sequence[str]) -> str:
    """A paragraph for the summary when the recording charts fewer cables
    than it has (:data:`CHARTED_CABLES`), naming those it charts; empty otherwise."""
    notes = []
    if len(worn) < cables:
        notes.append(f"wear bar charts of the {len(worn)} most worn of {cables} cables ({', '.join(worn)})")
    if len(twisted) < twisted_of:
        notes.append(f"twist charts of the {len(twisted)} most twisted of {twisted_of} ({', '.join(twisted)})")
    if not notes:
        return ""
    return "\n\nCharted in this recording: " + "; ".join(notes) + ". The wear map and the report cover every cable.\n"


SLIDING_FLOOR = 1e-6
"""Sliding below this fraction of the run's most is not wear (a millionth of
the worst bin; on the 8-bit colour map it would be the lowest colour anyway)."""
ROUNDING_ULPS = 16
"""Units in the last place one step's sliding may carry from rounding alone:
a material point is taken into the touched part's frame at two steps (a
rotation and a translation each, a few roundings of coordinates as large as
the scene's extent) and differenced."""


@dataclass(frozen=True)
class WearScale:
    """One colour scale for the whole run's wear map.

    Attributes:
      measure: "sliding" (scene units), or "contact_time" (s) when no bin of
        any cable slid more than the floor.
      top: the most of any bin of any cable (the scale's end), in the
        measure's units.
      floor: at or below this nothing counts (grey), in the measure's units:
        for sliding the larger of :data:`SLIDING_FLOOR` of `top` and the
        rounding a run can add up (steps x :data:`ROUNDING_ULPS` x machine
        epsilon x the scene's extent); for contact time 0.
      units: the measure's units.
    """

    measure: str
    top: float
    floor: float
    units: str

    def legend(self) -> str:
        """The scale in words, as the wear view's title gives it."""
        if self.measure == "sliding":
            return (f"sliding 0 to {self.top:.4g} {self.units}; grey: no contact, "
                    f"or slid at most {self.floor:.2g} {self.units}")
        return f"contact time 0 to {self.top:.4g} s (nothing slid); grey: no contact"


def wear_scale(wear: list, unit: float = 1.0, units: str = "m", steps: int = 0, extent: float = 0.0) -> WearScale:
    """The run's wear scale over every cable's bins (`unit`: metres per
    scene unit; `steps`: the run's simulated steps and `extent`: the largest
    coordinate of the scene, metres, which bound the rounding in sliding)."""
    sliding = np.concatenate([np.asarray(w.sliding, float) for w in wear]) if wear else np.zeros(0)
    top = float(sliding.max()) if sliding.size else 0.0
    rounding = steps * ROUNDING_ULPS * np.finfo(float).eps * extent
    floor = max(SLIDING_FLOOR * top, rounding)
    if top > floor:
        return WearScale("sliding", top / unit, floor / unit, units)
    contact = np.concatenate([np.asarray(w.contact_time, float) for w in wear]) if wear else np.zeros(0)
    return WearScale("contact_time", float(contact.max()) if contact.size else 0.0, 0.0, "s")


def viridis(x: np.ndarray) -> np.ndarray:
    """(n, 3) viridis colours (float, 0-255) of `x` in [0, 1]."""
    x = np.clip(np.asarray(x, float), 0.0, 1.0)
    pos = x * (len(_VIRIDIS) - 1)
    lo = np.minimum(np.floor(pos).astype(int), len(_VIRIDIS) - 2)
    f = (pos - lo)[:, None]
    return (1 - f) * _VIRIDIS[lo] + f * _VIRIDIS[lo + 1]


def wear_colours(sliding: np.ndarray, contact_time: np.ndarray, scale: WearScale | None = None,
                 unit: float = 1.0) -> np.ndarray:
    """(B, 3) uint8 colours of one cable's wear bins (`sliding` metres,
    `contact_time` s) on `scale` (default: this cable's own, with no
    rounding floor): grey where nothing touched or the bin's value is at or
    below the floor, else viridis from 0 to the scale's top."""
    sliding = np.asarray(sliding, float)
    contact = np.asarray(contact_time, float)
    if scale is None:
        scale = wear_scale([_Bins(sliding, contact)], unit)
    values = sliding / unit if scale.measure == "sliding" else contact
    counts = (contact > 0.0) & (values > scale.floor)
    rgb = viridis(values / scale.top if scale.top > 0 else np.zeros_like(values))
    rgb[~counts] = _UNWORN
    return np.round(rgb).astype(np.uint8)


@dataclass(frozen=True)
class _Bins:
    sliding: np.ndarray
    contact_time: np.ndarray


@cache
def _tensor_parts() -> tuple:
    """What every 1-D float64 tensor shares: the arrow type, its shape's
    type, the F64 arm of its buffer union (index and type), the (empty)
    arrays of the other arms, the union's type-code and offset buffers, its
    (null) names and the offsets of a one-row list."""
    dt = TensorDataBatch._ARROW_DATATYPE
    union = dt.field("buffer").type
    k = [f.name for f in union].index("F64")
    empty = [pa.nulls(0, type=f.type) for f in union]
    codes = [pa.array([k], pa.int8()).buffers()[1], pa.array([0], pa.int32()).buffers()[1]]
    return (dt, dt.field("shape").type, union, k, union[k].type, empty, codes, pa.nulls(1, dt.field("names").type),
            pa.py_buffer(np.array([0, 1], np.int32)))


def tensor_1d(values: np.ndarray) -> pa.StructArray:
    """A 1-D float64 vector as rerun's tensor component (`TensorDataBatch`'s
    arrow type), built directly from buffers: rerun's own converter casts
    its arrays, and the first cast of a process imports `pyarrow.compute`
    (tens of ms)."""
    v = np.ascontiguousarray(values, np.float64).ravel()
    dt, shape_type, union, k, f64_type, empty, codes, names, one_row = _tensor_parts()
    shape = pa.Array.from_buffers(shape_type, 1, [None, one_row], children=[pa.array(np.array([len(v)], np.uint64))])
    children = list(empty)
    children[k] = pa.Array.from_buffers(f64_type, 1, [None, pa.py_buffer(np.array([0, len(v)], np.int32))],
                                        children=[pa.array(v)])
    buffer = pa.Array.from_buffers(type=union, length=1, children=children, buffers=[None, *codes])
    return pa.Array.from_buffers(dt, 1, [None], children=[shape, names, buffer])


def send_bars(rec: rr.RecordingStream, path: str, at: np.ndarray, values: np.ndarray,
              widths: np.ndarray | None = None) -> None:
    """A bar chart of `values` at the positions `at` along a cable, one static
    chunk; each bar `widths` wide, else as wide as the gap to the next (the
    last as the one before)."""
    at = np.asarray(at, float)
    if widths is None:
        gaps = np.diff(at)
        widths = np.append(gaps, gaps[-1] if len(gaps) else 1.0)
    bar = rr.BarChart
    rec.send_columns(path, indexes=[], columns=[
        column(bar.descriptor_values(), tensor_1d(values)), column(bar.descriptor_abscissa(), tensor_1d(at)),
        column(bar.descriptor_widths(), floats(widths, np.float32), [len(widths)])])


def send_wear(rec: rr.RecordingStream, built: Built, wear: list, rest: list[np.ndarray] | None,
              unit: float, scale: WearScale, part_shapes: dict | None = None, part_batches: list = (),
              charts: Sequence[str] | None = None) -> None:
    """Each cable's wear (:class:`cablecheck.checker.wear.CableWear`): colour along its rest
    shape (`rest`, metres; else as routed) on the run's `scale`, its name, and
    for the cables named in `charts` (default: every cable) a bar chart per
    measure, each one static chunk; the scale's colour bar;
    `part_shapes`: name -> (archetype in its own frame, pose at t = 0 in
    metres) of the parts the cables touch, drawn beside them; `part_batches`:
    (entity path, archetype, columns) of those touched parts drawn many to an entity
    (`cablecheck.record.batches`)."""
    line = rr.LineStrips3D
    shapes = []
    for i, w in enumerate(wear):
        name = escape(w.name)
        edges = np.append(w.s, w.length) / unit
        for measure, values in (("contact_time", w.contact_time), ("sliding", w.sliding / unit),
                                ("bend_cycles", w.bend_cycles)) if charts is None or w.name in charts else ():
            send_bars(rec, f"wear/{name}/{measure}", edges[:-1], values, np.diff(edges))
        pts = np.asarray(rest[i] if rest is not None else built.cables[i].routed, float) / unit
        shapes.append(pts)
        ends = np.stack([pts[:-1], pts[1:]], axis=1).reshape(-1, 3)          # one two-point strip per bin
        k = len(pts) - 1
        rec.send_columns(f"wear_map/{name}", indexes=[], columns=[
            column(line.descriptor_strips(), strips(ends, np.arange(0, 2 * k + 1, 2)), [k]),
            column(line.descriptor_radii(), floats([built.cables[i].radius / unit], np.float32), [1]),
            column(line.descriptor_colors(), rgba(wear_colours(w.sliding, w.contact_time, scale, unit)), [k])])
        mid = pts[len(pts) // 2] + np.array([0.0, 0.0, 2.0 * built.cables[i].radius / unit])
        rec.log(f"wear_map/{name}/name", rr.Points3D([mid], radii=[-1.0], colors=[LABEL_COLOUR],
                                                     labels=[w.name], show_labels=True), static=True)
    for part_name, (shape, pose) in (part_shapes or {}).items():
        path = "wear_map/parts/" + "/".join(escape(p) for p in part_name.split("/"))
        faded = (column(rr.Mesh3D.descriptor_albedo_factor(), rgba([PART_FADED])) if isinstance(shape, rr.Mesh3D)
                 else column(type(shape).descriptor_colors(), rgba([PART_FADED])))
        rec.log(path, shape, rr.Transform3D(translation=pose[:3, 3] / unit, mat3x3=pose[:3, :3]), static=True)
        rec.send_columns(path, indexes=[], columns=[faded])
    for path, kind, columns in part_batches:
        rec.send_columns(path, indexes=[], columns=[*columns, column(kind.descriptor_colors(), rgba([PART_FADED]), [1])])
    if shapes:
        send_legend(rec, np.concatenate(shapes), scale, max(c.radius for c in built.cables) / unit)


def send_legend(rec: rr.RecordingStream, points: np.ndarray, scale: WearScale, radius: float) -> None:
    """The scale as a colour bar under `points` (the cables, scene units):
    along x from the cables' least to greatest x, a grey swatch before it,
    labelled at its ends and middle with values and units."""
    lo, hi = points.min(axis=0), points.max(axis=0)
    span = max(float(hi[0] - lo[0]), 1e-9)
    y = float(lo[1]) - 0.15 * max(float(hi[1] - lo[1]), span)
    z = float(lo[2]) - 0.1 * span
    n = LEGEND_STEPS
    x = lo[0] + span * np.linspace(0.0, 1.0, n + 1)
    line = np.stack([x, np.full(n + 1, y), np.full(n + 1, z)], axis=1)
    ends = np.stack([line[:-1], line[1:]], axis=1).reshape(-1, 3)
    colours = np.round(viridis((np.arange(n) + 0.5) / n)).astype(np.uint8)
    grey = np.array([[lo[0] - 0.12 * span, y, z], [lo[0] - 0.04 * span, y, z]])
    r = 1.5 * radius
    strips_ = [*ends.reshape(-1, 2, 3), grey]
    rec.log("wear_map/legend/bar", rr.LineStrips3D(strips_, radii=[r], colors=[*colours, _UNWORN]), static=True)
    u = scale.units
    what = "sliding" if scale.measure == "sliding" else "contact time"
    grey_label = (f"grey: no contact, or slid <= {scale.floor:.2g} {u}" if scale.measure == "sliding"
                  else "grey: no contact")
    at = np.array([[lo[0], y, z], [lo[0] + 0.5 * span, y, z], [hi[0], y, z], grey.mean(axis=0)])
    at[:, 2] -= 3.0 * r
    at[3, 2] += 6.0 * r                    # the grey swatch's label above it, clear of the bar's "0"
    labels = ["0", f"{0.5 * scale.top:.3g} {u}", f"{scale.top:.3g} {u} {what} (most of any cable)", grey_label]
    rec.log("wear_map/legend/values", rr.Points3D(at, radii=[-1.0], colors=[LABEL_COLOUR], labels=labels,
                                                  show_labels=True), static=True)
