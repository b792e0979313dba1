"""The grid order of a full factorial's results (studies.run.results.grid_order), made one
factor and one block of runs at a time, against ``np.ravel_multi_index`` + ``argsort``."""

from __future__ import annotations

import json

import numpy as np
import pytest
import xarray as xr

from studies.common.errors import StudyError
from studies.run import results


def shuffled_factorial(counts: tuple[int, ...], seed: int) -> xr.Dataset:
    rng = np.random.default_rng(seed)
    cells = rng.permutation(int(np.prod(counts)))
    codes = np.unravel_index(cells, counts)
    names = [f"f{i}" for i in range(len(counts))]
    coords = {f"{n}_level": ("run", c.astype(np.int32)) for n, c in zip(names, codes, strict=True)}
    attrs = {"design": "full_factorial", "factors": json.dumps(names)}
    return xr.Dataset(coords=coords, attrs=attrs)


@pytest.mark.parametrize("counts", [(7,), (3, 5), (4, 1, 6), (2, 3, 2, 5)])
def test_grid_order_is_the_inverse_of_each_runs_cell(monkeypatch, counts) -> None:
    monkeypatch.setattr(results, "ORDER_BLOCK", 4)
    ds = shuffled_factorial(counts, seed=len(counts))
    factors, got_counts, order = results.grid_order(ds)
    flat = np.ravel_multi_index([ds[f"{f}_level"].values for f in factors], counts)
    assert got_counts == counts
    np.testing.assert_array_equal(order, np.argsort(flat))


def test_an_incomplete_or_repeated_factorial_is_refused() -> None:
    ds = shuffled_factorial((3, 4), seed=1)
    repeated = ds.assign_coords(f1_level=("run", np.where(ds.f1_level == 3, 2, ds.f1_level)))
    with pytest.raises(StudyError, match="incomplete"):
        results.grid_order(ds.isel(run=slice(0, 11)))
    with pytest.raises(StudyError, match="incomplete"):
        results.grid_order(repeated)
