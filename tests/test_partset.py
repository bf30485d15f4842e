"""Part sets built in whole arrays: the same per-part data as one part at a time, trees that
answer box queries as brute force does."""

import numpy as np
import trimesh
from hypothesis import given, settings, strategies as st

from cablecheck.checker.bvh import LEAF_SIZE, TriangleForest
from cablecheck.checker.partset import PROBE_DEPTH, PartSet
from cablecheck.checker.shapes import Shape, ShapeType, mesh_shape
from cablecheck.checker.tessellate import part_surface

TOL = 5e-3


def mixed_parts():
    torus = trimesh.creation.torus(0.3, 0.1, major_sections=16, minor_sections=8)
    return ([f"a/p{k}" for k in range(7)],
            [Shape(ShapeType.BOX, [0.1, 0.2, 0.3]), Shape(ShapeType.SPHERE, [0.4]),
             Shape(ShapeType.PLANE, []), mesh_shape(torus.vertices, torus.faces),
             Shape(ShapeType.CYLINDER, [0.2, 0.5]), Shape(ShapeType.CAPSULE, [0.1, 0.3]),
             Shape(ShapeType.ELLIPSOID, [0.3, 0.2, 0.1])])


def test_per_part_data_equal_one_part_at_a_time():
    names, shapes = mixed_parts()
    ps = PartSet.build(names, shapes, tolerance=TOL)
    assert list(ps.plane) == [False, False, True, False, False, False, False]
    for k, sh in enumerate(shapes):
        surf = part_surface(sh, TOL)
        tris = ps.tris[ps.tri_part == k]
        np.testing.assert_allclose(tris, surf.vertices[surf.faces], atol=1e-12)
        verts = ps.vertices[ps.vert_part == k]
        np.testing.assert_allclose(verts, surf.vertices, atol=1e-12)
        assert ps.error[k] == surf.error and ps.closed[k] == surf.closed
        if surf.plane:
            assert np.all(ps.lo[k] == -np.inf) and np.all(ps.hi[k] == np.inf) and ps.size[k] == 0
            continue
        # the box holds the true shape: the triangles' box grown by the error
        np.testing.assert_allclose(ps.lo[k], surf.vertices.min(axis=0) - surf.error)
        np.testing.assert_allclose(ps.hi[k], surf.vertices.max(axis=0) + surf.error)
        # probes: the vertices, then the centroids set in along the normals
        probes = ps.probes[ps.probe_start[k]:ps.probe_start[k + 1]]
        nrm = ps.normals[ps.tri_part == k]
        cen = tris.mean(axis=1) - PROBE_DEPTH * ps.size[k] * nrm
        np.testing.assert_allclose(probes, np.concatenate([surf.vertices, cen]), atol=1e-12)
        # unit outward normals (closed surfaces: the centroid probes lie inside)
        np.testing.assert_allclose(np.linalg.norm(nrm, axis=1), 1.0)


def test_edge_pseudonormals_sum_the_two_faces_of_each_edge():
    names, shapes = mixed_parts()
    ps = PartSet.build(names, shapes, tolerance=TOL)
    k = 4                                                        # the cylinder: closed
    sel = np.flatnonzero(ps.tri_part == k)
    tris = ps.tris[sel]
    key = {}
    for t, tri in zip(sel, tris):                               # reference, face by face
        for e in range(3):
            a, b = tuple(np.round(tri[e], 12)), tuple(np.round(tri[(e + 1) % 3], 12))
            key.setdefault(frozenset((a, b)), []).append(t)
    for t, tri in zip(sel, tris):
        for e in range(3):
            a, b = tuple(np.round(tri[e], 12)), tuple(np.round(tri[(e + 1) % 3], 12))
            faces = key[frozenset((a, b))]
            assert len(faces) == 2
            np.testing.assert_allclose(ps.edge_normals[t, e], ps.normals[faces].sum(axis=0), atol=1e-12)


@settings(max_examples=40, deadline=None)
@given(st.integers(0, 2 ** 32 - 1), st.integers(1, 6), st.booleans())
def test_forest_query_matches_brute_force(seed, parts, stacked):
    rng = np.random.default_rng(seed)
    counts = rng.integers(0, 5 * LEAF_SIZE, parts)               # some parts without triangles
    n = int(counts.sum())
    part = np.repeat(np.arange(parts), counts)
    lo = rng.uniform(-5, 5, (n, 3))
    if stacked:                                                  # equal centres: any split is a median
        lo[: n // 2] = 1.0
    hi = lo + rng.uniform(0, 1, (n, 3))
    forest = TriangleForest.build(lo, hi, part, parts)
    # every triangle is in exactly one leaf of its own part's tree, leaves small
    leaf = forest.left < 0
    assert np.all(forest.count[leaf] <= LEAF_SIZE) and np.sort(forest.order).tolist() == list(range(n))
    q = 30
    q_part = rng.integers(0, parts, q)
    q_lo = rng.uniform(-6, 6, (q, 3))
    q_hi = q_lo + rng.uniform(0, 5, (q, 3))
    qi, ti = forest.query(q_part, q_lo, q_hi)
    got = sorted(zip(qi.tolist(), ti.tolist()))
    want = sorted((a, t) for a in range(q) for t in range(n)
                  if part[t] == q_part[a] and np.all(lo[t] <= q_hi[a]) and np.all(q_lo[a] <= hi[t]))
    assert got == want
    # node boxes hold their triangles
    for node in np.flatnonzero(leaf)[:50]:
        tri = forest.order[forest.first[node]:forest.first[node] + forest.count[node]]
        assert np.all(forest.node_lo[node] <= lo[tri]) and np.all(hi[tri] <= forest.node_hi[node])


def test_empty_and_plane_only_sets():
    ps = PartSet.build(["floor"], [Shape(ShapeType.PLANE, [])])
    assert len(ps.tris) == 0 and ps.forest.root.tolist() == [-1]
    ps = PartSet.build([], [])
    assert len(ps.tris) == 0 and len(ps.lo) == 0


def test_solids_of_revolution_about_their_z_axis():
    """axial: the sphere, capsule, cylinder and an ellipsoid with equal x and
    y radii are unchanged by turning about their z axis; a box (even a
    square one), a flattened ellipsoid, a mesh and a plane are not marked.
    Checked on the shapes' own signed distances: turning points about z
    changes none of an axial part's."""
    from cablecheck.checker.shapes import signed_distance

    box = trimesh.creation.box(extents=[1, 1, 1])
    shapes = [Shape(ShapeType.SPHERE, [0.3]), Shape(ShapeType.CAPSULE, [0.2, 0.4]),
              Shape(ShapeType.CYLINDER, [0.2, 0.4]), Shape(ShapeType.ELLIPSOID, [0.3, 0.3, 0.5]),
              Shape(ShapeType.BOX, [0.3, 0.3, 0.5]), Shape(ShapeType.ELLIPSOID, [0.3, 0.2, 0.5]),
              mesh_shape(np.asarray(box.vertices), np.asarray(box.faces)), Shape(ShapeType.PLANE, [])]
    ps = PartSet.build([f"p{k}" for k in range(len(shapes))], shapes, tolerance=1e-2)
    assert ps.axial.tolist() == [True] * 4 + [False] * 4
    pts = np.random.default_rng(4).uniform(-0.8, 0.8, (200, 3))
    c, s = np.cos(0.7), np.sin(0.7)
    turned = pts @ np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]]).T
    for shape, axial in zip(shapes[:6], ps.axial[:6]):
        same = np.allclose(signed_distance(shape, pts)[0], signed_distance(shape, turned)[0], atol=1e-9)
        assert same == axial
