"""cablecheck.study.goal: requirements and goals read from study tables, judged on reports with known answers."""

from __future__ import annotations

import math

import pytest

from cablecheck.checker.cable import TAUT_STRAIN
from cablecheck.study.goal import GoalError, Need, check_names, judge, parse_goal, parse_requirements

REPORT = {
    "complete": True,
    "cables": [{"name": "a", "length": 1.0, "max_strain": 0.004, "min_bend_radius": 0.05,
                "wear": {"most_worn": {"sliding": 0.2}}},
               {"name": "b", "length": 2.0, "max_strain": -0.002, "min_bend_radius": None,
                "wear": {"most_worn": None}}],
    "closest": {"reach": 0.015, "pairs": [
        {"type": "cable-structure", "a": "a", "b": "arm/link3/geom", "min_distance": 0.003},
        {"type": "cable-cable", "a": "a", "b": "b", "min_distance": 0.001},
        {"type": "self", "a": "b", "b": "b", "min_distance": -0.0005},
        {"type": "cable-structure", "a": "b", "b": "arm/link30", "min_distance": 0.0001}]},
}


def _one(table: dict):
    (r,) = parse_requirements([table])
    return judge(REPORT, (r,), None)


@pytest.mark.parametrize("table, margin, at_least", [
    ({"clearance": 0.005, "between": ["a", "arm/link3"]}, 0.003 - 0.005, False),
    ({"clearance": 0.005, "between": ["arm/link3", "a"]}, 0.003 - 0.005, False),   # either order
    ({"clearance": 0.005, "between": ["b", "arm/link3"]}, 0.015 - 0.005, True),     # link30 is not under link3
    ({"clearance": 0.0, "between": ["a", "b"]}, 0.001, False),
    ({"no_hard": True, "cables": ["a"]}, 0.001, False),
    ({"no_hard": True, "cables": ["b"]}, -0.0005, False),
    ({"no_hard": True}, -0.0005, False),
    ({"min_bend_radius": 0.04}, 0.05 - 0.04, False),                                # b is straight
    ({"max_strain": 0.01}, (0.01 - 0.004) * 1.0, False),
    ({"taut": False, "cables": ["b"]}, (TAUT_STRAIN + 0.002) * 2.0, False),
])
def test_each_requirement_has_its_margin_in_scene_units(table, margin, at_least):
    j = _one(table)
    assert j.margins[0] == pytest.approx(margin) and j.at_least == (at_least,)
    assert j.satisfied is (margin >= 0) and j.margin == pytest.approx(margin)


def test_the_least_margin_decides_and_a_goal_is_read_larger_is_better():
    reqs = parse_requirements([{"clearance": 0.002, "between": ["a", "arm"]}, {"min_bend_radius": 0.01}])
    j = judge(REPORT, reqs, parse_goal({"maximise": "clearance", "between": ["a", "arm/link3"]}))
    assert j.satisfied and j.margin == pytest.approx(0.001) and j.objective == pytest.approx(0.003)
    assert judge(REPORT, (), parse_goal({"minimise": "length"})).objective == pytest.approx(-3.0)
    assert judge(REPORT, (), parse_goal({"minimise": "length", "cables": ["b"]})).objective == pytest.approx(-2.0)
    assert judge(REPORT, (), parse_goal({"minimise": "wear"})).objective == pytest.approx(-0.2)
    assert judge(REPORT, (), None).margin == math.inf


@pytest.mark.parametrize("entries, where, words", [
    ([{"clearance": 0.005}], "require[0].between", "two names"),
    ([{"clearance": 0.005, "no_hard": True, "between": ["a", "b"]}], "require[0]", "exactly one"),
    ([{}], "require[0]", "exactly one"),
    ([{"clearance": -1, "between": ["a", "b"]}], "require[0].clearance", ">= 0"),
    ([{"no_hard": False}], "require[0].no_hard", "expected true"),
    ([{"taut": True}], "require[0].taut", "expected false"),
    ([{"max_strain": 0.01, "between": ["a", "b"]}], "require[0].between", "only a clearance"),
    ([{"min_bend_radius": 0.01, "colour": 1}], "require[0].colour", "unknown key"),
    ({"clearance": 1}, "require", "tables"),
])
def test_a_bad_requirement_names_its_key(entries, where, words):
    with pytest.raises(GoalError) as e:
        parse_requirements(entries)
    assert e.value.args[0] == where and words in e.value.args[1]


@pytest.mark.parametrize("table, where", [
    ({}, "goal"), ({"maximise": "clearance", "minimise": "length"}, "goal"),
    ({"maximise": "length"}, "goal.maximise"), ({"minimise": "clearance"}, "goal.minimise"),
    ({"maximise": "clearance"}, "goal.between"), ({"minimise": "wear", "between": ["a", "b"]}, "goal.between"),
])
def test_a_bad_goal_names_its_key(table, where):
    with pytest.raises(GoalError) as e:
        parse_goal(table)
    assert e.value.args[0] == where


def test_names_must_be_cables_parts_assembly_paths_or_under_a_model_body():
    reqs = parse_requirements([{"clearance": 0.01, "between": ["a", "cell/table"]},
                               {"no_hard": True, "cables": ["a"]}])
    assert check_names(reqs, None, {"a"}, {"cell/table/top"}) is None                      # an assembly path
    assert check_names(reqs, None, {"a"}, {"fence"}) == ("require[0].between",
                                                          "'cell/table' names no cable or part of the scene")
    assert check_names(reqs, None, {"a"}, set(), {"cell"}) is None                        # an mjcf body's geoms
    assert check_names(reqs, None, {"b"}, {"cell/table"})[0] == "require[0].between"
    (bad,) = parse_requirements([{"no_hard": True, "cables": ["c"]}])
    assert check_names((bad,), None, {"a"}, set()) == ("require[0].cables", "'c' is not a cable of the scene")
    assert bad.need is Need.NO_HARD
