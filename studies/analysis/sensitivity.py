"""Variance decomposition of a complete full factorial: a computer experiment, with no noise.

A deterministic simulation repeated at the same point gives the same number, so in a full
factorial what an ANOVA calls "error" is the interactions. Here the total sum of squares of
the response on the grid (one axis per factor, every cell a run) is split exactly into

* main effects   SS_f  = (N / n_f) Σ_i m_f(i)²,          m_f the centred mean over the other axes;
* two-factor     SS_fg = (N / n_f n_g) Σ_ij (m_fg - m_f - m_g)²;
* the higher-order remainder = total - Σ SS_f - Σ SS_fg,

which add up to the total. With every level equally likely (the grid as a uniform discrete
distribution) these are the functional ANOVA (Hoeffding/Sobol) terms, and the first-order and
total-effect indices follow exactly by means over axes:

    S_f  = SS_f / SS_total,
    ST_f = Σ (y - mean over axis f)² / SS_total   (= E[Var(Y | X_~f)] / Var(Y)).

Each quantity is a mean over axes of the grid: O(N) per term.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from studies.analysis.sums_of_squares import Centred, centred, without_round_off
from studies.common.blocks import BLOCK, rows_per_block


@dataclass(frozen=True)
class Decomposition:
    """Sums of squares and Sobol indices of one response over a full-factorial grid."""

    factors: tuple[str, ...]
    main: np.ndarray  # SS per factor
    pairs: tuple[tuple[str, str], ...]
    pair: np.ndarray  # SS per factor pair (interaction only)
    remainder: float  # SS of all interactions of three or more factors
    total: float
    first_order: np.ndarray  # S_f per factor
    total_effect: np.ndarray  # ST_f per factor


def _mean_keeping(d: np.ndarray, keep: tuple[int, ...]) -> np.ndarray:
    return d.mean(axis=tuple(a for a in range(d.ndim) if a not in keep))


def slabs(shape: Sequence[int]) -> list[slice]:
    """Slices along the first axis of a grid of ``shape``, each about :data:`BLOCK` values."""
    step = rows_per_block(math.prod(shape[1:]))
    return [slice(i, i + step) for i in range(0, shape[0], step)]


class SlabGrid:
    """A grid (axis i = factor i) over values in grid order that are read a slab along the
    first axis at a time (``grid[a:b]``: rows a…b-1 of the first axis), e.g. a
    :class:`studies.common.blocks.RunValues`: what :func:`decompose` and
    :func:`mean_keeping` take instead of a grid in memory."""

    def __init__(self, values: Any, shape: Sequence[int]) -> None:
        self.values, self.shape = values, tuple(int(n) for n in shape)
        self.ndim, self.size = len(self.shape), math.prod(self.shape)

    def __getitem__(self, part: slice) -> np.ndarray:
        first, stop, _ = part.indices(self.shape[0])
        inner = self.size // self.shape[0]
        slab = np.asarray(self.values[first * inner : max(first, stop) * inner], dtype=float)
        return slab.reshape((-1, *self.shape[1:]))

    def reshape(self, shape: int) -> Any:
        """The values in grid order (``shape`` -1 only)."""
        if shape != -1:
            raise ValueError(f"a SlabGrid reshapes to -1 only, not {shape}")
        return self.values


def mean_keeping(grid: np.ndarray | SlabGrid, keep: tuple[int, ...]) -> np.ndarray:
    """The mean of ``grid`` over the axes not in ``keep``: NumPy's mean of an array, the sums
    of the slabs of a :class:`SlabGrid` added (the same within round-off)."""
    if isinstance(grid, np.ndarray):
        return _mean_keeping(grid, keep)
    others = tuple(a for a in range(grid.ndim) if a not in keep)
    total = np.zeros(tuple(grid.shape[a] for a in keep))
    for part in slabs(grid.shape):
        kept = grid[part].sum(axis=others)
        if 0 in keep:
            total[part] += kept
        else:
            total += kept
    return total / (grid.size / total.size)


def squares(d: np.ndarray, axis: int | None = None) -> float:
    """Σ d² (``axis`` None) or Σ (d − the mean of d along ``axis``)², summed by slabs of about
    :data:`BLOCK` values along another axis, so no temporary as large as ``d`` is made (a grid
    of 10⁷ runs: 80 MB each). One slab (``d.size`` ≤ BLOCK): NumPy's pairwise sum of the whole,
    as written; more: the slabs' sums added, which differs from it in the last bits only."""
    mean = None if axis is None else d.mean(axis=axis, keepdims=True)
    if d.size <= BLOCK or d.ndim == 1:
        e = d if mean is None else d - mean
        return float(np.sum(e * e))
    along = 1 if axis == 0 else 0
    step = max(1, BLOCK * d.shape[along] // d.size)
    total = 0.0
    for start in range(0, d.shape[along], step):
        slab = tuple(
            slice(start, start + step) if k == along else slice(None) for k in range(d.ndim)
        )
        e = d[slab] if mean is None else d[slab] - mean[slab]
        total += float(np.sum(e * e))
    return total


Sums = tuple[float, list[np.ndarray], dict[tuple[int, int], np.ndarray], np.ndarray]
"""Of the centred grid d: Σ d², the mean over the other axes of each axis and of each pair of
axes, and Σ (d − its mean along each axis)²."""


def _whole(grid: np.ndarray) -> Sums:
    """:data:`Sums` from the centred grid made whole (one block: the numbers as written)."""
    d = centred(grid.ravel()).reshape(grid.shape)
    pairs = itertools.combinations(range(d.ndim), 2)
    return (
        squares(d),
        [_mean_keeping(d, (a,)) for a in range(d.ndim)],
        {(a, b): _mean_keeping(d, (a, b)) for a, b in pairs},
        np.array([squares(d, a) for a in range(d.ndim)]),
    )


def _by_slabs(grid: np.ndarray | SlabGrid) -> Sums:
    """:data:`Sums` over slabs of about :data:`BLOCK` values along the first axis, each
    centred when read (:class:`studies.analysis.sums_of_squares.Centred`): no array as large
    as the grid is made (the mean along the first axis, ``grid.size / grid.shape[0]`` values,
    is kept for a second pass). The sums of the slabs are added: the numbers of
    :func:`_whole` within round-off."""
    k, n, shape = grid.ndim, grid.size, grid.shape
    centring = Centred(grid.reshape(-1))
    parts = slabs(shape)
    pairs = list(itertools.combinations(range(k), 2))
    total = 0.0
    sums = [np.zeros(m) for m in shape]
    pair_sums = {(a, b): np.zeros((shape[a], shape[b])) for a, b in pairs}
    first_axis = np.zeros(shape[1:])
    within = np.zeros(k)

    def slab(part: slice) -> np.ndarray:
        d = grid[part] - centring.first
        d -= centring.second
        return d

    for part in parts:
        d = slab(part)
        total += float(np.sum(d * d))
        first_axis += d.sum(axis=0)
        for a in range(k):
            kept = d.sum(axis=tuple(x for x in range(k) if x != a))
            if a == 0:
                sums[0][part] += kept
            else:
                sums[a] += kept
                e = d - d.mean(axis=a, keepdims=True)  # whole lines along a: in the slab
                within[a] += float(np.sum(e * e))
        for a, b in pairs:
            kept = d.sum(axis=tuple(x for x in range(k) if x not in (a, b)))
            if a == 0:
                pair_sums[a, b][part] += kept
            else:
                pair_sums[a, b] += kept
    first_axis /= shape[0]
    for part in parts:
        e = slab(part) - first_axis
        within[0] += float(np.sum(e * e))
    means = [total_a / (n / m) for total_a, m in zip(sums, shape, strict=True)]
    pair_means = {p: t / (n / t.size) for p, t in pair_sums.items()}
    return total, means, pair_means, within


def decompose(grid: np.ndarray | SlabGrid, factors: tuple[str, ...]) -> Decomposition:
    """Decomposition of a response on a complete grid (axis i = factor i; finite values; a
    :class:`SlabGrid` above a block is read a slab at a time)."""
    if isinstance(grid, SlabGrid) and grid.size <= BLOCK:
        grid = grid[:]
    elif not isinstance(grid, SlabGrid):
        grid = np.asarray(grid, dtype=float)
    if isinstance(grid, np.ndarray) and (grid.size <= BLOCK or grid.ndim == 1):
        total, means, pair_means, within = _whole(grid)
    else:
        total, means, pair_means, within = _by_slabs(grid)
    n = grid.size
    main = np.array([n / m.size * float(m @ m) for m in means])
    pairs = tuple(itertools.combinations(range(grid.ndim), 2))
    pair = np.zeros(len(pairs))
    for i, (a, b) in enumerate(pairs):
        effect = pair_means[a, b] - means[a][:, None] - means[b][None, :]
        pair[i] = n / effect.size * float(np.sum(effect * effect))
    main, pair = without_round_off(main, total), without_round_off(pair, total)
    within = without_round_off(within, total)
    remainder = float(without_round_off(np.array([total - main.sum() - pair.sum()]), total)[0])
    with np.errstate(invalid="ignore", divide="ignore"):
        first, total_effect = main / total, within / total
    return Decomposition(
        factors=factors,
        main=main,
        pairs=tuple((factors[a], factors[b]) for a, b in pairs),
        pair=pair,
        remainder=remainder,
        total=total,
        first_order=first,
        total_effect=total_effect,
    )
