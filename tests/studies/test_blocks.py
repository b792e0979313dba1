"""Passes over runs in blocks (studies.common.blocks) against the whole-array NumPy answer
(brute force), with blocks of a few runs so that every pass crosses block boundaries."""

from __future__ import annotations

import numpy as np
import pytest

from studies.common import blocks


@pytest.fixture(params=[None, 3], ids=["one block", "blocks of 3"])
def block(request, monkeypatch) -> None:
    if request.param:
        monkeypatch.setattr(blocks, "BLOCK", request.param)


@pytest.mark.parametrize("seed", range(5))
def test_finite_summary_is_numpys_over_the_finite_values(seed: int, block: None) -> None:
    rng = np.random.default_rng(seed)
    y = rng.normal(3.0, 2.0, size=int(rng.integers(1, 40)))
    y[rng.random(y.size) < 0.3] = rng.choice([np.nan, np.inf, -np.inf])
    finite = y[np.isfinite(y)]
    seen = blocks.finite_summary(y)
    assert seen.count == finite.size
    if finite.size:
        assert (seen.low, seen.high, seen.largest) == (
            finite.min(),
            finite.max(),
            np.abs(finite).max(),
        )
        assert seen.mean == pytest.approx(finite.mean(), rel=1e-14)
    else:
        assert np.isnan(seen.mean)


@pytest.mark.parametrize("seed", range(5))
def test_codes_are_kept_exactly_in_the_smallest_type(seed: int, block: None) -> None:
    rng = np.random.default_rng(seed)
    high = [5, 126, 127, 40_000, 2**31][seed]
    codes = rng.integers(-1, high + 1, size=25).astype(np.int64)
    codes[0] = high
    compact = blocks.compact_codes(codes)
    np.testing.assert_array_equal(compact, codes)
    expected = [np.int8, np.int8, np.int8, np.int32, np.int64][seed]
    assert compact.dtype == expected
    assert blocks.code_range(codes) == (int(codes.min()), high)
    assert blocks.level_count(codes) == high + 1


@pytest.mark.parametrize("seed", range(5))
def test_first_runs_are_the_first_occurrences(seed: int, block: None) -> None:
    rng = np.random.default_rng(seed)
    codes = rng.integers(0, 6, size=int(rng.integers(1, 30)))
    expected = [
        int(np.flatnonzero(codes == level)[0]) if (codes == level).any() else -1
        for level in range(8)
    ]
    assert blocks.first_runs(codes, 8).tolist() == expected


@pytest.mark.parametrize("seed", range(5))
def test_runs_matching_are_the_runs_at_every_level(seed: int, block: None) -> None:
    rng = np.random.default_rng(seed)
    runs = int(rng.integers(1, 40))
    a, b = rng.integers(0, 3, size=runs), rng.integers(0, 2, size=runs)
    expected = np.flatnonzero((a == 1) & (b == 0))  # the whole arrays at once
    assert blocks.runs_matching([(a, 1), (b, 0)], runs).tolist() == expected.tolist()
