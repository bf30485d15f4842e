"""A mesh's acceleration data (cablecheck.checker.meshdata): closure decides the sign,
and the box tree still finds every point's and segment's nearest triangle."""

import numpy as np
import pytest
import trimesh

from cablecheck.checker.shapes import mesh_shape, signed_distance

pytestmark = pytest.mark.filterwarnings("error")


def test_open_mesh_is_unsigned():
    m = trimesh.creation.box(extents=[1.0, 1.0, 1.0])
    faces = m.faces[2:]  # drop one side
    shape = mesh_shape(m.vertices, faces)
    assert not shape.closed
    d, _ = signed_distance(shape, np.array([[0.0, 0, 0], [0.1, 0.1, 0.1]]))
    assert np.all(d > 0)


def test_sliver_mesh_nearest_and_segment_distance_are_the_brute_force_ones():
    """A CAD-style tessellation: a finely meshed cylinder wall plus long slivers
    (flat caps fanned from one corner). The box tree must still find the
    nearest triangle of every point and segment that every triangle tried
    finds, with or without an upper bound from a point of the segment."""
    from cablecheck.checker import meshnearest, segments
    from cablecheck.checker.closest import point_triangle, segment_triangle
    rng = np.random.default_rng(7)
    wall = trimesh.creation.cylinder(0.04, 0.2, sections=96)
    fine = wall.subdivide()
    # fan caps: long slivers from one rim vertex (reach ~ the diameter)
    rim = np.stack([0.04 * np.cos(np.linspace(0, 2 * np.pi, 97)[:-1]),
                    0.04 * np.sin(np.linspace(0, 2 * np.pi, 97)[:-1])], axis=1)
    verts = [fine.vertices]
    faces = [fine.faces]
    for z in (-0.1, 0.1):
        base = sum(len(v) for v in verts)
        verts.append(np.column_stack([rim, np.full(96, z)]))
        faces.append(np.array([[base, base + k, base + k + 1] for k in range(1, 95)]))
    v, f = np.concatenate(verts), np.concatenate(faces)
    md = mesh_shape(v, f).mesh
    p = rng.uniform([-0.08, -0.08, -0.15], [0.08, 0.08, 0.15], (200, 3))
    d = meshnearest.mesh_nearest(md, p)[0]
    rows = np.repeat(np.arange(len(p)), len(md.faces))
    fi = np.tile(np.arange(len(md.faces)), len(p))
    brute = point_triangle(p[rows], md.a[fi], md.b[fi], md.c[fi])[0].reshape(len(p), -1).min(axis=1)
    assert np.array_equal(d, brute)
    a, b = p[:60], p[:60] + rng.normal(size=(60, 3)) * 0.01
    ds = segments.mesh_segment_unsigned(md, a, b)[0]
    rows = np.repeat(np.arange(len(a)), len(md.faces))
    fi = np.tile(np.arange(len(md.faces)), len(a))
    brute_s = segment_triangle(a[rows], b[rows], md.a[fi], md.b[fi], md.c[fi])[0].reshape(len(a), -1).min(axis=1)
    assert np.allclose(ds, brute_s, rtol=0, atol=1e-15)
    # an upper bound from the midpoint's distance (the checker's), and from a looser point
    mid = meshnearest.mesh_nearest(md, 0.5 * (a + b))[0]
    for upper in (mid, mid * 1.5 + 0.01):
        du, tu, fu = segments.mesh_segment_unsigned(md, a, b, upper=upper)
        assert np.allclose(du, brute_s, rtol=0, atol=1e-15)
        again = segment_triangle(a, b, md.a[fu], md.b[fu], md.c[fu])
        assert np.array_equal(again[0], du) and np.array_equal(again[1], tu)
    # a bound that is none (below the true distance) is measured the usual way
    du = segments.mesh_segment_unsigned(md, a, b, upper=0.5 * brute_s)[0]
    assert np.allclose(du, brute_s, rtol=0, atol=1e-15)
    # a cap: segments farther (their midpoints outside) are answered at it, the others exactly,
    # and their signed distances are those without it
    from cablecheck.checker.segments import segment_sd_mesh
    sd = segment_sd_mesh(md, a, b)[0]
    from cablecheck.checker.meshdata import sd_mesh

    signed_mid = sd_mesh(md, 0.5 * (a + b))[0]
    cap = np.full(len(a), float(np.median(brute_s)))
    du, tu, fu = segments.mesh_segment_unsigned(md, a, b, upper=signed_mid, cap=cap)
    far = (brute_s > cap) & (signed_mid > 0)
    assert far.any() and (~far).any()
    assert np.all(du[far] == cap[far]) and np.all(fu[far] == -1)
    assert np.allclose(du[~far], brute_s[~far], rtol=0, atol=1e-15)
    capped = segment_sd_mesh(md, a, b, signed_mid, cap)[0]
    assert np.array_equal(capped[~far], sd[~far]) and np.all(capped[far] <= sd[far] + 1e-15)


def test_faces_within_holds_every_triangle_that_comes_within_the_radius():
    """The box tree's lists against every triangle measured: nothing within the radius left out."""
    from cablecheck.checker.closest import point_triangle
    from cablecheck.checker.meshnearest import faces_within
    rng = np.random.default_rng(3)
    m = trimesh.creation.icosphere(3, 0.05)
    md = mesh_shape(m.vertices, m.faces).mesh
    q = rng.normal(size=(300, 3)) * 0.06
    radius = rng.uniform(0.0, 0.03, len(q))
    rows, faces = faces_within(md, q, radius)
    got = set(zip(rows.tolist(), faces.tolist()))
    r = np.repeat(np.arange(len(q)), len(md.faces))
    f = np.tile(np.arange(len(md.faces)), len(q))
    d = point_triangle(q[r], md.a[f], md.b[f], md.c[f])[0]
    need = set(zip(r[d <= radius[r]].tolist(), f[d <= radius[r]].tolist()))
    assert need and need <= got


def test_limit_with_the_callers_lower_bounds_is_the_same_answer():
    """signed_distance with a limit and the lower bounds the caller took from
    distance_bounds answers as with the limit alone: exact below the limit,
    the same bound beyond it."""
    from cablecheck.checker.shapes import distance_bounds
    rng = np.random.default_rng(11)
    shape = mesh_shape(*(lambda m: (m.vertices, m.faces))(trimesh.creation.icosphere(2, 0.05)))
    p = rng.normal(size=(400, 3)) * 0.05
    limit = rng.uniform(0.0, 0.03, len(p))
    lower, _ = distance_bounds(shape, p)
    d0, c0 = signed_distance(shape, p, limit)
    d1, c1 = signed_distance(shape, p, limit, lower)
    exact, _ = signed_distance(shape, p)
    assert np.array_equal(d0, d1) and np.array_equal(np.isnan(c0), np.isnan(c1))
    near = exact < limit
    assert near.any() and (~near).any() and np.array_equal(d1[near], exact[near])
    assert np.all(d1[~near] <= exact[~near] + 1e-12)
