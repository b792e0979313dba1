"""The computer-experiment view of a complete full factorial, for :func:`studies.analysis.analyze.analyze`:
main, two-factor and remainder sums of squares, Sobol indices (:mod:`studies.analysis.sensitivity`) and
the two-way mean over the strongest factor pair, written into the analysis Dataset."""

from __future__ import annotations

import numpy as np
import xarray as xr

from studies.analysis.sensitivity import SlabGrid, decompose, mean_keeping
from studies.common.blocks import blocks, values_of
from studies.run.results import grid_cells

GridOrder = tuple[list[str], tuple[int, ...], np.ndarray | None]


def grid_of(base: xr.Dataset) -> GridOrder | None:
    """Factors, level counts and grid order (None: the runs are in grid order) of a complete
    full factorial (None otherwise)."""
    try:
        return grid_cells(base)
    except ValueError:
        return None


def factorial_frame(out: xr.Dataset, grid: GridOrder) -> None:
    """The full-factorial variables (NaN until a response fills them) and their coordinates."""
    factors, counts, _ = grid
    nr, nf, most = out.sizes["response"], len(factors), max(counts)
    pairs = [f"{a} x {b}" for i, a in enumerate(factors) for b in factors[i + 1 :]]
    out.update(
        {
            "main_SS": (("response", "factor"), np.full((nr, nf), np.nan)),
            "first_order": (("response", "factor"), np.full((nr, nf), np.nan)),
            "total_effect": (("response", "factor"), np.full((nr, nf), np.nan)),
            "pair_SS": (("response", "pair"), np.full((nr, len(pairs)), np.nan)),
            "remainder_SS": ("response", np.full(nr, np.nan)),
            "total_SS": ("response", np.full(nr, np.nan)),
            "map_x": ("response", np.full(nr, "", dtype=object)),
            "map_y": ("response", np.full(nr, "", dtype=object)),
            "map_mean": (
                ("response", "map_level_y", "map_level_x"),
                np.full((nr, most, most), np.nan),
            ),
        }
    )
    out.coords["factor"] = factors
    out.coords["pair"] = pairs


def factorial(out: xr.Dataset, one: xr.Dataset, name: str, grid: GridOrder) -> None:
    """Main, two-factor and remainder SS and Sobol indices of a response that is finite in
    every run of a complete full factorial (otherwise the grid has holes: left NaN). A
    response in memory is used as the grid; one read lazily in grid order is read a slab of
    about a block of runs at a time (:class:`studies.analysis.sensitivity.SlabGrid`)."""
    factors, counts, order = grid
    y = values_of(one[name].variable)
    if order is not None:  # a copy only when the runs are not in grid order
        y = np.asarray(y[:], dtype=float)[order]
    if not all(np.isfinite(part).all() for part in blocks(y)):
        return
    i = out.indexes["response"].get_loc(name)
    values = y.reshape(counts) if isinstance(y, np.ndarray) else SlabGrid(y, counts)
    dec = decompose(values, tuple(factors))
    out["main_SS"].values[i], out["pair_SS"].values[i] = dec.main, dec.pair
    out["first_order"].values[i], out["total_effect"].values[i] = dec.first_order, dec.total_effect
    out["remainder_SS"].values[i], out["total_SS"].values[i] = dec.remainder, dec.total
    if len(factors) >= 2:
        a, b = np.argsort(-dec.total_effect, kind="stable")[:2]
        x, yy = sorted((int(a), int(b)))
        mean = mean_keeping(values, (x, yy))
        out["map_x"].values[i], out["map_y"].values[i] = factors[x], factors[yy]
        out["map_mean"].values[i, : counts[yy], : counts[x]] = mean.T
