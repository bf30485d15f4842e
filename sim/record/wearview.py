"""The wear map in the review recording.

`wear_map/<cable>`: each cable's rest shape coloured per arc-length bin
(grey where nothing touched, else viridis over sliding, or over contact time
when nothing slid); `wear/<cable>/<measure>`: a bar chart per measure
(`contact_time`, `sliding`, `bend_cycles`) over the bins.

Not here: measuring wear (`checker.wear`).
"""

from __future__ import annotations

from functools import cache

import numpy as np
import pyarrow as pa
import rerun as rr
from rerun.components import TensorDataBatch

from sim.build import Built
from sim.record.columns import column, floats, rgba, strips
from sim.record.style import escape

_VIRIDIS = np.array([(68, 1, 84), (59, 82, 139), (33, 145, 140), (94, 201, 98), (253, 231, 37)], float)
_UNWORN = (200, 200, 200)


def wear_colours(sliding: np.ndarray, contact_time: np.ndarray) -> np.ndarray:
    """(B, 3) uint8 colours of wear bins: grey where nothing touched, else
    viridis over sliding (or over contact time when nothing slid)."""
    values = np.asarray(sliding, float)
    touched = np.asarray(contact_time, float) > 0.0
    if not (values[touched] > 0).any():
        values = np.asarray(contact_time, float)
    top = float(values.max()) if values.size else 0.0
    x = np.clip(values / top, 0.0, 1.0) if top > 0 else np.zeros_like(values)
    pos = x * (len(_VIRIDIS) - 1)
    lo = np.minimum(np.floor(pos).astype(int), len(_VIRIDIS) - 2)
    f = (pos - lo)[:, None]
    rgb = (1 - f) * _VIRIDIS[lo] + f * _VIRIDIS[lo + 1]
    rgb[~touched] = _UNWORN
    return np.round(rgb).astype(np.uint8)


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


def send_wear(rec: rr.RecordingStream, built: Built, wear: list, rest: list[np.ndarray] | None,
              unit: float) -> None:
    """Each cable's wear (:class:`checker.wear.CableWear`): colour along its rest
    shape (`rest`, metres; else as routed) and a bar chart per measure, each
    one static chunk."""
    bar, line = rr.BarChart, rr.LineStrips3D
    for i, w in enumerate(wear):
        name = escape(w.name)
        edges = np.append(w.s, w.length) / unit
        at, widths = tensor_1d(edges[:-1]), floats(np.diff(edges), np.float32)
        for measure, values in (("contact_time", w.contact_time), ("sliding", w.sliding / unit),
                                ("bend_cycles", w.bend_cycles)):
            rec.send_columns(f"wear/{name}/{measure}", indexes=[], columns=[
                column(bar.descriptor_values(), tensor_1d(values)), column(bar.descriptor_abscissa(), at),
                column(bar.descriptor_widths(), widths, [len(widths)])])
        pts = np.asarray(rest[i] if rest is not None else built.cables[i].routed, float) / unit
        ends = np.stack([pts[:-1], pts[1:]], axis=1).reshape(-1, 3)          # one two-point strip per bin
        k = len(pts) - 1
        rec.send_columns(f"wear_map/{name}", indexes=[], columns=[
            column(line.descriptor_strips(), strips(ends, np.arange(0, 2 * k + 1, 2)), [k]),
            column(line.descriptor_radii(), floats([built.cables[i].radius / unit], np.float32), [1]),
            column(line.descriptor_colors(), rgba(wear_colours(w.sliding, w.contact_time)), [k])])
