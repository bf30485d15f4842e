"""Triangle-triangle crossing, distance and translational contact against known answers."""

import numpy as np
import pytest

from checker.tritri import edge_edge_contact, triangle_distance, triangles_cross, vertex_face_contact

T = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0]])


def one(a):
    return np.asarray(a, float)[None]


def test_piercing_triangles_cross_both_ways():
    b = np.array([[0.2, 0.2, -1], [0.2, 0.2, 1], [2, 2, 0]])
    assert triangles_cross(one(T), one(b))[0] and triangles_cross(one(b), one(T))[0]


@pytest.mark.parametrize("other, why", [
    ([[0.2, 0.2, 0], [0.2, 0.3, 1], [0.5, 0.2, 1]], "a corner on the face"),
    ([[0.0, 0, 0], [1, 0, 0], [0, -1, 0]], "a shared edge, coplanar"),
    ([[0.0, 0, 0], [1, 0, 0], [0.5, 0, 1]], "a shared edge, at an angle"),
    ([[0.1, 0.1, 0], [0.5, 0.1, 0], [0.1, 0.5, 0]], "coplanar, lying on it"),
    ([[0.5, -1, 0], [0.5, 0, 0], [0.5, -1, 1]], "edge meeting edge at one point"),
])
def test_touching_is_not_crossing(other, why):
    assert not triangles_cross(one(T), one(other))[0], why
    assert not triangles_cross(one(other), one(T))[0], why


def test_crossing_is_translation_and_scale_invariant():
    b = np.array([[0.2, 0.2, -1], [0.2, 0.2, 1], [2, 2, 0]])
    for shift, scale in ((1e4, 1.0), (0.0, 1e-3), (-3e3, 1e3)):
        assert triangles_cross(one(T * scale + shift), one(b * scale + shift))[0]


def test_distance_parallel_and_skew():
    d, p, q = triangle_distance(one(T), one(T + [0, 0, 2]))
    assert d[0] == pytest.approx(2.0)
    skew = np.array([[2.0, -1, 1], [2, 1, 1], [3, 0, 5]])   # nearest: corner (1,0,0) to edge x=2,z=1
    d, p, q = triangle_distance(one(T), one(skew))
    assert d[0] == pytest.approx(np.sqrt(2.0))


def test_vertex_face_contact_exact_and_direction_sensitive():
    p = np.array([[0.25, 0.25, -3.0]])
    t = vertex_face_contact(p, one(T), np.array([0, 0, 1.0]), np.zeros(1), 10.0)
    assert t[0] == pytest.approx(3.0, abs=1e-15)
    assert np.isinf(vertex_face_contact(p, one(T), np.array([0, 0, -1.0]), np.zeros(1), 10.0))[0]
    assert np.isinf(vertex_face_contact(p, one(T), np.array([0, 0, 1.0]), np.zeros(1), 2.0))[0]
    # parallel to the face: no contact
    assert np.isinf(vertex_face_contact(np.array([[0.2, 0.2, 0]]), one(T), np.array([1.0, 0, 0]),
                                        np.zeros(1), 10.0))[0]


def test_edge_edge_contact_skew_edges():
    a0, a1 = np.array([[-1.0, 0, 0]]), np.array([[1.0, 0, 0]])
    b0, b1 = np.array([[0.0, -1, 5]]), np.array([[0.0, 1, 5]])
    t, p = edge_edge_contact(a0, a1, b0, b1, np.array([0, 0, 1.0]), 10.0)
    assert t[0] == pytest.approx(5.0) and np.allclose(p[0], [0, 0, 5])
    t, _ = edge_edge_contact(a0, a1, b0 + [3, 0, 0], b1 + [3, 0, 0], np.array([0, 0, 1.0]), 10.0)
    assert np.isinf(t[0])
