"""Masks over runs held only where they are mixed (studies.common.run_masks): the same
answers as a plain bool array (brute force), with nothing held when they are uniform."""

from __future__ import annotations

import numpy as np
import pytest

from studies.common import blocks
from studies.common.run_masks import BlockMask, all_runs, false_count, run_mask


def test_a_mask_that_is_all_true_holds_no_memory() -> None:
    mask = run_mask(10**8, ((p, np.ones(p.stop - p.start, bool)) for p in blocks.run_slices(10**8)))
    assert mask.shape == (10**8,)
    assert mask.strides == (0,)  # one value seen through a broadcast, not 100 MB
    assert not mask.flags.writeable
    assert false_count(mask) == 0
    assert bool(mask[123_456_789 % 10**8])


@pytest.mark.parametrize("seed", range(12))
def test_masks_built_by_blocks_are_the_plain_mask(seed: int, monkeypatch) -> None:
    # Brute force: the mask computed whole; blocks of 1-5 runs, with uniform and mixed blocks.
    monkeypatch.setattr(blocks, "BLOCK", int(1 + seed % 5))
    rng = np.random.default_rng(seed)
    size = int(rng.integers(1, 40))
    plain = rng.random(size) < rng.choice([0.0, 0.3, 0.97, 1.0])
    built = run_mask(size, ((p, plain[p]) for p in blocks.run_slices(size)))
    np.testing.assert_array_equal(built, plain)
    assert false_count(built) == int((~plain).sum())
    held = BlockMask(size)
    for i, part in enumerate(held.parts):
        held[i] = plain[part]
    np.testing.assert_array_equal(held.whole(), plain)
    assert held.count() == int(plain.sum())
    assert held.first() == int(np.argmax(plain))
    for i, part in enumerate(held.parts):
        np.testing.assert_array_equal(held[i], plain[part])
        assert held.any(i) == bool(plain[part].any())


def test_all_runs_is_true_everywhere() -> None:
    assert all_runs(5).tolist() == [True] * 5
