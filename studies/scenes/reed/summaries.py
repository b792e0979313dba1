"""The ``reed`` scene's table for ``analysis.txt``: every design point's first natural
frequency and its margin to the excitation band."""

from __future__ import annotations

import numpy as np
import pandas as pd
import xarray as xr

from studies.common.summary_tables import column_header, factor_columns, sig4


def reed_summary(ds: xr.Dataset) -> list[str]:
    """First natural frequency and band margin of every design point (4 significant figures)."""
    if "first_frequency" not in ds:
        return []
    columns = factor_columns(ds)
    columns[column_header(ds, "first_frequency")] = [sig4(v) for v in ds["first_frequency"].values]
    if {"band_min", "band_max"} <= set(ds.data_vars):
        columns["band [Hz]"] = [
            f"{sig4(a)}–{sig4(b)}"
            for a, b in zip(ds["band_min"].values, ds["band_max"].values, strict=True)
        ]
    if "first_margin" in ds:
        margin = ds["first_margin"].values
        columns[column_header(ds, "first_margin")] = [sig4(v) for v in margin]
        columns["first mode"] = np.where(margin > 0, "outside the band", "INSIDE the band")
    table = pd.DataFrame(columns).to_string(index=False)
    title = (
        "First natural frequency and its margin to the excitation band (4 significant "
        "figures; margin > 0 outside the band)"
    )
    return [f"{title}\n{table}"]
