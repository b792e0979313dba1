"""Regression guard: a fresh isac_l9 run must reproduce the committed baseline.

The baseline (tests/studies/data/isac_l9_baseline.nc) was produced by
tests/studies/refresh_baseline.py (``nox -s baseline``) and reviewed against the physics
tests of the cam kernels; it is not an independent truth, it guards against unintended change.
Tolerances per variable: the responses are maxima over a fixed angle grid of closed-form
expressions, so runs agree to round-off; rtol 1e-7 leaves room for fused multiply-add and libm
differences between CPUs, and nothing more.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from studies.compare.testing import assert_results_close
from studies.pipeline import run_study

BASELINE = Path(__file__).parent / "data" / "isac_l9_baseline.nc"
RTOL = {
    "max_contact_stress": 1e-7,  # MPa
    "max_lubrication_coefficient_nose": 1e-7,  # dimensionless
    "max_jerk": 1e-7,  # mm/rad^3
}


@pytest.fixture(scope="module")
def fresh(tmp_path_factory: pytest.TempPathFactory) -> xr.Dataset:
    return run_study("isac_l9", outputs=tmp_path_factory.mktemp("out"), progress=False).dataset


@pytest.fixture(scope="module")
def baseline() -> xr.Dataset:
    with xr.open_dataset(BASELINE) as ds:
        return ds.load()


def test_same_design(fresh: xr.Dataset, baseline: xr.Dataset) -> None:
    assert fresh.sizes["run"] == baseline.sizes["run"] == 9
    for name in baseline.coords:
        np.testing.assert_array_equal(fresh[name].values, baseline[name].values, err_msg=name)
        assert fresh[name].attrs.get("units") == baseline[name].attrs.get("units")


def test_responses_match_baseline(fresh: xr.Dataset, baseline: xr.Dataset) -> None:
    assert_results_close(fresh, baseline, RTOL, atol=0)
