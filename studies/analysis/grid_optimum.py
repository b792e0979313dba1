"""The best computed point of a full factorial, with its neighbours, per operating condition.

Every level combination of a full factorial was computed, so its optimum is not predicted: it
is the best run. Factors have a role (:mod:`studies.define.values`): only **control**
factors are chosen; **operating** factors (speed, load) are conditions the design must meet at
every level. With operating factors, the design points form a table of control combinations ×
conditions (the operating-level combinations); the chosen control combination is the one with
the best mean over the conditions, and the table gives its value
in each condition, the worst of them, and the best run of each condition on its own.
Neighbours: the control combinations one level below and above the chosen one in each control
factor, others fixed (their mean over the conditions), which shows whether the optimum is flat
and whether it sits at the edge of the grid. O(N) in the design points.

Runs without a value of their own (:mod:`studies.analysis.missing`) enter at the bound they were counted
at, but a bound is not a value: a run whose ``none_means`` is "best" (the reed's "no crossing")
is better than every computed value and one whose value is "worst" is worse than every one. So
the combinations are ranked by (fewest such worst runs, most such best runs, best mean, means
within round-off of each other equal, as in the range analysis); among ties, the one whose levels have the best main effects wins (then the first in grid order),
and the number of tied combinations is kept, for the report to say.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable, Iterator, Mapping, Sequence
from contextlib import ExitStack
from dataclasses import dataclass
from typing import Any

import numpy as np

from studies.analysis import scratch
from studies.analysis.sensitivity import SlabGrid, slabs
from studies.analysis.sums_of_squares import ROUND_OFF
from studies.common.blocks import (
    FiniteSummary,
    finite_summary,
    gather,
    rows_per_block,
    run_slices,
    values_of,
)
from studies.common.run_masks import BlockMask

SIDES = ("below", "above")
SCORE_ROWS = 1 << 16
"""Table rows whose tie-break scores are made at a time (:meth:`Grid._tie_break`)."""


@dataclass(frozen=True)
class GridOptimum:
    """The chosen control levels (0-based; empty when nothing varies under control) and, per
    condition, the value and run there and the best run of that condition. ``neighbours``:
    control factor → ((mean, run), (mean, run)) one level below and above (NaN, -1 at an edge;
    the run only when there is a single condition). ``ties``: control combinations that share the
    best rank (1: no tie); ``tie_rule``: what chose among them ("main effects", "grid order" or
    "" without a tie)."""

    levels: dict[str, int]
    at: np.ndarray
    runs: np.ndarray
    best_values: np.ndarray
    best_runs: np.ndarray
    neighbours: dict[str, tuple[tuple[float, int], tuple[float, int]]]
    ties: int = 1
    tie_rule: str = ""

    @property
    def mean(self) -> float:
        return float(np.mean(self.at)) if self.at.size else math.nan


class RunView:
    """``form(values[key])`` where read (``values`` per run, read by slices): a table per
    control combination that is a function of one run's value, never written out."""

    def __init__(self, values: Any, form: Callable[[np.ndarray], np.ndarray]) -> None:
        self.values, self.form, self.size = values, form, len(values)

    def __len__(self) -> int:
        return self.size

    def __getitem__(self, key: slice | int) -> Any:
        if not isinstance(key, slice):
            return self[int(key) : int(key) + 1][0]
        return self.form(np.asarray(self.values[key]))


class Grid:
    """The runs of a complete full factorial as control combinations × operating conditions.

    ``order``: the grid order of :func:`studies.run.results.grid_order` (run index of each grid
    cell, factors in ``factors`` order, last factor fastest), or None when each run is at its
    own cell (:func:`studies.run.results.grid_cells`): then the runs of a block of rows are
    computed when read, and no table of all runs is held."""

    def __init__(
        self,
        factors: Sequence[str],
        counts: Sequence[int],
        order: np.ndarray | None,
        operating: Sequence[str],
    ) -> None:
        self.control = [f for f in factors if f not in operating]
        self.operating = [f for f in factors if f in operating]
        index = {f: i for i, f in enumerate(factors)}
        self.control_counts = tuple(int(counts[index[f]]) for f in self.control)
        self.operating_counts = tuple(int(counts[index[f]]) for f in self.operating)
        self.shape = (math.prod(self.control_counts), math.prod(self.operating_counts))
        strides = [math.prod(int(c) for c in counts[i + 1 :]) for i in range(len(counts))]
        self._strides = (
            [strides[index[f]] for f in self.control],
            [strides[index[f]] for f in self.operating],
        )
        perm = [index[f] for f in (*self.control, *self.operating)]
        self._runs = None
        if order is not None:
            self._runs = (
                np.asarray(order).reshape(tuple(counts)).transpose(perm).reshape(self.shape)
            )
        self._in_row_order = order is None and perm == sorted(perm)  # rows are run ranges

    @property
    def runs(self) -> np.ndarray:
        """The run of every cell of :meth:`table` (O(N): :meth:`rows` reads a block of rows)."""
        return self.rows(slice(None))

    def rows(self, part: slice) -> np.ndarray:
        """The runs of the rows ``part`` of :meth:`table` (rows × conditions)."""
        if self._runs is not None:
            return self._runs[part]
        first, stop, _ = part.indices(self.shape[0])
        if self._in_row_order:  # operating factors last: row r holds runs r·n … r·n + n - 1
            n = self.shape[1]
            return np.arange(first * n, max(first, stop) * n).reshape(-1, n)
        rows = np.arange(first, stop)
        cell = np.zeros((rows.size, self.shape[1]), dtype=np.int64)
        for counts, strides, at, axis in (
            (self.control_counts, self._strides[0], rows, 0),
            (self.operating_counts, self._strides[1], np.arange(self.shape[1]), 1),
        ):
            codes = np.unravel_index(at, counts) if counts else ()
            for c, stride in zip(codes, strides, strict=True):
                cell += np.expand_dims(c * stride, 1 - axis)
        return cell

    def row(self, row: int) -> np.ndarray:
        """The runs of one row of :meth:`table` (one per condition; a copy)."""
        return self.rows(slice(row, row + 1))[0].copy()

    def conditions(self) -> list[dict[str, int]]:
        """The operating-level combinations, in the column order of :meth:`table`."""
        return [
            dict(zip(self.operating, combo, strict=True))
            for combo in itertools.product(*(range(n) for n in self.operating_counts))
        ]

    def table(self, y: np.ndarray) -> np.ndarray:
        """``y`` (per run) as control combinations × conditions."""
        return np.asarray(y, dtype=float)[self.runs]

    def combination(self, levels: Mapping[str, int]) -> int:
        """Row of :meth:`table` holding the control ``levels``."""
        if not self.control:
            return 0
        codes = tuple(int(levels[f]) for f in self.control)
        return int(np.ravel_multi_index(codes, self.control_counts))

    def optimum(self, y: Any, sense: str, beyond: Any = None) -> GridOptimum | None:
        """The best computed control combination of ``y`` (per run: a float array, or a
        :class:`studies.common.blocks.RunValues` read a block of rows at a time; NaN where a run has no value: a
        combination missing a condition is not chosen); None if none is complete. ``beyond``
        (per run, :attr:`studies.analysis.missing.Filled.beyond`): +1 where the run's value is a bound
        it is better than, -1 one it is worse than."""
        with ExitStack() as stack:
            return self._optimum(values_of(y), sense, beyond, stack)

    def _optimum(self, y: Any, sense: str, beyond: Any, stack: ExitStack) -> GridOptimum | None:
        mean, bounds, best_values, best_runs = self._rows(y, sense, beyond, stack)
        if not finite_summary(mean).count:
            return None
        row, ties, rule = self._tie_break(mean, self._best(mean, bounds))
        codes = np.unravel_index(row, self.control_counts) if self.control else ()
        levels = {f: int(c) for f, c in zip(self.control, codes, strict=True)}
        sign = 1.0 if sense == "smaller" else -1.0
        neighbours = {
            f: (
                self._neighbour(mean, sign, levels, f, -1),
                self._neighbour(mean, sign, levels, f, 1),
            )
            for f in self.control
        }
        return GridOptimum(
            levels,
            gather(y, self.row(row)),
            self.row(row),
            best_values,
            best_runs,
            neighbours,
            ties,
            rule,
        )

    def _rows(
        self, y: Any, sense: str, beyond: Any, stack: ExitStack
    ) -> tuple[Any, tuple[Any, Any] | None, np.ndarray, np.ndarray]:
        """One pass over :meth:`table`, a block of rows at a time: each control combination's
        signed mean over the conditions (the smaller the better), its runs counted at a worse
        and at a better bound (when ``beyond`` is given), and each condition's best value and
        its run (the first of equals). The per-row tables are arrays up to a block of rows,
        else scratch files closed with ``stack`` (:func:`studies.analysis.scratch.column`)."""
        rows, conditions = self.shape
        # One condition, rows in run order, values read by slices: a row's mean is its run's
        # signed value, read where needed instead of written out.
        views = conditions == 1 and self._in_row_order and not isinstance(y, np.ndarray)
        if views:
            mean: Any = RunView(y, lambda v: v if sense == "smaller" else -v)
        else:
            mean = scratch.column(rows, float, stack)
        bounds: tuple[Any, Any] | None = None
        if beyond is not None and views:
            bounds = (RunView(beyond, lambda b: b < 0), RunView(beyond, lambda b: b > 0))
        elif beyond is not None:
            bounds = (scratch.column(rows, np.int32, stack), scratch.column(rows, np.int32, stack))
        best_signed = np.full(conditions, np.inf)
        best_values = np.full(conditions, np.nan)
        best_runs = np.full(conditions, -1, dtype=np.int64)
        for part in run_slices(rows, rows_per_block(conditions)):
            runs = self.rows(part)
            values = gather(y, runs)
            signed = values if sense == "smaller" else -values
            if not views:
                with np.errstate(invalid="ignore"):
                    mean[part] = signed.mean(axis=1)
            if bounds is not None and not views:
                seen = gather(beyond, runs)
                bounds[0][part] = (seen < 0).sum(axis=1)
                bounds[1][part] = (seen > 0).sum(axis=1)
            # each condition's first smallest value (nanargmin), later blocks only if smaller
            k = np.argmin(np.where(np.isnan(signed), np.inf, signed), axis=0)
            columns = np.arange(conditions)
            found = signed[k, columns]
            better = np.isfinite(signed).any(axis=0) & (found < best_signed)
            best_signed[better] = found[better]
            best_values[better] = values[k, columns][better]
            best_runs[better] = runs[k, columns][better]
        return mean, bounds, best_values, best_runs

    def _best(self, mean: Any, bounds: tuple[Any, Any] | None) -> BlockMask:
        """The control combinations that share the first place in the order of the module
        docstring (a mask, held only in its mixed blocks): fewest worst-bound runs, then most
        best-bound runs, then the best mean. O(rows), one pass per key (no sort: only the
        first place is needed), each pass a block of rows at a time (minima and maxima: exact
        in any order)."""
        seen = finite_summary(mean)
        # Means within round-off of the best are ties, as in the range analysis (R = 0).
        best, tolerance = seen.low, ROUND_OFF * seen.largest
        chosen = BlockMask(mean.size)
        parts = list(enumerate(chosen.parts))
        for i, p in parts:
            chosen[i] = np.isfinite(mean[p])

        def keep(key_of: Callable[[slice], np.ndarray], smallest: bool) -> None:
            """Keep the chosen rows whose key is the smallest (largest) among them."""
            extreme = min if smallest else max
            found = [
                k.min() if smallest else k.max()
                for i, p in parts
                if chosen.any(i) and (k := key_of(p)[chosen[i]]).size
            ]
            target = extreme(found)
            for i, p in parts:
                if chosen.any(i):
                    chosen[i] = chosen[i] & (key_of(p) == target)

        if bounds is not None:
            worse, better = bounds
            keep(lambda p: worse[p], smallest=True)
            keep(lambda p: better[p], smallest=False)
        keep(lambda p: np.where(mean[p] <= best + tolerance, best, mean[p]), smallest=True)
        return chosen

    def _tie_break(self, mean: Any, first: BlockMask) -> tuple[int, int, str]:
        """The best-ranked row, the number of rows sharing its rank and the rule that chose:
        among exact ties, the one whose levels have the best main effects (mean of ``mean``
        over each factor's level, summed), so a flat optimum agrees with the range analysis
        instead of the grid order."""
        ties = first.count()
        if ties == 1 or not self.control:
            return first.first(), ties, "" if ties == 1 else "grid order"
        effects = self._main_effects(mean)
        parts = [i for i in range(len(first.parts)) if first.any(i)]

        def scores() -> Iterator[tuple[np.ndarray, np.ndarray]]:
            """The tied rows and their summed main effects, ``SCORE_ROWS`` rows of the table
            at a time: temporaries of one size, which the allocator reuses (a block's worth,
            of a size that varies with its ties, made its heap grow at every block)."""
            for i in parts:
                start, mask = first.parts[i].start, first[i]
                for at in range(0, mask.size, SCORE_ROWS):
                    rows = start + at + np.flatnonzero(mask[at : at + SCORE_ROWS])
                    codes = np.unravel_index(rows, self.control_counts)
                    terms = (effect[c] for effect, c in zip(effects, codes, strict=True))
                    yield rows, sum(terms, np.zeros(rows.size))

        seen = FiniteSummary()
        for _, score in scores():
            seen.add(score)
        if not seen.count:
            return first.first(), ties, "grid order"
        # Scores within round-off of the best are equal (as the means are): a choice made by
        # the last bits would depend on the order of a sum, and say "main effects" falsely.
        limit = seen.low + ROUND_OFF * seen.largest
        near, row = 0, -1  # how many score within round-off of the best; the first of them
        for rows, score in scores():
            within = score <= limit
            near += int(within.sum())
            if row < 0 and within.any():
                row = int(rows[np.argmax(within)])
        if near == ties:
            return first.first(), ties, "grid order"
        return row, ties, "main effects"

    def _main_effects(self, mean: Any) -> list[np.ndarray]:
        """Per control factor, the mean of the finite row means at each of its levels (NaN
        where none), summed over slabs of about a block of rows along the first factor."""
        grid = SlabGrid(mean, self.control_counts)
        sums = [np.zeros(n) for n in grid.shape]
        counts = [np.zeros(n) for n in grid.shape]
        for rows in slabs(grid.shape):
            slab = grid[rows]
            finite = np.isfinite(slab)
            filled = np.where(finite, slab, 0.0)
            for axis in range(slab.ndim):
                others = tuple(a for a in range(slab.ndim) if a != axis)
                part = rows if axis == 0 else slice(None)
                sums[axis][part] += filled.sum(axis=others)
                counts[axis][part] += finite.sum(axis=others)
        return [
            np.where(n > 0, total / np.maximum(n, 1), np.nan)
            for total, n in zip(sums, counts, strict=True)
        ]

    def _neighbour(
        self, mean: Any, sign: float, levels: Mapping[str, int], factor: str, step: int
    ) -> tuple[float, int]:
        """The mean (``sign`` × the signed ``mean``) and, with one condition, the run of the
        combination one level ``step`` away in ``factor`` (NaN, -1 past the edge)."""
        level = levels[factor] + step
        if not 0 <= level < self.control_counts[self.control.index(factor)]:
            return math.nan, -1
        row = self.combination({**levels, factor: level})
        run = int(self.row(row)[0]) if self.shape[1] == 1 else -1
        return float(mean[row] * sign), run
