"""Tests of cablecheck.checker.refine: method points' records near touching measured again exactly,
against an independent `Checker` with method exact on the same drawn cable and part (primitives and
meshes, turned, far from the origin), and the points' error bound that decides which records are."""

import numpy as np
import trimesh
from hypothesis import event, given, settings
from hypothesis import strategies as st

from cablecheck.checker.interference import Checker
from cablecheck.checker.interference.discrete import points_error
from cablecheck.checker.recheck import Recheck
from cablecheck.checker.records import PairType, Severity
from cablecheck.checker.refine import refined_records
from cablecheck.checker.scene_state import CableState, CheckConfig, PartState
from cablecheck.checker.shapes import Shape, ShapeType, mesh_shape
from helpers import examples
from strategies import coords, rotations

_BOX = trimesh.creation.box((0.06, 0.04, 0.05))
_SHAPES = {
    "box": Shape(ShapeType.BOX, [0.03, 0.02, 0.025]),
    "capsule": Shape(ShapeType.CAPSULE, [0.015, 0.03]),
    "mesh box": mesh_shape(_BOX.vertices, _BOX.faces),
    "mesh sphere": mesh_shape(trimesh.creation.icosphere(1, 0.03).vertices, trimesh.creation.icosphere(1, 0.03).faces),
}


def _record(recs, kind, name):
    found = [r for r in recs if PairType(r.type) is kind and r.b == name]
    return found[0] if found else None


def _top(kind: str, rot: np.ndarray) -> np.ndarray:
    """The part's highest point (turned by rot, about its origin)."""
    sh = _SHAPES[kind]
    if sh.type is ShapeType.BOX:
        pts = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]) * sh.size
    elif sh.type is ShapeType.CAPSULE:
        pts = np.array([[0, 0, -sh.size[1]], [0, 0, sh.size[1]]])
        pts = pts @ rot.T
        return pts[np.argmax(pts[:, 2])] + [0.0, 0.0, sh.size[0]]
    else:
        pts = np.asarray(sh.vertices, float)
    pts = pts @ rot.T
    return pts[np.argmax(pts[:, 2])]


@settings(max_examples=examples(60), deadline=None)
@given(st.sampled_from(sorted(_SHAPES)), rotations(), st.floats(0.0, np.pi), coords((5,), -0.004, 0.004),
       st.floats(-0.4, 1.5), coords(2, -0.01, 0.01), st.floats(0.002, 0.01), st.sampled_from([0.0, 500.0]),
       st.booleans())
def test_records_near_touching_are_the_exact_methods(kind, rot, heading, jitter, lift, off, radius, far, keepout):
    """A cable laid level across a drawn part's highest point at a drawn height (-0.4 to 1.5 radii
    off its surface there), its points jittered along it: a soft points record within the points'
    error of touching becomes method exact's record of the pair (the same value, severity and
    place, to rounding); a record farther out keeps the points' value; and the points never over-state
    exact's distance by more than that error where exact finds no overlap (so no exact-hard pair
    is left soft)."""
    top = _top(kind, rot)
    along = np.array([np.cos(heading), np.sin(heading), 0.0])
    steps = np.linspace(-0.05, 0.05, 5) + jitter
    line = top + np.array([off[0], off[1], radius * (1.0 + lift)]) + steps[:, None] * along
    pose = np.eye(4)
    pose[:3, :3], pose[:3, 3] = rot, far
    part = PartState("p", _SHAPES[kind], pose, keepout=keepout)
    cable = CableState("c", line + far, radius)
    clearance = 0.004
    points = Checker([part], CheckConfig(method="points", clearance=clearance)).check([cable])
    exact = Checker([part], CheckConfig(method="exact", clearance=clearance)).check([cable])
    ptype = PairType.KEEPOUT if keepout else PairType.CABLE_STRUCTURE
    p_rec, e_rec = _record(points, ptype, "p"), _record(exact, ptype, "p")
    err = points_error(radius, 2.0)
    rounding = 1e-12 * (1.0 + far)
    if e_rec is not None and e_rec.severity is Severity.HARD:
        assert p_rec is not None and p_rec.min_distance < err          # the refinement asks for it
    if p_rec is not None:
        assert e_rec is not None and e_rec.min_distance <= p_rec.min_distance + rounding
        if e_rec.min_distance >= 0.0:                 # the bound holds where exact finds no overlap
            assert p_rec.min_distance - e_rec.min_distance <= err + rounding
    recheck = Recheck([PartState("p", _SHAPES[kind], np.eye(4), keepout)], CheckConfig(clearance=clearance), [])
    swap = refined_records([points], lambda i: {"c": cable}, pose[None, None], recheck, {"c": err})[0]
    if p_rec is None:
        assert not swap
        return
    got = swap.get(id(p_rec), p_rec)
    event(f"points {p_rec.severity.value}{' near touching' if p_rec.min_distance < err else ''}, exact {e_rec.severity.value}")
    if p_rec.severity is Severity.SOFT and p_rec.min_distance < err:
        assert abs(got.min_distance - e_rec.min_distance) <= rounding   # two elements meeting at a point tie
        assert got.severity is e_rec.severity or abs(e_rec.min_distance) <= rounding
        assert np.allclose(got.where, e_rec.where, atol=rounding) and abs(got.s - e_rec.s) <= rounding
    else:
        assert got is p_rec


def test_a_corner_between_two_points_reads_as_touching():
    """A box's edge across a straight cable half way between two of its points (10 mm apart, r =
    5 mm), touching its surface: the points read the whole error bound, sqrt(r^2 + (h/2)^2) - r =
    2.07 mm; the refined record reads what exact does, 0 (soft, touching); the edge 0.1 mm further
    in, -0.1 mm (hard)."""
    r, half = 0.005, 0.01
    cable = CableState("c", np.array([[-0.03, 0.0, 0.0], [0.0, 0.0, 0.0], [0.01, 0.0, 0.0], [0.04, 0.0, 0.0]]), r)
    cfg = CheckConfig(clearance=0.003, spacing=2.0)
    err = points_error(r, 2.0)
    for depth, severity in ((0.0, Severity.SOFT), (1e-4, Severity.HARD)):
        pose = np.eye(4)                               # a box turned 45 degrees about y: an edge up, along y
        pose[:3, :3] = [[np.sqrt(0.5), 0.0, np.sqrt(0.5)], [0.0, 1.0, 0.0], [-np.sqrt(0.5), 0.0, np.sqrt(0.5)]]
        pose[:3, 3] = [0.005, 0.0, -(r - depth) - half * np.sqrt(2.0)]
        part = PartState("p", Shape(ShapeType.BOX, [half, 0.05, half]), pose)
        rec = _record(Checker([part], cfg).check([cable]), PairType.CABLE_STRUCTURE, "p")
        assert abs(rec.min_distance - (np.hypot(0.005, r - depth) - r)) < 1e-6     # to the edge or a face beside it
        recheck = Recheck([PartState("p", part.shape, np.eye(4))], cfg, [])
        got = refined_records([[rec]], lambda i: {"c": cable}, pose[None, None], recheck, {"c": err})[0][id(rec)]
        assert got.severity is severity
        assert abs(got.min_distance + depth) < 1e-12
        assert abs(got.where[0] - 0.005) < 1e-9
