"""The bench's random scenes (cablecheck.bench.scenes): proper rotations, the sizes
asked for, cable points at the step asked for, the same scene for the same
seed, and a synthetic scene through the real parser."""

from __future__ import annotations

import numpy as np

from cablecheck.bench.scenes import RADIUS, make_scene, random_rotation, synthetic_scene
from cablecheck.checker.shapes import ShapeType


def test_random_rotations_are_proper():
    rng = np.random.default_rng(3)
    for _ in range(50):
        q = random_rotation(rng)
        assert np.allclose(q.T @ q, np.eye(3), atol=1e-12) and np.isclose(np.linalg.det(q), 1.0)


def test_make_scene_has_the_sizes_and_spacing_asked_for_and_repeats_by_seed():
    cables, parts = make_scene(seed=5, n_cables=3, n_points=12, n_prims=4, n_meshes=1, step=0.01)
    assert len(cables) == 3 and len(parts) == 5
    assert sum(p.shape.type is ShapeType.MESH for p in parts) == 1
    for c in cables:
        assert c.points.shape == (12, 3) and c.radius == RADIUS
        assert np.allclose(np.linalg.norm(np.diff(c.points, axis=0), axis=1), 0.01, rtol=1e-9)
    again, parts2 = make_scene(seed=5, n_cables=3, n_points=12, n_prims=4, n_meshes=1, step=0.01)
    assert all(np.array_equal(a.points, b.points) for a, b in zip(cables, again))
    assert all(np.array_equal(a.pose, b.pose) for a, b in zip(parts, parts2))
    other, _ = make_scene(seed=6, n_cables=3, n_points=12, n_prims=4, n_meshes=1, step=0.01)
    assert not np.array_equal(cables[0].points, other[0].points)


def test_synthetic_scene_is_a_parsed_scene_of_the_sizes_asked_for():
    scene = synthetic_scene(n_cables=2, segments=10, n_parts=3)
    assert len(scene.cables) == 2 and len(scene.parts) == 3
    assert all(c.segments == 10 and c.radius == RADIUS for c in scene.cables)
    assert all(p.shape in ("box", "cylinder", "capsule", "sphere", "ellipsoid") for p in scene.parts)
