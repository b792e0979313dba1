"""Results for other tools: tables per run (CSV or Parquet, via pandas).

One row per design point (under ``[noise]``: per design point and noise case, with the noise
factors' values): the factor values, their level indices and every scalar response;
column names carry the units (``max_jerk [mm/rad^3]``), so the file says what it holds without
the netCDF beside it. A run that stored curves (run × ``cam_angle`` or another axis) gets a
second table ``<name>_curves.<format>`` in long format: one row per design point and angle,
with the run index, the factor values, the angle and every curve, written
:data:`CURVE_CHUNK` design points at a time (memory stays flat in the number of points).
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import xarray as xr

from studies.common.errors import StudyError
from studies.run.results import NOISE, is_scalar, readable

FORMATS = ("csv", "parquet")
CURVE_CHUNK = 1024  # design points per written block of the curve table


def results_table(ds: xr.Dataset) -> pd.DataFrame:
    """The design points of a results Dataset as a DataFrame (index: design point; under
    ``[noise]`` one row per design point and noise case, index (run, noise), each design
    point's values repeated over its noise cases)."""
    cases = ds.sizes.get(NOISE, 0)
    columns = {}
    for name in [*ds.coords, *ds.data_vars]:
        da = ds[name]
        if name in ("run", NOISE) or not is_scalar(da):
            continue
        values = da.values
        if cases and da.dims == ("run",):
            values = values.repeat(cases)
        columns[_label(da, name)] = values.reshape(-1)
    runs = ds["run"].values
    index = (
        pd.MultiIndex.from_product([runs, np.arange(cases)], names=["run", NOISE])
        if cases
        else pd.Index(runs, name="run")
    )
    frame = pd.DataFrame(columns, index=index)
    frame.attrs = {k: v for k, v in ds.attrs.items() if k in ("run_id", "study_name", "scene")}
    return frame


def _label(da: xr.DataArray, name: Any) -> str:
    units = str(da.attrs.get("units", ""))
    return f"{name} [{units}]" if units not in ("", "1") else str(name)


def curve_names(ds: xr.Dataset) -> list[str]:
    """The stored curves: variables on ``run`` × one axis."""
    return [
        str(n)
        for n, da in ds.data_vars.items()
        if da.ndim == 2 and da.dims[0] == "run" and da.dims[1] != NOISE
    ]


def curve_blocks(ds: xr.Dataset, size: int = CURVE_CHUNK) -> Any:
    """The curves in long format, ``size`` design points per DataFrame."""
    names = curve_names(ds)
    axis = ds[names[0]].dims[1]
    factors = [f for f in json.loads(ds.attrs.get("factors", "[]")) if f in ds]
    angles = ds[axis].values
    for start in range(0, ds.sizes["run"], size):
        part = ds.isel(run=slice(start, start + size))
        runs = part["run"].values
        columns: dict[str, Any] = {"run": runs.repeat(angles.size)}
        columns |= {_label(ds[f], f): part[f].values.repeat(angles.size) for f in factors}
        columns[_label(ds[axis], axis)] = np.tile(angles, runs.size)
        columns |= {_label(ds[n], n): part[n].values.reshape(-1) for n in names}
        yield pd.DataFrame(columns)


def export_results(results: Path, to: Path, file_format: str) -> list[Path]:
    """Write the table of ``results`` to ``to`` as CSV or Parquet, and its curves (if any) to
    ``<to stem>_curves<suffix>``; return the files written."""
    if file_format not in FORMATS:
        raise StudyError(f"unknown format {file_format!r}: use one of {', '.join(FORMATS)}")
    to.parent.mkdir(parents=True, exist_ok=True)
    with readable(results) as ds:
        frame = results_table(ds.load())
        written = [_write(iter([frame]), to, file_format, index=True)]
        if curve_names(ds):
            curves = to.with_name(f"{to.stem}_curves{to.suffix}")
            written.append(_write(curve_blocks(ds), curves, file_format, index=False))
    return written


def _write(blocks: Any, to: Path, file_format: str, index: bool) -> Path:
    """Write DataFrame blocks one after another into one CSV or Parquet file."""
    if file_format == "csv":
        for i, block in enumerate(blocks):
            block.to_csv(to, mode="w" if i == 0 else "a", header=i == 0, index=index)
        return to
    try:
        import pyarrow as pa  # noqa: PLC0415  (optional: only Parquet needs it)
        import pyarrow.parquet as pq  # noqa: PLC0415
    except ImportError as exc:
        msg = f"Parquet needs pyarrow: pip install -e '.[parquet]' ({exc})"
        raise StudyError(msg) from None
    writer = None
    try:
        for block in blocks:
            table = pa.Table.from_pandas(block, preserve_index=index)
            writer = writer or pq.ParquetWriter(to, table.schema)
            writer.write_table(table)
    finally:
        if writer is not None:
            writer.close()
    return to
