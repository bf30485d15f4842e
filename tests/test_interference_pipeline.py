"""The check pipeline (cablecheck.checker.interference.pipeline): a reused Checker, and the gaps it returns."""

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st
from strategies import cable_sets, part_sets

from cablecheck.checker.interference import Checker, check_state
from cablecheck.checker.interference.discrete import points_error
from cablecheck.checker.records import PairType
from cablecheck.checker.scene_state import CableState, CheckConfig, Exclusion, PartState
from cablecheck.checker.shapes import Shape, ShapeType

pytestmark = pytest.mark.filterwarnings("error")


@pytest.mark.parametrize("method", ["points", "exact"])
def test_checker_reused_across_poses_matches_check_state(method):
    """A Checker built once gives check_state's records for every set of poses."""
    rng = np.random.default_rng(11)
    r = 0.004
    t = np.linspace(0, 1, 60)
    cables = [CableState(f"c{k}", np.c_[t * 0.3, 0.02 * k + 0.01 * np.sin(9 * t + k), 0.05 + 0.0 * t], r)
              for k in range(4)]
    shapes = [Shape(ShapeType.BOX, [0.02, 0.01, 0.03]), Shape(ShapeType.ELLIPSOID, [0.02, 0.015, 0.01]),
              Shape(ShapeType.CYLINDER, [0.01, 0.03]), Shape(ShapeType.PLANE, [0.0])]
    cfg = CheckConfig(method=method)
    parts0 = [PartState(f"p{k}", sh, np.eye(4), keepout=k == 1) for k, sh in enumerate(shapes)]
    checker = Checker(parts0, cfg)
    ex = [Exclusion("c0", "p0", 0.0, 0.05)]
    for _ in range(5):
        poses = []
        for k in range(len(shapes)):
            q, rr = np.linalg.qr(rng.normal(size=(3, 3)))
            q = q * np.sign(np.diag(rr))
            if np.linalg.det(q) < 0:
                q[:, 0] *= -1
            pose = np.eye(4)
            pose[:3, :3] = q
            pose[:3, 3] = rng.uniform([0, -0.02, 0.0], [0.3, 0.08, 0.08])
            poses.append(pose)
        parts = [PartState(p.name, p.shape, pose, p.keepout) for p, pose in zip(parts0, poses)]
        want = check_state(cables, parts, cfg, ex)
        got = checker.check(cables, np.array(poses), ex)
        assert [(x.type, x.a, x.b, x.min_distance, x.s) for x in got] == \
            [(x.type, x.a, x.b, x.min_distance, x.s) for x in want]
    assert [(x.type, x.min_distance, x.s) for x in checker.check(cables, None, ex)] == \
        [(x.type, x.min_distance, x.s) for x in check_state(cables, parts0, cfg, ex)]
    with pytest.raises(ValueError):
        checker.check(cables, np.zeros((len(shapes), 4, 4)), ex)


@settings(max_examples=25, deadline=None)
@given(cable_sets(max_cables=3, max_points=10), part_sets(max_parts=4), st.floats(0.001, 0.03))
def test_gaps_are_the_least_values_up_to_the_horizon(cables, parts, horizon):
    """With a horizon the records do not change, and each part's gap is the
    least value of any cable against it minus the clearance and minus the
    cable's points' error (a pair kept past that is past the clearance by
    method exact too), capped at the horizon: what a check with the
    clearance raised by the horizon and the errors finds."""
    clearance = 0.005
    checked = Checker(parts, CheckConfig(clearance=clearance), horizon=horizon).check_with_gaps(cables)
    plain = Checker(parts, CheckConfig(clearance=clearance)).check(cables)
    assert [(r.type, r.a, r.b, r.min_distance, r.s, r.s_b) for r in checked.records] == \
        [(r.type, r.a, r.b, r.min_distance, r.s, r.s_b) for r in plain]
    gaps = checked.gaps
    assert gaps.horizon == horizon and gaps.cable <= horizon and len(gaps.part) == len(parts)
    err = {c.name: points_error(c.radius, 2.0) for c in cables}
    wide = check_state(cables, parts, CheckConfig(clearance=clearance + horizon + max(err.values())))
    for k, part in enumerate(parts):
        least = min((r.min_distance - clearance - err[r.a] for r in wide if r.b == part.name
                     and r.type in (PairType.CABLE_STRUCTURE, PairType.KEEPOUT)), default=np.inf)
        assert gaps.part[k] == min(horizon, least)
    pc = gaps.part_candidates
    assert np.all(pc.value < horizon) and np.all((pc.part >= 0) & (pc.part < len(parts)))


def test_no_gaps_without_a_horizon_or_with_method_exact():
    cables = [CableState("c", np.array([[0.0, 0, 0], [0.1, 0, 0], [0.2, 0, 0]]), 0.005)]
    assert Checker([], CheckConfig()).check_with_gaps(cables).gaps is None
    assert Checker([], CheckConfig(method="exact"), horizon=0.01).check_with_gaps(cables).gaps is None
    assert Checker([], CheckConfig(), horizon=0.01).check_with_gaps(cables, horizon=0.0).gaps is None
    assert Checker([], CheckConfig(), horizon=0.01).check_with_gaps(cables).gaps.cable == pytest.approx(0.01)
