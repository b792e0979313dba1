"""Refresh the isac_l9 regression baseline: ``nox -s baseline`` (or run this file).

Runs the shipped isac_l9 study and keeps its factor coordinates and responses (with units) in
tests/studies/data/isac_l9_baseline.nc. Review ``git diff --stat`` and the printed values
before committing: a refresh is a claim that the new numbers are the right ones.
"""

from __future__ import annotations

import sys
import tempfile
from pathlib import Path

import xarray as xr

from studies.pipeline import run_study

BASELINE = Path(__file__).parent / "data" / "isac_l9_baseline.nc"
KEEP_ATTRS = (
    "study_name",
    "scene",
    "design",
    "factors",
    "error_columns",
    "responses",
    "git_commit",
    "git_dirty",
)


def baseline_from(ds: xr.Dataset) -> xr.Dataset:
    """The part of a results Dataset the regression test compares."""
    small = ds.copy()
    small.attrs = {k: ds.attrs[k] for k in KEEP_ATTRS if k in ds.attrs}
    return small


def refresh() -> Path:
    with tempfile.TemporaryDirectory() as tmp:
        result = run_study("isac_l9", outputs=Path(tmp), progress=False)
        small = baseline_from(result.dataset)
    BASELINE.parent.mkdir(parents=True, exist_ok=True)
    small.to_netcdf(BASELINE, engine="netcdf4", format="NETCDF4")
    return BASELINE


if __name__ == "__main__":
    path = refresh()
    with xr.open_dataset(path) as ds:
        print(ds.to_dataframe().to_string(), file=sys.stdout)
    print(f"wrote {path}")
