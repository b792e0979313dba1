"""Level codes of a full factorial in grid order, computed from the run index when read.

This engine writes a full factorial in grid order, the last factor fastest, so the level of
factor ``i`` at run ``r`` is ``(r // stride_i) % count_i`` with ``stride_i`` the product of
the later factors' level counts. Computed a block at a time, the codes cost nothing per run:
held compactly they are a byte per run and factor (400 MB for four factors at 10⁸ runs).
Like :mod:`studies.analysis.filled_array`, an xarray backend array (``BackendArray`` with
``explicit_indexing_adapter``)."""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from typing import Any

import numpy as np
import xarray as xr
from xarray.backends import BackendArray
from xarray.core import indexing

from studies.analysis.factorial import GridOrder, grid_of


class GridCodes(BackendArray):
    """The 0-based level of one factor at each run of a full factorial in grid order."""

    def __init__(self, runs: int, count: int, stride: int) -> None:
        self.shape = (runs,)
        self.count, self.stride = count, stride
        self.dtype = np.dtype(np.int8 if count <= np.iinfo(np.int8).max else np.int32)

    def __getitem__(self, key: indexing.ExplicitIndexer) -> Any:
        return indexing.explicit_indexing_adapter(
            key, self.shape, indexing.IndexingSupport.OUTER, self._read
        )

    def _read(self, key: tuple[Any, ...]) -> np.ndarray:
        (at,) = key
        if isinstance(at, slice) and at.indices(self.shape[0])[2] == 1:
            start, stop, _ = at.indices(self.shape[0])
            return self._range(start, max(start, stop))
        runs = np.arange(*at.indices(self.shape[0])) if isinstance(at, slice) else np.asarray(at)
        return ((runs // self.stride) % self.count).astype(self.dtype)

    def first_runs(self) -> np.ndarray:
        """The first run at each level (level × stride), without reading a run."""
        return np.arange(self.count, dtype=np.int64) * self.stride

    def _range(self, start: int, stop: int) -> np.ndarray:
        """The codes of runs ``start … stop-1`` without a division per run: the period of
        ``count × stride`` runs tiled when the range spans it, else the runs of each level
        repeated (at most ``(stop - start) / stride + 2`` of them)."""
        period = self.count * self.stride
        if period <= stop - start:
            pattern = np.repeat(np.arange(self.count, dtype=self.dtype), self.stride)
            offset = start % period
            reps = -(-(offset + stop - start) // period)
            return np.tile(pattern, reps)[offset : offset + stop - start]
        first, last = start // self.stride, (stop - 1) // self.stride
        bounds = np.arange(first, last + 2) * self.stride
        bounds[0], bounds[-1] = start, stop
        codes = (np.arange(first, last + 1) % self.count).astype(self.dtype)
        return np.repeat(codes, np.diff(bounds))


def grid_coordinates(
    ds: xr.Dataset, factors: Sequence[str], counts: Sequence[int]
) -> dict[str, xr.Variable]:
    """``<factor>_level`` of every factor as :class:`GridCodes` (attributes kept)."""
    runs = ds.sizes["run"]
    out = {}
    for i, (f, count) in enumerate(zip(factors, counts, strict=True)):
        codes = GridCodes(runs, int(count), math.prod(int(c) for c in counts[i + 1 :]))
        old = ds[f"{f}_level"].variable
        out[f"{f}_level"] = xr.Variable(old.dims, indexing.LazilyIndexedArray(codes), old.attrs)
    return out


def computed(variable: xr.Variable) -> GridCodes | None:
    """The :class:`GridCodes` behind ``variable``, if it is made of them."""
    found = getattr(getattr(variable, "_data", None), "array", None)
    return found if isinstance(found, GridCodes) else None


def grid_in_order(ds: xr.Dataset) -> GridOrder | None:
    """Factors, level counts and order (None: in grid order) of a full factorial, without
    reading a run when the codes are :class:`GridCodes`; else :func:`grid_of` (a pass over the
    codes). None when ``ds`` is not a complete full factorial."""
    if ds.attrs.get("design") != "full_factorial":
        return None
    factors = [str(f) for f in json.loads(ds.attrs.get("factors", "[]"))]
    codes = [computed(ds[f"{f}_level"].variable) for f in factors if f"{f}_level" in ds.coords]
    if factors and len(codes) == len(factors) and all(c is not None for c in codes):
        return factors, tuple(c.count for c in codes if c is not None), None
    return grid_of(ds)
