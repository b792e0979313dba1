"""The pieces of the valve error bar: halving differences and derived-output differences."""

from __future__ import annotations

import numpy as np
from hypothesis import given
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from studies.scenes.valve.error_bar import halving_difference, output_difference

FINITE = st.floats(-1.0, 1.0, allow_nan=False)


@given(arrays(np.float64, (3, 5), elements=FINITE), arrays(np.float64, (3, 9), elements=FINITE))
def test_halving_difference_compares_on_the_shared_nodes(
    coarse: np.ndarray, fine: np.ndarray
) -> None:
    # Brute force: node j of the coarse grid is node 2j of the fine one.
    expected = [max(abs(coarse[r, j] - fine[r, 2 * j]) for j in range(5)) for r in range(3)]
    np.testing.assert_array_equal(halving_difference(coarse, fine), expected)


def test_output_difference_says_when_the_runs_disagree_on_an_event() -> None:
    nan = np.nan
    coarse = np.array([1.0, nan, nan, 2.0])
    fine = np.array([1.5, nan, 3.0, nan])
    np.testing.assert_array_equal(output_difference(coarse, fine), [0.5, 0.0, np.inf, np.inf])
