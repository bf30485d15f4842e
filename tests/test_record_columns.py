"""cablecheck.record.columns: arrow columns built from numpy equal rerun's own conversions.

The reference is rerun's archetype helpers (`rr.<Archetype>.columns(...)`),
which convert field by field; a column of `Once` is read back from a written
recording with rerun's own reader.
"""

from __future__ import annotations

import uuid
from pathlib import Path

import numpy as np
import pyarrow as pa
import rerun as rr
from hypothesis import given, settings, strategies as st
from rerun.chunk import RrdReader

from cablecheck.record.columns import Once, column, floats, mat3, rgba, strings, strips, times, vec3


def _rerun(columns) -> dict[str, pa.Array]:
    return {str(c.component_descriptor()): c.as_arrow_array() for c in columns}


@settings(max_examples=25, deadline=None)
@given(st.lists(st.integers(0, 4), min_size=1, max_size=8), st.integers(0, 2 ** 31))
def test_columns_equal_reruns_own(lengths, seed):
    rng = np.random.default_rng(seed)
    n = int(sum(lengths))
    centres, sizes = rng.normal(size=(n, 3)) * 1e3, rng.random((n, 3))
    labels = [f"spot {k}" for k in range(n)]
    ours = _rerun([column(rr.Ellipsoids3D.descriptor_centers(), vec3(centres), lengths),
                   column(rr.Ellipsoids3D.descriptor_half_sizes(), vec3(sizes), lengths),
                   column(rr.Ellipsoids3D.descriptor_labels(), strings(labels), lengths)])
    theirs = _rerun(rr.Ellipsoids3D.columns(centers=centres, half_sizes=sizes, labels=labels).partition(lengths))
    assert ours.keys() == theirs.keys()
    for key in ours:
        assert ours[key].type == theirs[key].type and ours[key].equals(theirs[key]), key
    values = rng.normal(size=len(lengths))
    (scalars,) = rr.Scalars.columns(scalars=values)
    assert column(rr.Scalars.descriptor_scalars(), floats(values)).as_arrow_array().equals(scalars.as_arrow_array())


def test_strips_radii_and_colours_equal_reruns_own():
    pts = np.arange(18, dtype=float).reshape(6, 3)
    ours = _rerun([column(rr.LineStrips3D.descriptor_strips(), strips(pts, [0, 2, 6]), [1, 1]),
                   column(rr.LineStrips3D.descriptor_radii(), floats([0.5, 2.0], np.float32)),
                   column(rr.LineStrips3D.descriptor_colors(), rgba([(255, 0, 230), (1, 2, 3)]))])
    theirs = _rerun(rr.LineStrips3D.columns(strips=[pts[:2], pts[2:]], radii=[0.5, 2.0],
                                            colors=[(255, 0, 230), (1, 2, 3)]))
    for key in ours:
        assert ours[key].type == theirs[key].type and ours[key].equals(theirs[key]), key
    (alpha,) = rr.LineStrips3D.columns(colors=[(255, 0, 230, 90), (1, 2, 3, 4)])
    assert rgba([(255, 0, 230, 90), (1, 2, 3, 4)]).equals(alpha.as_arrow_array().flatten())


@settings(max_examples=25, deadline=None)
@given(st.integers(1, 6), st.integers(0, 2 ** 31))
def test_poses_and_colours_equal_reruns_own(frames, seed):
    """Poses (translation, column-major rotation) and packed colours, as the
    recorder sends moving parts and part colours."""
    rng = np.random.default_rng(seed)
    poses = rng.normal(size=(frames, 4, 4)) * 1e2
    t = rr.Transform3D
    ours = _rerun([column(t.descriptor_translation(), vec3(poses[:, :3, 3])),
                   column(t.descriptor_mat3x3(), mat3(poses[:, :3, :3]))])
    theirs = _rerun(t.columns(translation=poses[:, :3, 3], mat3x3=poses[:, :3, :3]))
    assert ours.keys() == theirs.keys()
    for key in ours:
        assert ours[key].type == theirs[key].type and ours[key].equals(theirs[key]), key
    colours = rng.integers(0, 256, size=(frames, 4)).astype(np.uint8)
    for kind in (rr.Boxes3D, rr.Ellipsoids3D, rr.Capsules3D, rr.Cylinders3D):
        (theirs,) = kind.columns(colors=colours)
        assert column(kind.descriptor_colors(), rgba(colours)).as_arrow_array().equals(theirs.as_arrow_array())
    (theirs,) = rr.Mesh3D.columns(albedo_factor=colours)
    assert column(rr.Mesh3D.descriptor_albedo_factor(), rgba(colours)).as_arrow_array().equals(theirs.as_arrow_array())


def test_once_is_in_the_first_row_and_absent_from_the_others(tmp_path: Path):
    path = tmp_path / "once.rrd"
    rec = rr.RecordingStream(application_id="once", recording_id=uuid.uuid4())
    rec.save(str(path))
    rec.send_columns("line", indexes=[times(np.array([0.0, 0.5, 1.0]))],
                     columns=[column(rr.Scalars.descriptor_scalars(), floats([1.0, 2.0, 3.0])),
                              Once(rr.SeriesLines.descriptor_names(), strings(["the line"]), 3)])
    rec.disconnect()
    (chunk,) = [c for c in RrdReader(path).stream() if c.entity_path == "/line"]
    batch = chunk.to_record_batch()
    assert batch.column("SeriesLines:names").to_pylist() == [["the line"], None, None]
    assert batch.column("Scalars:scalars").to_pylist() == [[1.0], [2.0], [3.0]]
