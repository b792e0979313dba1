"""The ``luffing`` scene's tables for ``analysis.txt``: each design check as value, limit and
pass count, and the failing checks of each design point."""

from __future__ import annotations

import numpy as np
import pandas as pd
import xarray as xr

from studies.common.summary_tables import factor_columns, sig4

# check → (value, limit) response names
LUFFING_CHECKS = {
    "motor": ("motor_power", "motor_rated_power"),
    "ratio": ("implied_ratio", "belt_ratio"),
    "coupling": ("coupling_torque", "coupling_limit"),
    "deflection": ("deflection", "deflection_limit"),
    "slope": ("slope", "slope_limit"),
    "key": ("key_stress", "key_limit"),
    "bearing": ("bearing_life", "bearing_limit"),
}


def luffing_summary(ds: xr.Dataset) -> list[str]:
    """Each check as value range, limit and pass count; the failing checks per design point."""
    checks = [c for c in LUFFING_CHECKS if f"{c}_ok" in ds]
    if not checks:
        return []
    n = ds.sizes["run"]
    rows = []
    for c in checks:
        value, limit = LUFFING_CHECKS[c]
        shown = {}
        for label, name in (("value", value), ("limit", limit)):
            if name in ds:
                v = ds[name].values.astype(float)
                span = (
                    sig4(np.nanmin(v))
                    if np.nanmin(v) == np.nanmax(v)
                    else (f"{sig4(np.nanmin(v))} … {sig4(np.nanmax(v))}")
                )
                units = ds[name].attrs.get("units", "")
                shown[label] = f"{span} {units}" if units not in ("", "1") else span
            else:
                shown[label] = "(not stored)"
        passes = int(ds[f"{c}_ok"].values.sum())
        rows.append(
            {
                "check": c,
                "value": shown["value"],
                "limit": shown["limit"],
                "passes": f"{passes} of {n}",
            }
        )
    checks_table = pd.DataFrame(rows).to_string(index=False)
    columns = factor_columns(ds)
    columns["failing checks"] = [
        ", ".join(c for c in checks if ds[f"{c}_ok"].values[run] == 0) or "none" for run in range(n)
    ]
    points_table = pd.DataFrame(columns).to_string(index=False)
    return [
        f"Design checks (value and limit over the design points)\n{checks_table}",
        f"Failing checks per design point\n{points_table}",
    ]
