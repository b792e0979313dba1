"""Runs in blocks: a pass over a study's runs that holds one block at a time.

A response of 10⁸ runs is 800 MB in double precision; read :data:`BLOCK` runs at a time it is
8 MB. Summaries that do not depend on the order of the values (counts, minima, maxima, "any")
are exact over blocks; a sum over more than one block adds the blocks' sums (each NumPy's
pairwise sum), which differs from one pairwise sum of the whole in the last bits only, and a
study of at most :data:`BLOCK` runs gets the whole-array numbers bit for bit.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
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


class RunValues:
    """A variable with one value per run (e.g. a response read lazily from ``results.nc``)
    that gives float arrays when sliced: ``values[a:b]`` reads only those runs. What the block
    passes take instead of an array, so a response of 10⁸ runs is never held whole."""

    ndim = 1

    def __init__(self, variable: Any) -> None:
        self.variable = variable
        self.shape = (len(variable),)
        self.size = self.shape[0]

    def __len__(self) -> int:
        return self.size

    def __getitem__(self, key: Any) -> np.ndarray:
        return np.asarray(self.variable[key], dtype=float)


Values = np.ndarray | RunValues
"""Values per run: in memory, or read a slice at a time."""


def in_memory(variable: Any) -> bool:
    """Whether an xarray Variable's values are an array in memory (not read lazily)."""
    return isinstance(getattr(variable, "_data", None), np.ndarray)


def values_of(variable: Any) -> Values:
    """A response's values as the block passes read them: an array, or a Variable whose
    values are in memory, as a float array (no copy of floats); anything else read by slices
    (a Variable read lazily, a scratch column, a :class:`RunValues`) as a :class:`RunValues`."""
    if isinstance(variable, RunValues):
        return variable
    if isinstance(variable, (np.ndarray, list, tuple)) or in_memory(variable):
        return np.asarray(variable, dtype=float)
    return RunValues(variable)


SMALL_READ = 4096
"""Runs read as one range rather than one by one (two chunks of ``results.nc``)."""


def gather(values: Any, runs: np.ndarray) -> np.ndarray:
    """``values[runs]`` for integer ``runs`` of any shape. From a :class:`RunValues`: the
    range the runs span is read once when it is small (at most twice their number, or a
    chunk's worth: e.g. a block of grid rows), else the range of each column of ``runs`` (one
    per operating condition of a grid; each run of a 1-D ``runs``), so about a block is read
    at a time."""
    if isinstance(values, np.ndarray):
        return values[runs]
    if not runs.size:
        return np.empty(runs.shape)
    low, high = int(runs.min()), int(runs.max())
    if high - low < max(2 * runs.size, SMALL_READ):
        return values[low : high + 1][runs - low]
    table = runs.reshape(-1, runs.shape[-1]) if runs.ndim > 1 else runs.reshape(1, -1)
    out = np.empty(table.shape)
    for j in range(table.shape[1]):
        column = table[:, j]
        start = int(column.min())
        out[:, j] = values[start : int(column.max()) + 1][column - start]
    return out.reshape(runs.shape)


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


def runs_matching(conditions: Sequence[tuple[Any, int]], runs: int) -> np.ndarray:
    """The runs (ascending) of ``runs`` where every ``(codes, level)`` of ``conditions`` has
    its level: the codes (e.g. lazily read ``<factor>_level`` variables) a block at a time."""
    found = [np.zeros(0, dtype=np.int64)]
    for part in run_slices(runs):
        keep = np.ones(part.stop - part.start, dtype=bool)
        for codes, level in conditions:
            keep &= np.asarray(codes[part]) == level
        found.append(part.start + np.flatnonzero(keep))
    return np.concatenate(found)


def first_runs(codes: Any, levels: int) -> np.ndarray:
    """The first run at each level 0…levels-1 of ``codes`` (-1 where a level has none); a
    block of runs at a time, stopping once every level has its run."""
    first = np.full(levels, -1, dtype=np.int64)
    for part in run_slices(len(codes)):
        here = np.full(levels, -1, dtype=np.int64)
        runs = np.arange(part.start, part.stop)
        here[np.asarray(codes[part])[::-1]] = runs[::-1]  # repeated indices: the last wins
        new = (first < 0) & (here >= 0)
        first[new] = here[new]
        if (first >= 0).all():
            break
    return first


def first_run(codes: Any, level: int) -> int:
    """The first run at ``level`` of ``codes`` (-1 when none), a block of runs at a time,
    stopping at the block that holds it."""
    for part in run_slices(len(codes)):
        found = np.flatnonzero(np.asarray(codes[part]) == level)
        if found.size:
            return part.start + int(found[0])
    return -1


def level_count(codes: Any) -> int:
    """Levels of 0-based level codes (their largest + 1; 0 for no run), read by blocks."""
    return code_range(codes)[1] + 1


def finite_summary(values: Any, block: int | None = None) -> FiniteSummary:
    """The :class:`FiniteSummary` of ``values`` (any shape, runs first), read block by block."""
    summary = FiniteSummary()
    for part in blocks(values, block):
        summary.add(np.asarray(part, dtype=float))
    return summary
