"""Results for other tools: a table per run (CSV or Parquet, via pandas).

One row per design point: the factor values, their level indices and every scalar response;
column names carry the units (``max_jerk [mm/rad^3]``), so the file says what it holds without
the netCDF beside it. Curves (run × angle) stay in ``results.nc``.
"""

from __future__ import annotations

from pathlib import Path

import pandas as pd
import xarray as xr

FORMATS = ("csv", "parquet")


def results_table(ds: xr.Dataset) -> pd.DataFrame:
    """The design points of a results Dataset as a DataFrame (index: design point)."""
    columns = {}
    for name in [*ds.coords, *ds.data_vars]:
        da = ds[name]
        if da.dims != ("run",) or name == "run":
            continue
        units = str(da.attrs.get("units", ""))
        columns[f"{name} [{units}]" if units not in ("", "1") else str(name)] = da.values
    frame = pd.DataFrame(columns, index=pd.Index(ds["run"].values, name="run"))
    frame.attrs = {k: v for k, v in ds.attrs.items() if k in ("run_id", "study_name", "scene")}
    return frame


def export_results(results: Path, to: Path, file_format: str) -> Path:
    """Write the table of ``results`` to ``to`` as CSV or Parquet; return ``to``."""
    if file_format not in FORMATS:
        raise ValueError(f"unknown format {file_format!r}: use one of {', '.join(FORMATS)}")
    with xr.open_dataset(results) as ds:
        frame = results_table(ds.load())
    to.parent.mkdir(parents=True, exist_ok=True)
    if file_format == "csv":
        frame.to_csv(to)
    else:
        try:
            frame.to_parquet(to)
        except ImportError as exc:
            msg = f"Parquet needs pyarrow: pip install pyarrow ({exc})"
            raise ValueError(msg) from None
    return to
