import numpy as np
import trimesh
from scipy.spatial.transform import Rotation

from cablecheck.checker.shapes import Shape, ShapeType, mesh_shape, signed_distance
from cablecheck.checker.spot import on_cable, on_cable_many, on_part, on_part_many


def _poses(rng, n):
    poses = np.tile(np.eye(4), (n, 1, 1))
    poses[:, :3, :3] = Rotation.random(n, random_state=rng.integers(1 << 30)).as_matrix()
    poses[:, :3, 3] = rng.uniform(-5.0, 5.0, (n, 3))
    return poses


def test_many_places_at_once_are_the_one_by_one_closest_points():
    rng = np.random.default_rng(3)
    m = trimesh.creation.torus(0.08, 0.02, major_sections=24, minor_sections=10)
    for shape in (Shape(ShapeType.BOX, [0.1, 0.05, 0.02]), mesh_shape(m.vertices, m.faces)):
        poses = _poses(rng, 12)
        where = poses[:, :3, 3] + rng.uniform(-0.15, 0.15, (12, 3))
        many = on_part_many(shape, poses, where)
        one = np.stack([on_part(shape, p, w) for p, w in zip(poses, where)])
        assert np.allclose(many, one, rtol=0, atol=1e-12)
        # the point lies on the surface, as far from `where` as the part is
        local = np.einsum("ni,nij->nj", where - poses[:, :3, 3], poses[:, :3, :3])
        d, _ = signed_distance(shape, local)
        assert np.allclose(np.linalg.norm(many - where, axis=1), np.abs(d), rtol=0, atol=1e-12)


def test_many_places_on_cables_are_the_one_by_one_closest_points():
    """Each place on its own copy of a wavy cable, s_b anywhere (ends too): the same point as one by one."""
    rng = np.random.default_rng(5)
    m, n = 40, 9
    x = np.linspace(0.0, 1.0, n)
    cables = np.stack([np.c_[x, 0.05 * np.sin(6 * x + ph), 0.02 * np.cos(4 * x)] for ph in rng.uniform(0, 6, m)])
    s_b = rng.uniform(-0.1, 1.2, m)
    s_b[:3] = (0.0, 1e9, -1.0)
    where = cables[np.arange(m), rng.integers(0, n, m)] + rng.normal(0, 0.03, (m, 3))
    many = on_cable_many(cables, s_b, where)
    one = np.stack([on_cable(c, s, w) for c, s, w in zip(cables, s_b, where)])
    assert np.allclose(many, one, rtol=0, atol=1e-12)
    # a single point is its own closest point
    assert np.allclose(on_cable_many(cables[:, :1], s_b, where), cables[:, 0])
