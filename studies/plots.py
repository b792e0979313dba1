"""Main-effect plots: mean response at each level of each factor.

Figures are built with :class:`matplotlib.figure.Figure` directly (no pyplot, no global backend
switch), so the module is safe to import in any program; PNGs are rendered by Agg on save.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from pathlib import Path

import numpy as np
import xarray as xr
from matplotlib.figure import Figure

from studies.analysis import range_analysis, sweep_runs

PANEL_SIZE = (3.0, 3.0)  # inches per factor panel
DPI = 120


def _label(name: str, units: str) -> str:
    return f"{name} [{units}]" if units else name


def main_effects_figure(
    ds: xr.Dataset, response: str, factors: Sequence[str] | None = None
) -> Figure:
    """One panel per factor: level mean of ``response`` against the factor's value.

    The dashed line is the grand mean of the response. Factors without numeric values are
    plotted against their 1-based level number.
    """
    ra = range_analysis(ds, response, factors)
    names = [str(f) for f in ra.factor.values]
    grand_mean = float(np.nanmean(ds[response].values.astype(float)))
    fig = Figure(figsize=(PANEL_SIZE[0] * len(names), PANEL_SIZE[1]), layout="constrained")
    axes = fig.subplots(1, len(names), sharey=True, squeeze=False)[0]
    for ax, f in zip(axes, names, strict=True):
        row = ra.sel(factor=f)
        k = row.k.values
        values = row.level_value.values
        present = np.isfinite(k)
        numeric = bool(np.isfinite(values[present]).all())
        x = values[present] if numeric else row.level.values[present] + 1
        ax.plot(x, k[present], marker="o")
        ax.axhline(grand_mean, linestyle="--", color="0.5", label="grand mean")
        unit = str(row.factor_units.values)
        ax.set_xlabel(_label(f, unit) if numeric else f"{f} (level)")
        if not numeric:
            ax.set_xticks(x)
    axes[0].set_ylabel(_label(ra.attrs["long_name"], ra.attrs["units"]))
    axes[0].legend(loc="best", fontsize="small")
    fig.suptitle(f"Main effects on {response}")
    return fig


def save_main_effects(ds: xr.Dataset, responses: str | Sequence[str], folder: Path) -> list[Path]:
    """Write ``main_effects_<response>.png`` for each response into ``folder``."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    names = [responses] if isinstance(responses, str) else list(responses)
    paths = []
    for name in names:
        path = folder / f"main_effects_{name}.png"
        main_effects_figure(ds, name).savefig(path, dpi=DPI)
        paths.append(path)
    return paths


def sweep_figure(ds: xr.Dataset, response: str) -> Figure:
    """One panel per swept factor: ``response`` against the factor's value."""
    factors = json.loads(ds.attrs["factors"])
    fig = Figure(figsize=(PANEL_SIZE[0] * len(factors), PANEL_SIZE[1]), layout="constrained")
    axes = fig.subplots(1, len(factors), sharey=True, squeeze=False)[0]
    for ax, f in zip(axes, factors, strict=True):
        part = sweep_runs(ds, f)
        ax.plot(part[f].values, part[response].values, marker="o")
        ax.set_xlabel(_label(f, ds[f].attrs.get("units", "")))
    y = ds[response]
    axes[0].set_ylabel(_label(y.attrs.get("long_name", response), y.attrs.get("units", "")))
    fig.suptitle(f"Sweep: {response}")
    return fig


def save_sweep_plots(ds: xr.Dataset, responses: Sequence[str], folder: Path) -> list[Path]:
    """Write ``sweep_<response>.png`` for each response into ``folder``."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    paths = []
    for name in responses:
        path = folder / f"sweep_{name}.png"
        sweep_figure(ds, name).savefig(path, dpi=DPI)
        paths.append(path)
    return paths
