"""The skip rule's part-pair bound (cablecheck.checker.advance.partpairs): box separations are lower bounds on distances."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh
from hypothesis import given, settings, strategies as st
from helpers import examples
from strategies import coords, poses

from cablecheck.checker.advance.partpairs import PartPairGaps, PartSolids, part_pair_bounds
from cablecheck.checker.parts import check_parts
from cablecheck.checker.partset import PartSet
from cablecheck.checker.shapes import Shape, ShapeType, mesh_shape

pytestmark = pytest.mark.filterwarnings("error")


def _corners(half: np.ndarray) -> np.ndarray:
    return np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]) * half


def test_boxes_apart_along_an_axis_and_a_box_above_a_plane():
    """Analytic: two unit cubes 0.5 apart along x; a cube 2 above a floor plane."""
    cube = Shape(ShapeType.BOX, [0.5, 0.5, 0.5])
    ps = PartSet.build(["a", "b", "floor"], [cube, cube, Shape(ShapeType.PLANE, [])])
    pose = np.tile(np.eye(4), (3, 1, 1))
    pose[1, :3, 3] = [1.5, 0.0, 0.0]
    pose[0, :3, 3] = [0.0, 0.0, 2.5]
    pose[1, 2, 3] = 2.5
    bound = part_pair_bounds(ps, ps.place(pose), np.array([0, 0, 1]), np.array([1, 2, 2]))
    assert bound == pytest.approx([0.5, 2.0, 2.0])


@settings(max_examples=60, deadline=None)
@given(coords(3, 0.01, 0.1), coords(3, 0.01, 0.1), poses(reach=0.2), poses(reach=0.2))
def test_bound_never_exceeds_the_distance_of_the_boxes(half_a, half_b, pose_a, pose_b):
    """The bound is at most the distance between any point of one box and
    any point of the other (checked on their corners and centres)."""
    ps = PartSet.build(["a", "b"], [Shape(ShapeType.BOX, half_a), Shape(ShapeType.BOX, half_b)])
    bound = part_pair_bounds(ps, ps.place(np.stack([pose_a, pose_b])), np.array([0]), np.array([1]))[0]
    pa = np.vstack([_corners(half_a), np.zeros(3)]) @ pose_a[:3, :3].T + pose_a[:3, 3]
    pb = np.vstack([_corners(half_b), np.zeros(3)]) @ pose_b[:3, :3].T + pose_b[:3, 3]
    assert bound <= np.linalg.norm(pa[:, None] - pb[None], axis=2).min() + 1e-12


@given(st.floats(0.0, 0.5), st.floats(0.0, 0.5))
def test_pairs_clear_while_the_moves_stay_below_the_bound(move_a, move_b):
    """Two parts 1 apart (bound 1, clearance 0.1): clear exactly while the
    motion of one relative to the other (the moves at right angles: their
    length) stays below 0.9 (less the rounding margin)."""
    gaps = PartPairGaps(np.array([0.5, 0.5]), 0.1)
    start = np.tile(np.eye(4), (2, 1, 1))
    gaps.start(start, (np.array([0]), np.array([1])), np.array([1.0]), mu=0.0)
    now = start.copy()
    now[0, 0, 3] += move_a
    now[1, 1, 3] -= move_b
    assert gaps.clear_at(now) == (np.sqrt(move_a * move_a + move_b * move_b) < 0.9)
    gaps.stop()
    assert not gaps.clear_at(start)


@given(st.floats(0.0, 1.5), st.floats(0.0, 1.5))
def test_failing_pairs_are_the_pairs_whose_bound_fails(move_a, move_c):
    """Three parts, pairs (0, 1) and (1, 2) bound 1 apart (clearance 0.1):
    a pair is failing exactly when its moves reach 0.9; no pairs after a stop."""
    gaps = PartPairGaps(np.array([0.5, 0.5, 0.5]), 0.1)
    start = np.tile(np.eye(4), (3, 1, 1))
    gaps.start(start, (np.array([0, 1]), np.array([1, 2])), np.array([1.0, 1.0]), mu=0.0)
    now = start.copy()
    now[0, 0, 3] += move_a
    now[2, 1, 3] -= move_c
    fi, fj = gaps.failing_at(now)
    want = [(0, 1)] * (move_a >= 0.9) + [(1, 2)] * (move_c >= 0.9)
    assert list(zip(fi.tolist(), fj.tolist())) == want
    assert gaps.clear_at(now) == (not want)
    gaps.stop()
    assert gaps.failing_at(start) is None


def _solids(ps: PartSet) -> PartSolids:
    return PartSolids(ps.lo, ps.hi, ps.axial, ps.error)


def _radius(ps: PartSet) -> np.ndarray:
    corner = np.maximum(np.abs(ps.lo), np.abs(ps.hi))
    return np.sqrt(np.einsum("ij,ij->i", corner, corner))


def _turn_z(angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    out = np.eye(4)
    out[:2, :2] = [[c, -s], [s, c]]
    return out


def _gaps(ps: PartSet, start: np.ndarray, clearance: float, solids: bool = True) -> PartPairGaps:
    i, j = np.array([0]), np.array([1])
    gaps = PartPairGaps(_radius(ps), clearance, _solids(ps) if solids else None)
    gaps.start(start, (i, j), part_pair_bounds(ps, ps.place(start), i, j))
    return gaps


@pytest.mark.parametrize("hinge", [ShapeType.CYLINDER, ShapeType.BOX])
def test_a_panel_swinging_round_a_knuckle(hinge):
    """A door panel 8 from a knuckle (half-width 12), swinging 60 degrees
    round the knuckle's axis, clearance 5: round a cylinder nothing moves
    relative to the solid (clear at every angle); round a box of the
    cylinder's size, a state is clear while a corner of the panel may have
    moved by less than the 3 left (a turn of 3 / 420 rad, the panel's far
    corners 420 from the axis), or while the boxes at the state itself are
    more than 5 apart along a box axis: along the panel, its near end 20
    from the axis less the box's 12 (cos + sin); along the box's x axis,
    the panel's near corner at 20 cos - 5 sin less 12 (past 5 apart up to
    about 20 degrees, not from there on)."""
    size = [12.0, 12.0, 20.0] if hinge is ShapeType.BOX else [12.0, 20.0]
    ps = PartSet.build(["knuckle", "panel"], [Shape(hinge, size), Shape(ShapeType.BOX, [200.0, 5.0, 150.0])],
                       tolerance=0.5)
    start = np.tile(np.eye(4), (2, 1, 1))
    start[1, :3, 3] = [220.0, 0.0, 0.0]
    gaps = _gaps(ps, start, 5.0)
    assert gaps.ok
    seen = set()
    for angle in np.linspace(0.0, np.pi / 3, 61):
        now = start.copy()
        now[1] = _turn_z(angle) @ start[1]
        if hinge is ShapeType.CYLINDER:
            assert gaps.clear_at(now)
            continue
        reach = np.hypot(420.0, 5.0) * 2 * np.sin(angle / 2)         # the far corners' move
        c, s = np.cos(angle), np.sin(angle)
        apart = max(20.0 - 12.0 * (c + s), 20.0 * c - 5.0 * s - 12.0)   # along the panel, along the box
        if min(abs(reach - 3.0), abs(apart - 5.0)) > 1e-6:
            want = reach < 3.0 or apart > 5.0
            assert gaps.clear_at(now) == want
            seen.add((reach < 3.0, apart > 5.0))
    assert hinge is ShapeType.CYLINDER or seen == {(True, True), (False, True), (False, False)}


def test_a_floor_tilted_with_a_box_on_it_moves_nothing_relative_to_it():
    """A floor plane and a box 2 above it, tilted and carried together: the
    plane turned (its world move unbounded), the box did not move in the
    plane's frame; lifted 1 more in that frame it is still clear, sunk by
    1.95 it is not (clearance 0.1)."""
    ps = PartSet.build(["floor", "box"], [Shape(ShapeType.PLANE, []), Shape(ShapeType.BOX, [0.5, 0.5, 0.5])])
    start = np.tile(np.eye(4), (2, 1, 1))
    start[1, 2, 3] = 2.5
    carry = _turn_z(0.7)
    carry[:3, :3] = carry[:3, :3] @ np.array([[1, 0, 0], [0, np.cos(0.4), -np.sin(0.4)], [0, np.sin(0.4), np.cos(0.4)]])
    carry[:3, 3] = [3.0, 1.0, -2.0]
    gaps = _gaps(ps, start, 0.1)
    assert gaps.ok and np.isinf(gaps.moves(carry @ start)[0])
    for lift, clear in ((0.0, True), (1.0, True), (-1.95, False)):
        now = carry @ start
        now[1] = carry @ _lift(start[1], lift)
        assert gaps.clear_at(now) == clear


def _lift(pose: np.ndarray, dz: float) -> np.ndarray:
    out = pose.copy()
    out[2, 3] += dz
    return out


def test_parts_moving_together_move_nothing_relative_to_each_other():
    """Two boxes 1 apart carried together by a large rigid motion: the world
    moves add up to far more than the gap, the relative move is 0."""
    cube = Shape(ShapeType.BOX, [0.5, 0.5, 0.5])
    ps = PartSet.build(["a", "b"], [cube, cube])
    start = np.tile(np.eye(4), (2, 1, 1))
    start[1, 0, 3] = 2.0
    carry = _turn_z(1.0)
    carry[:3, 3] = [5.0, -3.0, 2.0]
    now = carry @ start
    assert _gaps(ps, start, 0.1).clear_at(now)
    assert _gaps(ps, start, 0.1, solids=False).clear_at(now)                # (radii alone: relative too)
    world = PartPairGaps(_radius(ps), 0.1, _solids(ps))
    world.start(start, (np.array([0]), np.array([1])), np.array([1.0]))
    assert (world.moves(now) > 1.0).all()                                  # each part moved farther
    moved = now.copy()
    moved[1] = _turn_z(0.0) @ now[1]
    moved[1, :3, 3] += carry[:3, :3] @ np.array([-0.95, 0.0, 0.0])         # then 0.95 closer: inside 0.1
    assert not _gaps(ps, start, 0.1).clear_at(moved)


@settings(max_examples=40, deadline=None)
@given(coords(3, -1.0, 1.0), coords(3, -2.0, 2.0), poses(reach=3.0), poses(reach=3.0))
def test_corner_moves_bound_every_point_of_the_box(lo_hi, shift, start, now):
    """The world move of a boxed part is its farthest corner's: at least the
    move of any point of its box, at most the radius bound."""
    half = np.abs(lo_hi) + 0.1
    ps = PartSet.build(["a"], [Shape(ShapeType.BOX, half)])
    start, now = start[None].copy(), now[None].copy()
    start[0, :3, 3] += shift
    plain = PartPairGaps(_radius(ps), 0.0)
    boxed = PartPairGaps(_radius(ps), 0.0, _solids(ps))
    for g in (plain, boxed):
        g.start(start, (np.zeros(0, np.int64), np.zeros(0, np.int64)), np.zeros(0))
    dp = boxed.moves(now)[0]
    u = np.random.default_rng(0).uniform(-1, 1, (500, 3)) * half
    u = np.vstack([u, _corners(half)])
    move = np.linalg.norm(u @ (now[0, :3, :3] - start[0, :3, :3]).T + (now[0, :3, 3] - start[0, :3, 3]), axis=1)
    assert move.max() <= dp * (1 + 1e-12) + 1e-12
    assert dp == pytest.approx(move.max(), rel=1e-9, abs=1e-12)           # attained at a corner
    assert dp <= plain.moves(now)[0] * (1 + 1e-12) + 1e-12


def _shape(kind, size):
    if kind == "mesh":
        tm = trimesh.creation.icosphere(subdivisions=1, radius=float(size[0]))
        return mesh_shape(np.asarray(tm.vertices), np.asarray(tm.faces))
    return Shape(kind, size)


def _random_rotation(rng) -> np.ndarray:
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    q = q * np.sign(np.diag(r))
    return q if np.linalg.det(q) > 0 else -q


def _nudge(rng, amount: float) -> np.ndarray:
    """A rigid motion turning by about ``amount`` rad and moving by up to ``amount``."""
    axis = rng.normal(size=3)
    axis /= np.linalg.norm(axis)
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    out = np.eye(4)
    out[:3, :3] = np.eye(3) + np.sin(amount) * k + (1 - np.cos(amount)) * k @ k
    out[:3, 3] = rng.uniform(-amount, amount, 3)
    return out


@pytest.mark.parametrize("seed", [0, 1])
def test_a_pair_proven_clear_has_no_record(seed):
    """Brute force against the part-part check itself: part b drawn near
    part a, then turned about a's axis by any angle, nudged, and both
    carried by a rigid motion (the world moves are large, the relative one
    a turn about the axis plus a little); whenever the condition says clear,
    the check at the new poses has no record for the pair. Coarse
    tessellations (errors up to 1e-2) make a curved part's triangles
    measure below its true distance. Many drawn pairs are proven clear,
    after large turns about an axis too."""
    rng = np.random.default_rng(seed)
    kinds = [ShapeType.BOX, ShapeType.SPHERE, ShapeType.CYLINDER, ShapeType.CAPSULE, "mesh"]
    clearance = 0.05
    proven = turned = 0
    for _ in range(200):
        ka, kb = kinds[rng.integers(5)], kinds[rng.integers(5)]
        ps = PartSet.build(["a", "b"], [_shape(ka, rng.uniform(0.05, 0.3, 3)), _shape(kb, rng.uniform(0.05, 0.3, 3))],
                           tolerance=1e-2)
        # b along a drawn direction, where the box bound is just past the clearance
        scale = np.linspace(0.0, 1.2, 61)
        far = ps.tiled(np.array([0, 1]), len(scale))
        poses = np.tile(np.eye(4), (2 * len(scale), 1, 1))
        poses[1::2, :3, :3] = _random_rotation(rng)
        poses[1::2, :3, 3] = scale[:, None] * rng.normal(size=3) / np.sqrt(3)
        sep = part_pair_bounds(far, far.place(poses), np.arange(0, 2 * len(scale), 2), np.arange(1, 2 * len(scale), 2))
        pick = np.flatnonzero(sep > clearance + rng.uniform(0.0, 0.05))
        if not len(pick):
            continue
        pose_b = poses[2 * pick[0] + 1]
        start = np.stack([np.eye(4), pose_b])
        carry = _nudge(rng, 3.0)
        turn = rng.uniform(-np.pi, np.pi)
        now = np.stack([carry, carry @ _turn_z(turn) @ _nudge(rng, rng.uniform(0.0, 0.05)) @ pose_b])
        gaps = _gaps(ps, start, clearance)
        if gaps.ok and gaps.clear_at(now):
            assert check_parts(ps, ps.place(now), clearance) == []
            proven += 1
            turned += abs(turn) > 0.5 and ps.axial[0]
    assert proven > 25 and turned > 10


def _far_start(ps: PartSet, clearance: float) -> PartPairGaps:
    """The pair's bound started with the parts far apart (a plane first, so
    the other part is 50 above it): any later state is a large move of one
    relative to the other, which only the state's own box separation can
    prove clear."""
    start = np.tile(np.eye(4), (2, 1, 1))
    start[1, 2, 3] = 50.0
    return _gaps(ps, start, clearance)


_KINDS = [ShapeType.BOX, ShapeType.SPHERE, ShapeType.CYLINDER, ShapeType.CAPSULE, "mesh", ShapeType.PLANE]


def _pair_set(ka, kb, size_a, size_b) -> PartSet:
    shapes = [Shape(ShapeType.PLANE, []) if k is ShapeType.PLANE else _shape(k, size)
              for k, size in ((ka, size_a), (kb, size_b))]
    return PartSet.build(["a", "b"], shapes, tolerance=1e-2)


@settings(max_examples=80, deadline=None)
@given(st.sampled_from(_KINDS), st.sampled_from(_KINDS[:5]), coords(3, 0.05, 0.3), coords(3, 0.05, 0.3),
       poses(reach=0.6), poses(reach=0.6))
def test_a_pair_its_boxes_prove_apart_has_no_record(ka, kb, size_a, size_b, pose_a, pose_b):
    """Brute force against the part-part check: two parts (a plane, a
    primitive or a coarse mesh, then a finite part) at drawn poses, their
    bound started far apart; whenever the condition says clear at the drawn
    poses (proven by the boxes' separation there: the moves are large), the
    check there has no record."""
    ps = _pair_set(ka, kb, size_a, size_b)
    gaps = _far_start(ps, 0.05)
    now = np.stack([pose_a, pose_b])
    if gaps.ok and gaps.clear_at(now):
        assert check_parts(ps, ps.place(now), 0.05) == []


def test_states_far_apart_are_proven_by_their_boxes_and_near_ones_not():
    """The same draws counted (seeded): many states are proven clear only by
    their own boxes' separation, and the others include states whose
    boxes are 0.01 past the clearance or less (none proven)."""
    rng = np.random.default_rng(3)
    proven = near = 0
    for _ in range(300):
        ka, kb = _KINDS[rng.integers(6)], _KINDS[rng.integers(5)]
        ps = _pair_set(ka, kb, rng.uniform(0.05, 0.3, 3), rng.uniform(0.05, 0.3, 3))
        gaps = _far_start(ps, 0.05)
        now = np.tile(np.eye(4), (2, 1, 1))
        now[1, :3, :3] = _random_rotation(rng)
        now[1, :3, 3] = rng.uniform(-0.8, 0.8, 3)
        sep = part_pair_bounds(ps, ps.place(now), np.array([0]), np.array([1]))[0]
        clear = gaps.clear_at(now)
        assert clear == (sep > 0.05 + 1e-6) or abs(sep - 0.05) < 1e-6
        if clear:
            assert check_parts(ps, ps.place(now), 0.05) == []
        proven += clear
        near += sep <= 0.06
    assert proven > 50 and near > 50


@settings(max_examples=30, deadline=None)
@given(st.lists(poses(reach=0.6), min_size=6, max_size=6), st.integers(1, 3))
def test_many_states_and_pairs_at_once_answer_as_one_by_one(drawn, k):
    """The condition for S states and several pairs at once is each
    state's own answer (the states and pairs laid out in one pass)."""
    cube, ball = Shape(ShapeType.BOX, [0.1, 0.2, 0.15]), Shape(ShapeType.SPHERE, [0.12])
    ps = PartSet.build(["floor", "a", "b"], [Shape(ShapeType.PLANE, []), cube, ball])
    start = np.tile(np.eye(4), (3, 1, 1))
    start[1, :3, 3] = [0.0, 0.0, 50.0]
    start[2, :3, 3] = [50.0, 0.0, 100.0]
    i, j = np.array([0, 0, 1]), np.array([1, 2, 2])
    gaps = PartPairGaps(_radius(ps), 0.05, _solids(ps))
    gaps.start(start, (i, j), part_pair_bounds(ps, ps.place(start), i, j))
    states = np.tile(start, (k, 1, 1, 1))
    for s in range(k):
        states[s, 1], states[s, 2] = drawn[2 * s], drawn[2 * s + 1]
    one_by_one = [gaps.clear_at(p) for p in states]
    assert gaps.clear(gaps.moves(states).T, states).tolist() == one_by_one


def _rigid(rng, amount: float) -> np.ndarray:
    out = np.eye(4)
    out[:3, :3] = _random_rotation(rng)
    out[:3, 3] = rng.uniform(-amount, amount, 3)
    return out


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_a_pair_its_groups_boxes_prove_apart_has_no_record(seed):
    """Brute force against the part-part check: three rigid groups of
    drawn parts (boxes, spheres, cylinders, capsules, coarse meshes; a
    floor plane beside the first), each carried by its own drawn rigid
    motion from a start far apart to states near each other. With the
    parts' own relative-move and box tests switched off, the groups' boxes
    alone prove many pairs clear that the world moves do not, and no pair
    proven has a record at its state; with everything on, the groups never
    prove fewer than the parts' tests alone, and the states at once answer
    as each alone."""
    rng = np.random.default_rng(seed)
    kinds = [ShapeType.BOX, ShapeType.SPHERE, ShapeType.CYLINDER, ShapeType.CAPSULE, "mesh"]
    clearance = 0.05
    shapes, group, local = [Shape(ShapeType.PLANE, [])], [0], [np.eye(4)]
    local[0][2, 3] = -2.0                                    # a floor under the first group
    for g in range(3):
        for _ in range(rng.integers(2, 6)):
            shapes.append(_shape(kinds[rng.integers(5)], rng.uniform(0.03, 0.15, 3)))
            group.append(g)
            local.append(_rigid(rng, 0.3))
    group, local = np.array(group), np.array(local)
    n = len(shapes)
    ps = PartSet.build([f"p{k}" for k in range(n)], shapes, tolerance=1e-2)
    i, j = np.triu_indices(n, 1)
    keep = group[i] != group[j]
    i, j = i[keep], j[keep]

    def placed(carry: list[np.ndarray]) -> np.ndarray:    # one rigid motion per group
        return np.stack(carry)[group] @ local

    apart = [np.eye(4), np.eye(4), np.eye(4)]
    apart[1][0, 3], apart[2][0, 3] = 30.0, -30.0
    start = placed(apart)
    states = np.stack([placed([_rigid(rng, 0.1), _rigid(rng, rng.uniform(0.3, 2.0)), _rigid(rng, rng.uniform(0.3, 2.0))])
                       for _ in range(40)])

    def gaps(groups: bool, alone: bool) -> PartPairGaps:
        g = PartPairGaps(_radius(ps), clearance, PartSolids(ps.lo, ps.hi, ps.axial, ps.error, group if groups else None))
        g.start(start, (i, j), part_pair_bounds(ps, ps.place(start), i, j))
        if alone:               # the parts' own tests proving nothing: what is proven, the groups proved
            g._relative_moves = lambda poses, rows: np.full((len(rows), len(poses)), np.inf)
            g._separated = lambda poses, rows: np.zeros((len(rows), len(poses)), bool)
        return g

    by_groups, by_moves = gaps(True, True).clear_pairs(states), gaps(False, True).clear_pairs(states)
    assert by_groups.sum() > by_moves.sum() + 20
    for s, pose in enumerate(states):
        found = {frozenset((r.a, r.b)) for r in check_parts(ps, ps.place(pose), clearance)}
        assert not found & {frozenset((f"p{i[k]}", f"p{j[k]}")) for k in np.flatnonzero(by_groups[:, s])}
    full = gaps(True, False)
    ok = full.clear_pairs(states)
    assert not (gaps(False, False).clear_pairs(states) & ~ok).any()
    assert np.array_equal(ok, np.stack([full.clear_pairs(p[None])[:, 0] for p in states], axis=1))


# ---- whole runs with moving meshes: the skip rule against checking every step in full ----

_MESH_FILES = {"torus.stl": lambda: trimesh.creation.torus(30.0, 6.0, major_sections=32, minor_sections=12),
               "plate.stl": lambda: trimesh.creation.box((60, 40, 4)),
               "foot.stl": lambda: trimesh.creation.box((50, 30, 5)),
               "rod.stl": lambda: trimesh.creation.cylinder(3.0, 80.0, sections=16),
               "ring.stl": lambda: trimesh.creation.annulus(10.0, 20.0, 8.0, sections=24),
               "bar.stl": lambda: trimesh.creation.box((30, 6, 6))}


def _moving_mesh_scene(v: dict, unit: float, far: float) -> str:
    """A scene of moving meshes near the clearance (lengths in mm times ``unit``,
    everything ``far`` mm from the origin): a plate sliding past a torus (a
    keep-out zone or not), a rod through a bracket's foot, a bar spinning
    over an annulus with a pin (cylinder) riding on it, and a cable
    elsewhere; contact off, so parts pass through each other."""
    def p(*xyz):
        return "[" + ", ".join(f"{(x + far) * unit:.9g}" for x in xyz) + "]"

    def m(*xyz):                    # a body's move (no offset)
        return "[" + ", ".join(f"{x * unit:.9g}" for x in xyz) + "]"

    parts = [("fixture/torus", "world", "torus.stl", p(0, 0, 0), v["torus_keepout"]),
             ("slider/plate", "slide", "plate.stl", m(0, 0, 0), False),
             ("bracket/foot", "world", "foot.stl", p(0, -150, 0), False),
             ("rodpart", "rod", "rod.stl", m(0, 0, 0), False),
             ("ring", "world", "ring.stl", p(0, 150, v["ring_z"]), False),
             ("spinner/bar", "spin", "bar.stl", m(v["bar_x"], 0, 7 + v["dz"]), False)]
    text = f'''[scene]
name = "moving-meshes"
units = "{'mm' if unit == 1.0 else 'm'}"
duration = 0.3
settle = 0.05

[effects]
contact = []

[check]
clearance = {v["clearance"] * unit:.9g}

[[bodies]]
name = "slide"
pos = {p(-120, 0, 8 + v["gap"])}
[[bodies]]
name = "rod"
pos = {p(v["rod_x"], -150, 0)}
[[bodies]]
name = "spin"
pos = {p(0, 150, 0)}

[[motion]]
body = "slide"
keys = [ {{ t = 0.0, pos = {p(-120, 0, 8 + v["gap"])} }}, {{ t = 0.3, pos = {p(120, v["slide_y"], 8 + v["gap"])} }} ]

[[motion]]
body = "rod"
keys = [ {{ t = 0.0, pos = {p(v["rod_x"], -150, 0)} }}, {{ t = 0.3, pos = {p(v["rod_x"], -150, v["rod_z"])}, euler = [{v["rod_tilt"]:.6g}, 0, 0] }} ]

[[motion]]
body = "spin"
keys = [ {{ t = 0.0, pos = {p(0, 150, 0)}, euler = [0, 0, 0] }}, {{ t = 0.3, pos = {p(0, 150, 0)}, euler = [0, 0, {v["spin"]:.6g}] }} ]

[[parts]]
name = "spinner/pin"
body = "spin"
shape = "cylinder"
size = {m(2.0, 10.0)}
pos = {m(v["bar_x"] + 12, 0, 14 + v["dz"])}
keepout = true

[[cables]]
name = "c"
radius = {2.0 * unit:.9g}
start = {{ pos = {p(0, 300, 100)} }}
end = {{ pos = {p(100, 300, 100)} }}
length = {110 * unit:.9g}
segments = 10
'''
    for name, body, file, pos, keepout in parts:
        text += (f'\n[[parts]]\nname = "{name}"\nbody = "{body}"\nshape = "mesh"\nfile = "{file}"\n'
                 f'scale = {unit:.9g}\npos = {pos}\nkeepout = {"true" if keepout else "false"}\n')
    return text


@settings(max_examples=examples(2), deadline=None)
@given(st.fixed_dictionaries({
    "gap": st.floats(-1.0, 3.0), "clearance": st.sampled_from([0.5, 2.0]), "torus_keepout": st.booleans(),
    "slide_y": st.floats(-20, 20), "rod_x": st.floats(-10, 10), "rod_z": st.floats(-30, 30),
    "rod_tilt": st.floats(-20, 20), "spin": st.floats(90, 720), "ring_z": st.floats(-1, 3),
    "bar_x": st.floats(5, 15), "dz": st.floats(-0.5, 2.5)}),
    st.sampled_from([1.0, 1e-3]), st.sampled_from([0.0, 5000.0]))
def test_moving_meshes_skip_without_changing_records(v, unit, far):
    """Randomly drawn runs with moving meshes near the clearance (a plate
    sliding past a torus, a rod through a bracket's foot, a bar spinning over
    an annulus, in mm or m, near or far from the origin): the run with the
    skip rule finishes and its report equals the one checking every step in
    full, apart from timing and the skip rule's own counts; records to the
    bit."""
    import json
    import tempfile
    from pathlib import Path

    from cablecheck.run.runner import RunOptions, run_scene
    from cablecheck.scene.load import load_scene

    with tempfile.TemporaryDirectory() as tmp:
        d = Path(tmp)
        for name, make in _MESH_FILES.items():
            make().export(d / name)
        (d / "s.toml").write_text(_moving_mesh_scene(v, unit, far))
        scene = load_scene(d / "s.toml")
        run_scene(scene, RunOptions(report=d / "a.json", record=None))
        run_scene(scene, RunOptions(report=d / "b.json", record=None, advance=False))
        fast, full = (json.loads((d / f).read_text()) for f in ("a.json", "b.json"))
    assert full["complete"] and fast["complete"]
    assert fast.keys() == full.keys()
    for key in fast:
        if key not in ("timing", "settings"):
            assert fast[key] == full[key], key
    assert {k: x for k, x in fast["settings"].items() if k != "advance"} == \
        {k: x for k, x in full["settings"].items() if k != "advance"}
    assert fast["settings"]["advance"]["proven_clear_steps"] > 0
