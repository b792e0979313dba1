"""A response's analysed values read lazily: the stored values resolved by
:class:`studies.analysis.missing.Rule` at the runs that are read, never held for all runs.

The trade-off of a complete full factorial reads a response at a few runs only; holding each
filled response until then cost 8 bytes per run and response (80 MB a response at 10⁷ runs).
This is an xarray backend array (``BackendArray`` with ``explicit_indexing_adapter``, as the
xarray documentation describes for lazily loaded variables)."""

from __future__ import annotations

from typing import Any

import numpy as np
import xarray as xr
from xarray.backends import BackendArray
from xarray.core import indexing

from studies.analysis.missing import Rule


class FilledArray(BackendArray):
    """``rule.apply(raw[key], ran[key])`` for any key along the one dimension of ``raw``."""

    def __init__(self, raw: xr.Variable, ran: np.ndarray, rule: Rule) -> None:
        self.raw, self.ran, self.rule = raw, ran, rule
        self.shape = raw.shape
        self.dtype = np.dtype(float)

    def __getitem__(self, key: indexing.ExplicitIndexer) -> Any:
        return indexing.explicit_indexing_adapter(
            key, self.shape, indexing.IndexingSupport.OUTER_1VECTOR, self._read
        )

    def _read(self, key: tuple[Any, ...]) -> np.ndarray:
        return self.rule.apply(np.asarray(self.raw[key].values, dtype=float), self.ran[key])


def filled_variable(raw: xr.Variable, ran: np.ndarray, rule: Rule) -> xr.Variable:
    """``raw`` (one value per run, read lazily) resolved by ``rule`` where it is read."""
    lazy = indexing.LazilyIndexedArray(FilledArray(raw, ran, rule))
    return xr.Variable(raw.dims, lazy, raw.attrs)
