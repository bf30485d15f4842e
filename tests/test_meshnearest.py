"""Nearest triangles and their sign (cablecheck.checker.meshnearest): the brute-force
nearest over every triangle, both roads (triangle boxes and centroid tree),
the winding number's inside, and a box mesh against the box primitive."""

from pathlib import Path

import numpy as np
import pytest
import trimesh
from shaperefs import winding_number

from cablecheck.checker.shapes import Shape, ShapeType, mesh_shape, signed_distance

pytestmark = pytest.mark.filterwarnings("error")


def test_box_mesh_equals_box_primitive():
    h = np.array([0.3, 0.2, 0.1])
    m = trimesh.creation.box(extents=2 * h)
    mesh = mesh_shape(m.vertices, m.faces)
    assert mesh.closed
    rng = np.random.default_rng(2)
    p = rng.normal(size=(500, 3)) * 0.3
    p[:5] = [[0.3, 0, 0], [0.3, 0.2, 0], [0.3, 0.2, 0.1], [0, 0, 0], [0.1, 0.1, 0.1]]
    dm, _ = signed_distance(mesh, p)
    db, _ = signed_distance(Shape(ShapeType.BOX, h), p)
    assert np.allclose(dm, db, rtol=0, atol=1e-12)


def test_torus_mesh_matches_brute_force():
    from cablecheck.checker.closest import point_triangle

    m = trimesh.creation.torus(0.08, 0.02, major_sections=40, minor_sections=16)
    shape = mesh_shape(m.vertices, m.faces)
    assert shape.closed
    rng = np.random.default_rng(4)
    p = rng.uniform(-0.12, 0.12, size=(80, 3)) * [1, 1, 0.4]
    d, cl = signed_distance(shape, p)
    # Brute force over every triangle, sign from the winding number.
    tri = m.vertices[m.faces]
    n, f = len(p), len(tri)
    rows = np.repeat(np.arange(n), f)
    dd = point_triangle(p[rows], *(np.tile(tri[:, k], (n, 1)) for k in range(3)))[0].reshape(n, f).min(axis=1)
    inside = winding_number(m, p) > 0.5
    assert inside.any() and (~inside).any()
    assert np.allclose(d, np.where(inside, -dd, dd), rtol=0, atol=1e-13)


def test_small_mesh_nearest_is_the_brute_force_nearest(monkeypatch):
    """Low-poly meshes take the triangle-box road in mesh_nearest: the same
    distances as every triangle tried, and the same as the centroid-tree road."""
    from cablecheck.checker import meshnearest
    from cablecheck.checker.closest import point_triangle
    rng = np.random.default_rng(4)
    for mesh in (trimesh.creation.box([0.04, 0.03, 0.05]), trimesh.creation.icosphere(0, 0.02),
                 trimesh.load(Path(__file__).resolve().parents[1] / "scenes" / "meshes" / "l_bracket.stl")):
        md = mesh_shape(mesh.vertices, mesh.faces).mesh
        assert len(md.faces) <= meshnearest.BOX_FACES
        p = rng.uniform(mesh.bounds[0] - 0.5 * mesh.extents, mesh.bounds[1] + 0.5 * mesh.extents, (300, 3))
        p[:20] = mesh.vertices[rng.integers(0, len(mesh.vertices), 20)]          # on corners
        d, cl, face, _ = meshnearest.mesh_nearest(md, p)
        rows = np.repeat(np.arange(len(p)), len(md.faces))
        fi = np.tile(np.arange(len(md.faces)), len(p))
        brute = point_triangle(p[rows], md.a[fi], md.b[fi], md.c[fi])[0].reshape(len(p), -1).min(axis=1)
        assert np.array_equal(d, brute)
        assert np.allclose(np.linalg.norm(p - cl, axis=1), d, rtol=1e-12, atol=1e-15)
        with monkeypatch.context() as mp:
            mp.setattr(meshnearest, "BOX_FACES", 0)                                  # the centroid-tree road
            assert np.array_equal(d, meshnearest.mesh_nearest(md, p)[0])
