"""The ``luffing`` scene's tables for ``analysis.txt``: each design check as value, limit and
pass count (with how many design points it was not evaluated at), and the failing checks of
each design point."""

from __future__ import annotations

import numpy as np
import pandas as pd
import xarray as xr

from studies.common.summary_tables import factor_columns, sig4
from studies.scenes.base import NOT_EVALUATED

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
        flag = ds[f"{c}_ok"].values
        passes = f"{int((flag == 1).sum())} of {n}"
        unknown = int((flag == NOT_EVALUATED).sum())
        rows.append(
            {
                "check": c,
                "value": shown["value"],
                "limit": shown["limit"],
                "passes": f"{passes} ({unknown} not evaluated)" if unknown else passes,
            }
        )
    checks_table = pd.DataFrame(rows).to_string(index=False)
    columns = factor_columns(ds)
    flags = {c: ds[f"{c}_ok"].values for c in checks}
    columns["failing checks"] = [_failing(flags, run) for run in range(n)]
    points_table = pd.DataFrame(columns).to_string(index=False)
    return [
        f"Design checks (value and limit over the design points)\n{checks_table}",
        f"Failing checks per design point\n{points_table}",
    ]


def _failing(flags: dict[str, np.ndarray], run: int) -> str:
    """The checks that fail at ``run``, then those not evaluated there (a check whose value
    needs a motor where none fits), or "none"."""
    failing = ", ".join(c for c, flag in flags.items() if flag[run] == 0) or "none"
    unknown = ", ".join(c for c, flag in flags.items() if flag[run] == NOT_EVALUATED)
    return f"{failing}; not evaluated: {unknown}" if unknown else failing
