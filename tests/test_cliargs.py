"""`cablecheck.cli.args`: the option types refuse what a run could not use, and the
parser gives every sub-command its options (no run is started here)."""

from __future__ import annotations

import argparse
from pathlib import Path

import pytest
from hypothesis import given, strategies as st

from cablecheck.cli.args import build_parser, nonnegative_float, positive_float, positive_int, xyz_direction


@given(st.floats(min_value=1e-300, max_value=1e300))
def test_positive_float_takes_every_finite_positive_number(x: float):
    assert positive_float(repr(x)) == x


@pytest.mark.parametrize("text", ["0", "-1", "inf", "nan", "-0.0", "two", ""])
def test_positive_float_refuses(text: str):
    with pytest.raises(argparse.ArgumentTypeError):
        positive_float(text)


def test_nonnegative_float_takes_zero_and_refuses_negative_and_infinite():
    assert nonnegative_float("0") == 0.0
    for text in ("-1e-9", "inf", "nan", "x"):
        with pytest.raises(argparse.ArgumentTypeError):
            nonnegative_float(text)


def test_positive_int():
    assert positive_int("3") == 3
    for text in ("0", "-2", "1.5", "x"):
        with pytest.raises(argparse.ArgumentTypeError):
            positive_int(text)


@given(st.tuples(*[st.floats(allow_nan=False, allow_infinity=False, width=64)] * 3)
       .filter(lambda v: any(v)))
def test_direction_reads_any_nonzero_finite_vector(v):
    assert xyz_direction(",".join(repr(x) for x in v)) == v


@pytest.mark.parametrize("text", ["0,0,0", "1,0", "1,0,0,0", "1,inf,0", "1,nan,0", "a,b,c", ""])
def test_direction_refuses(text: str):
    with pytest.raises(argparse.ArgumentTypeError):
        xyz_direction(text)


def test_the_parser_knows_every_sub_command_and_its_defaults():
    parser = build_parser("1.2.3")
    run = parser.parse_args(["run", "s.toml"])
    assert (run.command, run.scene, run.fail_on, run.report, run.record, run.no_record) == \
        ("run", Path("s.toml"), "hard", None, None, False)
    sweep = parser.parse_args(["sweep", "s.toml", "--part", "p", "--direction=-1,0,0", "--distance", "5"])
    assert sweep.direction == (-1.0, 0.0, 0.0) and sweep.distance == 5.0
    assert parser.parse_args(["bench"]).out == Path("recordings/bench")
    assert parser.parse_args(["study", "x.toml"]).out == Path("recordings/studies")
    assert parser.parse_args(["check", "s.toml", "--quiet"]).quiet


def test_version_and_exclusive_options(capsys):
    parser = build_parser("1.2.3")
    with pytest.raises(SystemExit) as e:
        parser.parse_args(["--version"])
    assert e.value.code == 0 and capsys.readouterr().out.strip() == "cablecheck 1.2.3"
    with pytest.raises(SystemExit) as e:
        parser.parse_args(["run", "s.toml", "--record", "r.rrd", "--no-record"])
    assert e.value.code == 2
    with pytest.raises(SystemExit):
        parser.parse_args(["run", "s.toml", "--spacing", "0"])
    assert parser.parse_args(["run", "s.toml", "--spacing", "0.5"]).spacing == 0.5
