"""Interference records, pair types and the one severity rule (cablecheck.checker.records)."""

from __future__ import annotations

import json

from hypothesis import given, strategies as st

from cablecheck.checker.records import PairType, Severity, severity_of


@given(st.floats(-1e3, 1e3, allow_nan=False), st.floats(0.0, 1e3, allow_nan=False))
def test_severity_against_the_clearance(distance, clearance):
    """Hard below 0, soft from 0 up to (not at) the clearance, else clear."""
    sev = severity_of(distance, clearance)
    if distance < 0.0:
        assert sev is Severity.HARD
    elif distance < clearance:
        assert sev is Severity.SOFT
    else:
        assert sev is None


def test_severity_edges():
    assert severity_of(0.0, 0.005) is Severity.SOFT           # touching: soft, not hard
    assert severity_of(0.005, 0.005) is None                  # exactly at the clearance: clear
    assert severity_of(-0.0, 0.0) is None and severity_of(-1e-300, 0.0) is Severity.HARD
    assert severity_of(None, 0.005) is None                   # a pair not seen at all


def test_enums_are_the_reports_strings():
    assert [t.value for t in PairType] == ["self", "cable-cable", "cable-structure", "keepout", "part-part",
                                           "bend", "taut"]
    assert f"{PairType.CABLE_CABLE}" == str(PairType.CABLE_CABLE) == "cable-cable"
    assert {Severity.HARD: 1}["hard"] == 1 and Severity("soft") is Severity.SOFT
    assert json.dumps({PairType.SELF: Severity.HARD}) == '{"self": "hard"}'
