"""Text tables a scene's summaries share (for ``analysis.txt``): values to four significant
figures, the factor columns of every design point, a column header with units, and a line
listing design points."""

from __future__ import annotations

import json
from typing import Any

import numpy as np
import xarray as xr

from studies.common.figure_style import axis_label


def sig4(value: float) -> str:
    """A value to four significant figures ("—" when not finite)."""
    return "—" if not np.isfinite(value) else f"{value:.4g}"


def factor_columns(ds: xr.Dataset) -> dict[str, Any]:
    """``{"<factor> [units]": values}`` for every factor of the results, in design order."""
    return {
        axis_label(f, ds[f].attrs.get("units", "")): ds[f].values
        for f in json.loads(ds.attrs.get("factors", "[]"))
    }


def column_header(ds: xr.Dataset, name: str) -> str:
    """``name [units]`` of a stored variable."""
    return axis_label(name, ds[name].attrs.get("units", ""))


def runs_line(label: str, runs: np.ndarray) -> str:
    """``  label: count (runs 0, 3, …)`` listing at most 20 design points."""
    shown = ", ".join(str(r) for r in runs[:20]) + (", …" if runs.size > 20 else "")
    return f"  {label}: {runs.size} (runs {shown})"
