"""The bound grid (cablecheck.checker.meshgrid): nearest triangles through its candidate
lists and its lower bounds under a limit, against brute force."""

import numpy as np
import pytest
import trimesh
from hypothesis import given, settings, strategies as st
from shaperefs import winding_number

from cablecheck.checker.shapes import Shape, ShapeType, mesh_shape, signed_distance

pytestmark = pytest.mark.filterwarnings("error")


def _brute_signed(m, shape, p):
    from cablecheck.checker.closest import point_triangle
    md = shape.mesh
    rows = np.repeat(np.arange(len(p)), len(md.faces))
    fi = np.tile(np.arange(len(md.faces)), len(p))
    dd = point_triangle(p[rows], md.a[fi], md.b[fi], md.c[fi])[0].reshape(len(p), -1).min(axis=1)
    return np.where(winding_number(m, p) > 0.5, -dd, dd) if shape.closed else dd


_TORUS = trimesh.creation.torus(0.08, 0.02, major_sections=32, minor_sections=12)


@settings(max_examples=20, deadline=None)
@given(st.integers(0, 2**31), st.sampled_from([1.0, 1000.0]), st.floats(-50.0, 50.0), st.booleans())
def test_grid_nearest_and_limit_bounds_are_the_brute_force_ones(seed, scale, shift, open_mesh):
    """Nearest triangles through the bound grid's candidate lists are every
    triangle's nearest, in any fill order; with a limit, a point is either
    answered exactly or by a lower bound above the limit (mm and m, away
    from the origin, open and closed meshes)."""
    rng = np.random.default_rng(seed)
    v = _TORUS.vertices * scale + shift * scale
    f = _TORUS.faces[3:] if open_mesh else _TORUS.faces
    m = trimesh.Trimesh(v, f, process=False)
    centre = shift * scale
    p = centre + rng.uniform(-0.13, 0.13, size=(120, 3)) * [1, 1, 0.5] * scale
    exact = _brute_signed(m, mesh_shape(v, f), p)
    shape = mesh_shape(v, f)
    assert shape.closed is not open_mesh
    d, _ = signed_distance(shape, p)
    assert np.allclose(d, exact, rtol=0, atol=1e-13 * scale * (1 + abs(shift)))
    # a fresh memo (mesh_shape would hand back the same shape), filled in another order
    again = Shape(ShapeType.MESH, np.zeros(0), vertices=shape.vertices, faces=shape.faces)
    order = rng.permutation(len(p))
    d2 = np.empty(len(p))
    for part in np.array_split(order, 4):
        d2[part] = signed_distance(again, p[part])[0]
    assert np.array_equal(d, d2)
    limit = rng.uniform(0.0, 0.03, len(p)) * scale
    fresh = Shape(ShapeType.MESH, np.zeros(0), vertices=shape.vertices, faces=shape.faces)
    dl, cl = signed_distance(fresh, p, limit)
    skipped = np.isnan(cl[:, 0])
    assert np.array_equal(dl[~skipped], d[~skipped])
    assert np.all(dl[skipped] > limit[skipped]) and np.all(dl[skipped] <= d[skipped])
    assert np.all(~skipped[d < limit])
