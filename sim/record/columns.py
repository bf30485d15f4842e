"""Arrow columns for rerun's `send_columns`, built from numpy directly.

rerun's archetype helpers (`rr.Scalars.columns(...)`, `rr.AnyValues.columns(...)`,
`rr.Ellipsoids3D.columns(...)`) convert and check their input field by field in
Python, tens to hundreds of microseconds per entity; at the close of a short
run, when every entity is sent, that was most of the recording's cost. Here
each component's arrow array is made in one call from numpy and sent with
the archetype's own descriptor.

Not here: what is logged where (the other modules of `cablecheck.record`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pyarrow as pa
import rerun as rr

VEC3 = pa.list_(pa.field("item", pa.float32(), nullable=False), 3)
"""A point or a size: three float32, as rerun stores them."""
STRIP = pa.list_(pa.field("item", VEC3, nullable=False))
"""A line strip: a list of points."""
QUAT = pa.list_(pa.field("item", pa.float32(), nullable=False), 4)
"""A rotation: a quaternion's x, y, z, w as four float32, as rerun stores it."""
MAT3 = pa.list_(pa.field("item", pa.float32(), nullable=False), 9)
"""A 3x3 matrix: nine float32, column by column, as rerun stores it."""


@dataclass(frozen=True)
class Column:
    """A component column for `send_columns` (rerun's `ComponentColumn` reads
    no more than these two methods): the component's values, `values`, cut
    into one row per entry of `offsets`."""

    descriptor: rr.ComponentDescriptor
    values: pa.Array
    offsets: np.ndarray

    def component_descriptor(self) -> rr.ComponentDescriptor:
        return self.descriptor

    def as_arrow_array(self) -> pa.Array:
        return pa.ListArray.from_arrays(pa.array(self.offsets), self.values)


def column(descriptor: rr.ComponentDescriptor, values: pa.Array,
           lengths: np.ndarray | Sequence[int] | None = None) -> Column:
    """A component column: `values` split into rows of `lengths` values (default one each)."""
    if lengths is None:
        offsets = np.arange(len(values) + 1, dtype=np.int32)
    else:
        offsets = np.zeros(len(lengths) + 1, np.int32)
        np.cumsum(lengths, out=offsets[1:])
    return Column(descriptor, values, offsets)


@dataclass(frozen=True)
class Once:
    """A component given once, in the first row of a column of `rows` rows,
    and absent (null) from the others: a style or a legend label that every
    later row finds (rerun looks each component up at or before the time
    shown; an empty value, unlike an absent one, would clear it). A column
    of `send_columns` like :class:`Column`."""

    descriptor: rr.ComponentDescriptor
    value: pa.Array
    rows: int

    def component_descriptor(self) -> rr.ComponentDescriptor:
        return self.descriptor

    def as_arrow_array(self) -> pa.Array:
        offsets = np.full(self.rows + 1, len(self.value), np.int32)
        offsets[0] = 0
        valid = np.zeros(self.rows, bool)
        valid[0] = True
        # from buffers: `ListArray.from_arrays(..., mask=)` imports pyarrow.compute (tens of ms)
        return pa.Array.from_buffers(pa.list_(self.value.type), self.rows,
                                     [pa.py_buffer(np.packbits(valid, bitorder="little")), pa.py_buffer(offsets)],
                                     null_count=self.rows - 1, children=[self.value])


@dataclass(frozen=True)
class _Ready:
    """An arrow array already in its component's type (rerun's `ComponentBatchLike`)."""

    array: pa.Array

    def as_arrow_array(self) -> pa.Array:
        return self.array


def named(values: dict[str, pa.Array]) -> list[rr.DescribedComponentBatch]:
    """Values named by component with no archetype, as `rr.AnyValues` makes
    them (whose type guessing, the first time in a process, imports
    `dateutil` and tries `pandas`: milliseconds)."""
    return [rr.DescribedComponentBatch(_Ready(v), rr.ComponentDescriptor(k)) for k, v in values.items()]


def vec3(points: np.ndarray) -> pa.Array:
    """(n, 3) points or sizes as rerun's `Vec3D` array."""
    flat = np.ascontiguousarray(points, np.float32).reshape(-1)
    return pa.FixedSizeListArray.from_arrays(pa.array(flat), type=VEC3)


def quats(quaternions: np.ndarray) -> pa.Array:
    """(n, 4) quaternions (x, y, z, w) as rerun's `RotationQuat` array."""
    flat = np.ascontiguousarray(quaternions, np.float32).reshape(-1)
    return pa.FixedSizeListArray.from_arrays(pa.array(flat), type=QUAT)


def mat3(matrices: np.ndarray) -> pa.Array:
    """(n, 3, 3) matrices as rerun's `Mat3x3` array (column-major)."""
    flat = np.ascontiguousarray(np.swapaxes(np.asarray(matrices).reshape(-1, 3, 3), 1, 2), np.float32).reshape(-1)
    return pa.FixedSizeListArray.from_arrays(pa.array(flat), type=MAT3)


def strips(points: np.ndarray, offsets: np.ndarray) -> pa.Array:
    """Line strips as rerun's `LineStrip3D` array: strip k runs through
    `points[offsets[k]:offsets[k + 1]]` ((n, 3) points, (k + 1,) offsets)."""
    return pa.ListArray.from_arrays(pa.array(np.asarray(offsets, np.int32)), vec3(points), type=STRIP)


def floats(values, dtype: type = np.float64) -> pa.Array:
    """A float array (rerun's scalars are float64, radii and widths float32)."""
    return pa.array(np.asarray(values, dtype))


def strings(texts: Sequence[str]) -> pa.Array:
    return pa.array(texts, pa.utf8())


def rgba(colours: Sequence[Sequence[int]] | np.ndarray) -> pa.Array:
    """(n, 3 or 4) 8-bit colours as rerun's packed RGBA (uint32)."""
    c = np.asarray(colours, np.uint32).reshape(len(colours), -1)
    if c.shape[1] == 3:
        c = np.concatenate([c, np.full((len(c), 1), 255, np.uint32)], axis=1)
    return pa.array((c[:, 0] << 24) | (c[:, 1] << 16) | (c[:, 2] << 8) | c[:, 3])


def times(seconds: np.ndarray) -> rr.TimeColumn:
    """The `sim_time` index of a column."""
    return rr.TimeColumn("sim_time", duration=seconds)


@dataclass(frozen=True)
class Sometimes:
    """A component given in some rows of a column of `rows` rows (`given`,
    (rows,) bool, True where a row has a value) and absent from the others,
    each of those found by the viewer's look-up at or before the time shown
    (as :class:`Once`, which is this with the first row alone). `values`:
    the given rows' values laid end to end, `lengths`: how many each row
    has. A column of `send_columns`."""

    descriptor: rr.ComponentDescriptor
    values: pa.Array
    given: np.ndarray
    lengths: np.ndarray

    def component_descriptor(self) -> rr.ComponentDescriptor:
        return self.descriptor

    def as_arrow_array(self) -> pa.Array:
        given = np.asarray(self.given, bool)
        sizes = np.zeros(len(given), np.int32)
        sizes[given] = self.lengths
        offsets = np.zeros(len(given) + 1, np.int32)
        np.cumsum(sizes, out=offsets[1:])
        return pa.Array.from_buffers(pa.list_(self.values.type), len(given),
                                     [pa.py_buffer(np.packbits(given, bitorder="little")), pa.py_buffer(offsets)],
                                     null_count=int((~given).sum()), children=[self.values])

