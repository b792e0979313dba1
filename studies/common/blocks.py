"""Runs in blocks: a pass over a study's runs that holds one block at a time.

A response of 10⁸ runs is 800 MB in double precision; read :data:`BLOCK` runs at a time it is
8 MB. Summaries that do not depend on the order of the values (counts, minima, maxima, "any")
are exact over blocks; a sum over more than one block adds the blocks' sums (each NumPy's
pairwise sum), which differs from one pairwise sum of the whole in the last bits only, and a
study of at most :data:`BLOCK` runs gets the whole-array numbers bit for bit.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any

import numpy as np

BLOCK = 1 << 20
"""Runs per block (8 MB of doubles)."""


def run_slices(runs: int, block: int | None = None) -> Iterator[slice]:
    """Consecutive slices of at most ``block`` (default :data:`BLOCK`) runs covering
    ``0 … runs-1``."""
    block = block or BLOCK
    for start in range(0, runs, block):
        yield slice(start, min(start + block, runs))


def rows_per_block(width: int) -> int:
    """Rows of ``width`` values that make about one block (at least one row)."""
    return max(1, BLOCK // max(width, 1))


def blocks(values: Any, block: int | None = None) -> Iterator[np.ndarray]:
    """``values`` (an array, or a lazily read xarray variable with ``run`` first) one block of
    runs at a time, each block read on its own."""
    for part in run_slices(len(values), block):
        yield np.asarray(values[part])


@dataclass
class FiniteSummary:
    """Count, sum, minimum and maximum of the finite values seen; :meth:`add` a block at a time."""

    count: int = 0
    total: float = 0.0
    low: float = np.inf
    high: float = -np.inf
    largest: float = 0.0  # the largest magnitude

    def add(self, values: np.ndarray) -> None:
        finite = values[np.isfinite(values)]
        if finite.size:
            self.count += finite.size
            self.total += float(np.sum(finite))
            self.low = min(self.low, float(finite.min()))
            self.high = max(self.high, float(finite.max()))
            self.largest = max(self.largest, float(np.abs(finite).max()))

    @property
    def mean(self) -> float:
        return self.total / self.count if self.count else np.nan


def code_range(codes: Any) -> tuple[int, int]:
    """The smallest and largest of integer codes ((0, -1) for no run), read by blocks."""
    found = [(int(part.min()), int(part.max())) for part in blocks(codes) if part.size]
    if not found:
        return 0, -1
    return min(low for low, _ in found), max(high for _, high in found)


def compact_codes(codes: Any) -> np.ndarray:
    """Integer codes (e.g. a lazily read ``<factor>_level``) in memory in the smallest signed
    integer type that holds them: 1 byte per run for up to 127 levels instead of 4. Read a
    block of runs at a time (two passes: the range, then the values)."""
    low, high = code_range(codes)
    dtype = next(
        t
        for t in (np.int8, np.int16, np.int32, np.int64)
        if np.iinfo(t).min <= low and high <= np.iinfo(t).max
    )
    out = np.empty(len(codes), dtype=dtype)
    for part in run_slices(len(codes)):
        out[part] = np.asarray(codes[part])
    return out


def level_count(codes: Any) -> int:
    """Levels of 0-based level codes (their largest + 1; 0 for no run), read by blocks."""
    return code_range(codes)[1] + 1


def finite_summary(values: Any, block: int | None = None) -> FiniteSummary:
    """The :class:`FiniteSummary` of ``values`` (any shape, runs first), read block by block."""
    summary = FiniteSummary()
    for part in blocks(values, block):
        summary.add(np.asarray(part, dtype=float))
    return summary
