"""The probability of violating a limit over the two strongest control factors: for a study
with ``[noise]`` and ``[limits]``, per limited response, the mean of each design point's
probability of violation (:mod:`studies.analysis.uncertainty.noise_statistics`) at every level pair of the two control
factors with the largest range R of the response's mean over the noise (range analysis,
:func:`studies.analysis.statistics.range_analysis`), averaged over the other factors' runs at
that pair (pandas ``groupby``; O(runs)).

Variables on ``noise_response``: ``violation_map`` (``violation_level_x`` ×
``violation_level_y``, NaN for a pair without runs and for responses without a limit) with
the design points in each cell (``violation_map_runs``), the
factors ``violation_map_x`` (the strongest) and ``violation_map_y``, and
``violation_map_basis`` (which analysis chose them).
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import xarray as xr

from studies.analysis.uncertainty.noise_statistics import DIM

X, Y = "violation_level_x", "violation_level_y"


def strongest_controls(out: xr.Dataset, response: str) -> list[str]:
    """The control factors by decreasing range R of ``response`` (range analysis)."""
    roles = out["term_role"].values
    factors = out["is_factor"].values.astype(bool)
    terms = [
        str(t)
        for t, r, f in zip(out["term"].values, roles, factors, strict=True)
        if f and r == "control"
    ]
    spread = out["R"].sel(response=response, term=terms).values
    order = np.argsort(-np.nan_to_num(spread, nan=-np.inf), kind="stable")
    return [terms[i] for i in order]


def with_violation_maps(out: xr.Dataset, ds: xr.Dataset) -> xr.Dataset:
    """``out`` with the variables above (unchanged without noise, limits or two control
    factors)."""
    if DIM not in out.dims or "R" not in out:
        return out
    names = [str(n) for n in out[DIM].values]
    limited = np.isfinite(out["limit_min"].values) | np.isfinite(out["limit_max"].values)
    levels = out.sizes["level"]
    grid = np.full((len(names), levels, levels), np.nan)
    runs = np.zeros((len(names), levels, levels), dtype=np.int64)
    xs, ys, basis = [""] * len(names), [""] * len(names), [""] * len(names)
    for i, name in enumerate(names):
        mean = f"{name}_mean"
        if not limited[i] or mean not in out["response"].values:
            continue
        controls = strongest_controls(out, mean)
        if len(controls) < 2:
            continue
        xs[i], ys[i] = controls[0], controls[1]
        basis[i] = f"range analysis of {mean} (the mean over the noise)"
        frame = pd.DataFrame(
            {
                "x": ds[f"{xs[i]}_level"].values,
                "y": ds[f"{ys[i]}_level"].values,
                "p": out["violation_probability"].values[i],
            }
        )
        cells = frame.groupby(["x", "y"])["p"].agg(["mean", "size"])
        at = (i, cells.index.get_level_values("x"), cells.index.get_level_values("y"))
        grid[at], runs[at] = cells["mean"].to_numpy(), cells["size"].to_numpy()
    if not any(xs):
        return out
    return out.assign(
        violation_map=((DIM, X, Y), grid, {"units": "1", "long_name": "probability of violation"}),
        violation_map_runs=((DIM, X, Y), runs, {"units": "1"}),
        violation_map_x=(DIM, xs),
        violation_map_y=(DIM, ys),
        violation_map_basis=(DIM, basis),
    )
