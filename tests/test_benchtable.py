"""The bench's table pieces (cablecheck.bench.table): rows must fit the columns, the
printed block and the CSV show each value as the bench reports it, and
`median_time` warms up once then times `repeat` calls."""

from __future__ import annotations

import csv

import pytest

from cablecheck.bench.table import Table, median_time, text_table


def test_rows_fit_the_columns_and_print_and_write_as_reported(tmp_path):
    t = Table("demo", "A demo table", ["name", "ms", "big", "ok", "none", "zero"], notes=["a note"])
    t.add("drawer", 1.23456, 123456.7, True, None, 0.0)
    t.add("arm", float("inf"), 12.0, False, None, -0.0)
    with pytest.raises(ValueError, match="demo: row of 2 values for 6 columns"):
        t.add("x", 1.0)
    assert t.column("ms") == [1.23456, float("inf")]
    lines = t.text().splitlines()
    assert lines[1] == "A demo table"
    assert lines[3].split() == ["drawer", "1.23", "123457", "yes", "-", "0"]
    assert lines[4].split() == ["arm", "inf", "12", "no", "-", "-0"]
    assert lines[5] == "  - a note"
    assert len({len(line) for line in lines[2:5]}) == 1          # right-aligned columns
    with open(t.write_csv(tmp_path)) as f:
        rows = list(csv.reader(f))
    assert (tmp_path / "demo.csv").exists()
    assert rows == [t.columns, ["drawer", "1.23456", "123457", "True", "", "0"],
                    ["arm", "inf", "12", "False", "", "-0"]]


def test_median_time_warms_up_once_then_times_repeat_calls():
    calls = []
    assert median_time(lambda: calls.append(1), 5) >= 0.0
    assert len(calls) == 6
    calls.clear()
    median_time(lambda: calls.append(1), 0)                       # at least one timed call
    assert len(calls) == 2


def test_text_table_right_aligns_each_column_to_its_widest_cell():
    text = text_table(["scene", "ms"], [["drawer", 0.5], ["a", None], ["bracket_static", 12]])
    lines = text.splitlines()
    assert lines == ["         scene     ms",
                     "        drawer  0.500",
                     "             a      -",
                     "bracket_static     12"]
