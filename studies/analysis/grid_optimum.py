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
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from studies.analysis.sums_of_squares import ROUND_OFF

SIDES = ("below", "above")
TIE_BLOCK = 1 << 20  # tied rows whose level codes are made at once (8 MB a factor)


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


class Grid:
    """The runs of a complete full factorial as control combinations × operating conditions.

    ``order``: the grid order of :func:`studies.run.results.grid_order` (run index of each grid
    cell, factors in ``factors`` order, last factor fastest)."""

    def __init__(
        self,
        factors: Sequence[str],
        counts: Sequence[int],
        order: np.ndarray,
        operating: Sequence[str],
    ) -> None:
        self.control = [f for f in factors if f not in operating]
        self.operating = [f for f in factors if f in operating]
        index = {f: i for i, f in enumerate(factors)}
        self.control_counts = tuple(int(counts[index[f]]) for f in self.control)
        self.operating_counts = tuple(int(counts[index[f]]) for f in self.operating)
        perm = [index[f] for f in (*self.control, *self.operating)]
        grid = np.asarray(order).reshape(tuple(counts)).transpose(perm)
        self.runs = grid.reshape(math.prod(self.control_counts), math.prod(self.operating_counts))

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

    def optimum(
        self, y: np.ndarray, sense: str, beyond: np.ndarray | None = None
    ) -> GridOptimum | None:
        """The best computed control combination of ``y`` (NaN where a run has no value: a
        combination missing a condition is not chosen); None if none is complete. ``beyond``
        (per run, :attr:`studies.analysis.missing.Filled.beyond`): +1 where the run's value is a bound
        it is better than, -1 one it is worse than."""
        values = self.table(y)
        signed = values if sense == "smaller" else -values
        with np.errstate(invalid="ignore"):
            mean = signed.mean(axis=1)
        if not np.isfinite(mean).any():
            return None
        row, ties, rule = self._tie_break(mean, self._best(mean, beyond))
        codes = np.unravel_index(row, self.control_counts) if self.control else ()
        levels = {f: int(c) for f, c in zip(self.control, codes, strict=True)}
        best_values = np.full(values.shape[1], np.nan)
        best_runs = np.full(values.shape[1], -1, dtype=np.int64)
        for j in range(values.shape[1]):
            column = signed[:, j]
            if np.isfinite(column).any():
                k = int(np.nanargmin(column))
                best_values[j], best_runs[j] = values[k, j], self.runs[k, j]
        sign = 1.0 if sense == "smaller" else -1.0
        neighbours = {
            f: (
                self._neighbour(mean * sign, levels, f, -1),
                self._neighbour(mean * sign, levels, f, 1),
            )
            for f in self.control
        }
        return GridOptimum(
            levels,
            values[row].copy(),  # a copy: a view would keep the whole table alive
            self.runs[row].copy(),
            best_values,
            best_runs,
            neighbours,
            ties,
            rule,
        )

    def _best(self, mean: np.ndarray, beyond: np.ndarray | None) -> np.ndarray:
        """The control combinations that share the first place in the order of the module
        docstring (a mask): fewest worst-bound runs, then most best-bound runs, then the best
        mean. O(N), one pass per key (no sort: only the first place is needed)."""
        finite = np.isfinite(mean)
        # Means within round-off of the best are ties, as in the range analysis (R = 0).
        best = np.min(mean[finite])
        tolerance = ROUND_OFF * np.max(np.abs(mean[finite]))
        chosen = finite.copy()
        if beyond is not None:
            bounds = np.asarray(beyond)[self.runs]
            worse, better = (bounds < 0).sum(axis=1), (bounds > 0).sum(axis=1)
            chosen &= worse == worse[chosen].min()
            chosen &= better == better[chosen].max()
        near = np.where(mean <= best + tolerance, best, mean)
        return chosen & (near == near[chosen].min())

    def _tie_break(self, mean: np.ndarray, first: np.ndarray) -> tuple[int, int, str]:
        """The best-ranked row, the number of rows sharing its rank and the rule that chose:
        among exact ties, the one whose levels have the best main effects (mean of ``mean``
        over each factor's level, summed), so a flat optimum agrees with the range analysis
        instead of the grid order."""
        tied = np.flatnonzero(first)
        if tied.size == 1:
            return int(tied[0]), 1, ""
        if not self.control:
            return int(tied[0]), int(tied.size), "grid order"
        grid = mean.reshape(self.control_counts)
        finite = np.isfinite(grid)
        filled = np.where(finite, grid, 0.0)
        effects = []
        for axis, _ in enumerate(self.control):
            others = tuple(a for a in range(len(self.control)) if a != axis)
            total = filled.sum(axis=others)
            count = finite.sum(axis=others)
            effects.append(np.where(count > 0, total / np.maximum(count, 1), np.nan))
        del grid, finite, filled
        score = np.empty(tied.size)
        for start in range(0, tied.size, TIE_BLOCK):  # the level codes of a block of rows
            block = tied[start : start + TIE_BLOCK]
            codes = np.unravel_index(block, self.control_counts)
            score[start : start + block.size] = sum(
                (effect[c] for effect, c in zip(effects, codes, strict=True)), np.zeros(block.size)
            )
        if not np.isfinite(score).any() or (score == np.nanmin(score)).sum() == tied.size:
            return int(tied[0]), int(tied.size), "grid order"
        return int(tied[int(np.nanargmin(score))]), int(tied.size), "main effects"

    def _neighbour(
        self, mean: np.ndarray, levels: Mapping[str, int], factor: str, step: int
    ) -> tuple[float, int]:
        level = levels[factor] + step
        if not 0 <= level < self.control_counts[self.control.index(factor)]:
            return math.nan, -1
        row = self.combination({**levels, factor: level})
        run = int(self.runs[row, 0]) if self.runs.shape[1] == 1 else -1
        return float(mean[row]), run
