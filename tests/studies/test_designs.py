"""Full factorial, one-factor sweep and orthogonal-array assignment."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from studies import designs


def test_full_factorial_is_every_combination() -> None:
    d = designs.full_factorial({"a": 2, "b": 3, "c": 4})
    rows = set(zip(d.levels["a"], d.levels["b"], d.levels["c"], strict=True))
    assert rows == set(itertools.product(range(2), range(3), range(4)))
    assert d.runs == 24


def test_sweep_moves_one_factor_at_a_time() -> None:
    d = designs.sweep({"a": 3, "b": 5}, base={"a": 1, "b": 2})
    assert d.runs == 1 + 2 + 4
    moved = (np.c_[d.levels["a"] != 1, d.levels["b"] != 2]).sum(axis=1)
    assert moved[0] == 0
    assert np.all(moved[1:] == 1)
    assert list(d.labels["swept_factor"]) == ["base", "a", "a", "b", "b", "b", "b"]


def test_l9_assignment_keeps_empty_column_as_error() -> None:
    d = designs.orthogonal("L9", {"A": 3, "B": 3, "C": 3}, {"A": 1, "B": 2, "C": 3}, ("D",))
    assert d.error_columns == ("D",)
    table = designs.orthogonal_array("L9")
    for i, name in enumerate(["A", "B", "C", "D"]):
        np.testing.assert_array_equal(d.levels[name], table[:, i])


def test_columns_are_taken_in_order_when_not_given() -> None:
    d = designs.orthogonal("L9", {"A": 3, "B": 3}, {"A": None, "B": 3}, ())
    table = designs.orthogonal_array("L9")
    np.testing.assert_array_equal(d.levels["A"], table[:, 0])
    np.testing.assert_array_equal(d.levels["B"], table[:, 2])
    assert d.error_columns == ("e2", "e4")


def test_auto_picks_l9_for_four_three_level_factors() -> None:
    d = designs.orthogonal("auto", dict.fromkeys("ABCD", 3), dict.fromkeys("ABCD"), ())
    assert d.name.startswith("L9")


@pytest.mark.parametrize(
    ("counts", "columns", "words"),
    [
        ({"A": 4}, {"A": 1}, "has 4 levels but column 1"),
        ({"A": 3, "B": 3}, {"A": 2, "B": 2}, "both assigned to column 2"),
        ({"A": 3}, {"A": 7}, "column 7 does not exist"),
        (dict.fromkeys("ABCDE", 3), dict.fromkeys("ABCDE"), "no free column"),
    ],
)
def test_misfits_are_reported(counts, columns, words) -> None:
    with pytest.raises(designs.DesignError, match=words):
        designs.orthogonal("L9", counts, columns, ())
