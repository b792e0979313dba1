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


SHOWN = 20
"""Design points a line lists."""


class RunList:
    """How many design points were found and the first :data:`SHOWN` of them, added a block
    of runs at a time (:meth:`add`), so a status of 10⁸ runs is never held whole."""

    def __init__(self) -> None:
        self.count, self.first = 0, np.zeros(0, dtype=np.int64)

    def add(self, runs: np.ndarray) -> None:
        self.count += runs.size
        if self.first.size < SHOWN:
            self.first = np.concatenate([self.first, runs[: SHOWN - self.first.size]])

    def line(self, label: str) -> str:
        """``  label: count (runs 0, 3, …)``."""
        shown = ", ".join(str(r) for r in self.first) + (", …" if self.count > SHOWN else "")
        return f"  {label}: {self.count} (runs {shown})"
