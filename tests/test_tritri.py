"""Triangle-triangle crossing, distance and translational contact against known answers."""

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from cablecheck.checker.tritri import (
    edge_edge_contact,
    edge_piercings,
    triangle_distance,
    triangles_cross,
    vertex_face_contact,
)

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


def _piercings_by_solving(src, dst):
    """Edge piercings found another way: each edge's line against the plane
    of dst solved as a 3x3 system ``p0 + s (p1 - p0) = d0 + u e1 + v e2``."""
    out = set()
    for m in range(len(src)):
        d0, e1, e2 = dst[m, 0], dst[m, 1] - dst[m, 0], dst[m, 2] - dst[m, 0]
        for k in range(3):
            p0, p1 = src[m, k], src[m, (k + 1) % 3]
            a = np.column_stack([p1 - p0, -e1, -e2])
            if abs(np.linalg.det(a)) < 1e-9:
                continue
            s, u, v = np.linalg.solve(a, d0 - p0)
            if 1e-9 < s < 1 - 1e-9 and u > 1e-9 and v > 1e-9 and u + v < 1 - 1e-9:
                out.add((m, k, round(float(s), 6)))
            elif -1e-9 <= s <= 1 + 1e-9 and -1e-9 <= u and -1e-9 <= v and u + v <= 1 + 1e-9:
                out.add((m, k, None))      # on a boundary: either answer
    return out


@settings(max_examples=40)
@given(st.integers(0, 2**32 - 1), st.sampled_from([1.0, 1e-3, 1e3]), st.sampled_from([0.0, 1e4]))
def test_edge_piercings_match_solved_lines(seed, scale, shift):
    """Random triangle pairs (many crossing): the piercings found are the
    edges whose line meets the other triangle's inside within the edge,
    solved as linear systems; in mm or m, far from the origin too."""
    rng = np.random.default_rng(seed)
    src = rng.uniform(-1, 1, (300, 3, 3))
    dst = rng.uniform(-1, 1, (300, 3, 3))
    dst[5:10, 2] = dst[5:10, 1]                      # zero-area targets: never pierced
    pair, edge, s = edge_piercings(src * scale + shift, dst * scale + shift)
    got = {(int(m), int(k)): float(x) for m, k, x in zip(pair, edge, s)}
    want = _piercings_by_solving(src, dst)
    sure = {(m, k): x for m, k, x in want if x is not None}
    loose = {(m, k) for m, k, x in want if x is None}
    assert set(sure) <= set(got) <= set(sure) | loose
    assert all(abs(got[key] - x) < 1e-5 for key, x in sure.items())
    assert not np.isin(pair, np.arange(5, 10)).any() and np.all((s > 0) & (s < 1))
    assert len(sure) > 20
