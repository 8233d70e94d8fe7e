"""The growing per-point columns behind a branch's arrays, against the stacking of the
same rows with ``np.array`` (the oracle): equal values and dtypes through growth,
a type that widens and rows of another shape; a view handed out never changes when a
row it covers is written again, and is read-only; and the cost of a partial branch
does not grow with the branch (one view per column, no copy)."""

from __future__ import annotations

import numpy as np
import pytest

from supercoil.continuation.columns import Columns


def test_views_equal_the_stacked_rows_through_growth():
    rng = np.random.default_rng(1)
    cols, rows = Columns(), []
    for i in range(100):
        row = rng.standard_normal(7)
        rows.append(row)
        cols.put("q", i, row)
        view = cols.view("q", i + 1)
        assert view.dtype == np.float64 and np.array_equal(view, np.array(rows))


def test_a_type_that_widens_and_rows_of_another_shape_stack_as_numpy_would():
    cols = Columns()
    values = [1, 2, 2.5, 4]
    for i, v in enumerate(values):
        cols.put("count", i, v)
    expected = np.array(values)
    assert cols.view("count", 4).dtype == expected.dtype
    assert np.array_equal(cols.view("count", 4), expected)
    words = ["a", "bcd", "ef"]
    for i, w in enumerate(words):
        cols.put("word", i, w)
    assert np.array_equal(cols.view("word", 3), np.array(words))
    cols.put("end", 0, np.zeros(3))
    cols.put("end", 1, np.ones(3))
    cols.put("end", 2, np.ones(2))  # another shape: kept as rows
    assert "end" in cols and np.array_equal(cols.get("end", 2), np.ones(2))
    assert np.array_equal(cols.get("end", 1), np.ones(3))


def test_a_view_handed_out_keeps_its_rows_when_one_is_written_again():
    cols = Columns()
    for i in range(5):
        cols.put("x", i, float(i))
    before = cols.view("x", 5)
    cols.put("x", 4, 40.0)  # the last row replaced (a regauged point)
    cols.put("x", 5, 50.0)
    assert np.array_equal(before, [0.0, 1.0, 2.0, 3.0, 4.0])
    assert np.array_equal(cols.view("x", 6), [0.0, 1.0, 2.0, 3.0, 40.0, 50.0])
    with pytest.raises(ValueError):
        before[0] = 1.0
    # a row beyond every view handed out is written in place: the view shares it
    again = cols.view("x", 6)
    cols.put("x", 6, 60.0)
    assert np.shares_memory(again, cols.view("x", 7))


def test_a_view_is_not_a_copy():
    cols = Columns()
    for i in range(2000):
        cols.put("q", i, np.full(50, float(i)))
    first, second = cols.view("q", 1999), cols.view("q", 2000)
    assert np.shares_memory(first, second)


def test_a_row_past_the_capacity_grows_the_column_and_keeps_the_rows_before():
    cols = Columns()
    for i in range(3):
        cols.put("x", i, float(i))
    cols.put("x", 40, 40.0)  # beyond the first capacity (16)
    assert cols.get("x", 40) == 40.0
    assert np.array_equal(cols.view("x", 3), [0.0, 1.0, 2.0])
