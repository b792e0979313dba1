"""Masks over a study's runs that take memory only where they are mixed.

A bool per run is 100 MB at 10⁸ runs, and the masks an analysis needs are nearly always
uniform: every run ran, every value is finite, almost no grid row is in first place. So a
mask is built a block of runs at a time (:data:`studies.common.blocks.BLOCK`) and only its
mixed blocks are held: :func:`run_mask` gives a read-only all-True view (no memory) when no
block is mixed, and :class:`BlockMask` keeps a block that is all True or all False as a flag.
"""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np

from studies.common.blocks import run_slices


def all_runs(runs: int) -> np.ndarray:
    """A read-only mask of ``runs`` values, all True, that holds no memory (a broadcast)."""
    return np.broadcast_to(np.True_, (runs,))


def run_mask(runs: int, parts: Iterable[tuple[slice, np.ndarray]]) -> np.ndarray:
    """The mask over ``runs`` runs whose blocks ``parts`` gives as (slice, mask) pairs covering
    every run: :func:`all_runs` when every block is all True, else one array. While it is
    built only the blocks that are not all True are held."""
    mixed = [(part, mask) for part, mask in parts if not mask.all()]
    if not mixed:
        return all_runs(runs)
    out = np.ones(runs, dtype=bool)
    for part, mask in mixed:
        out[part] = mask
    return out


def false_count(mask: np.ndarray) -> int:
    """How many values of a bool mask are False (no temporary of the mask's size)."""
    return int(mask.size - np.count_nonzero(mask))


class BlockMask:
    """A bool mask over ``size`` rows held block by block (``parts``): a block all True or all
    False is a flag, only a mixed block an array."""

    def __init__(self, size: int) -> None:
        self.size = size
        self.parts = list(run_slices(size))
        self._blocks: list[bool | np.ndarray] = [False] * len(self.parts)

    def __getitem__(self, i: int) -> np.ndarray:
        """Block ``i`` as an array."""
        block = self._blocks[i]
        if isinstance(block, np.ndarray):
            return block
        part = self.parts[i]
        return np.full(part.stop - part.start, block)

    def __setitem__(self, i: int, mask: np.ndarray) -> None:
        everywhere = bool(mask.all())
        self._blocks[i] = everywhere if everywhere or not mask.any() else mask

    def any(self, i: int) -> bool:
        """Whether block ``i`` has a True row."""
        block = self._blocks[i]
        return bool(block) if not isinstance(block, np.ndarray) else True

    def count(self) -> int:
        """The number of True rows."""
        return sum(
            int(np.count_nonzero(block))
            if isinstance(block, np.ndarray)
            else (part.stop - part.start) * bool(block)
            for part, block in zip(self.parts, self._blocks, strict=True)
        )

    def first(self) -> int:
        """The first True row (0 if none, as ``np.argmax``)."""
        for i, part in enumerate(self.parts):
            if self.any(i):
                return part.start + int(np.argmax(self[i]))
        return 0

    def whole(self) -> np.ndarray:
        """The mask as one array (for tests and small grids)."""
        out = np.empty(self.size, dtype=bool)
        for i, part in enumerate(self.parts):
            out[part] = self[i]
        return out
