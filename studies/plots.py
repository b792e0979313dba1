"""Main-effect plots (mean response at each level of each factor), sweep plots, interaction
plots and S/N main-effect plots.

Figures are built with :class:`matplotlib.figure.Figure` directly (no pyplot, no global backend
switch), so the module is safe to import in any program; PNGs are rendered by Agg on save.
"""

from __future__ import annotations

import json
import textwrap
from collections.abc import Sequence
from pathlib import Path

import numpy as np
import xarray as xr
from matplotlib.figure import Figure

from studies import taguchi
from studies.analysis import range_analysis, sweep_runs

PANEL_SIZE = (3.0, 3.0)  # inches per factor panel
DPI = 120
TITLE_CHARS_PER_INCH = 11  # what fits at the default title size


def _title(fig: Figure, text: str) -> None:
    """A figure title wrapped to the figure's width (narrow sweeps have one panel)."""
    width = int(fig.get_figwidth() * TITLE_CHARS_PER_INCH)
    fig.suptitle(textwrap.fill(text, width), fontsize="medium")


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
    axes[0].set_ylabel(_label(response, ra.attrs["units"]))
    axes[0].legend(loc="best", fontsize="small")
    _title(fig, f"Main effects on {response}: {ra.attrs['long_name']}")
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
    axes[0].set_ylabel(_label(response, y.attrs.get("units", "")))
    _title(fig, f"Sweep of {response}: {y.attrs.get('long_name', '')}")
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


def sn_png(response: str) -> str:
    return f"sn_{response}.png"


def interaction_png(response: str, a: str, b: str) -> str:
    return f"interaction_{response}_{a}_x_{b}.png"


def sn_figure(ds: xr.Dataset, response: str, kind: str | None = None) -> Figure:
    """Main effects on the S/N ratio [dB] of ``response`` (see :mod:`studies.taguchi`).

    ``kind`` ("smaller", "larger", "nominal") defaults to the response's ``better`` attribute.
    A response with a ``replicate`` dimension gives one S/N value per run over its replicates.
    """
    view = taguchi.with_sn(ds, response, {response: kind} if kind else None)
    name = taguchi.sn_name(response)
    fig = main_effects_figure(view, name)
    fig.axes[0].set_ylabel("S/N ratio [dB]")
    _title(fig, f"S/N ratio of {response} ({view[name].attrs['sn_kind']} is better)")
    return fig


def interaction_figure(ds: xr.Dataset, response: str, a: str, b: str) -> Figure:
    """Mean ``response`` against the levels of ``a``, one line per level of ``b``.

    Parallel lines mean no interaction. Factors without numeric values are plotted against
    their 1-based level number.
    """
    means = taguchi.interaction_means(ds, response, a, b)
    x = means[a].values
    numeric = np.issubdtype(x.dtype, np.number)
    if not numeric:
        x = means[f"{a}_level"].values + 1
    units_a = ds[a].attrs.get("units", "") if a in ds.coords else ""
    units_b = ds[b].attrs.get("units", "") if b in ds.coords else ""
    fig = Figure(figsize=(1.5 * PANEL_SIZE[0], 1.3 * PANEL_SIZE[1]), layout="constrained")
    ax = fig.subplots()
    for j, value in enumerate(means[b].values):
        shown = f"{value:g}" if isinstance(value, int | float | np.number) else str(value)
        label = f"{b} = {shown} {units_b}".rstrip()
        ax.plot(x, means.values[:, j], marker="o", label=label)
    ax.set_xlabel(_label(a, units_a) if numeric else f"{a} (level)")
    if not numeric:
        ax.set_xticks(x)
    y = ds[response]
    ax.set_ylabel(_label(y.attrs.get("long_name", response), y.attrs.get("units", "")))
    ax.legend(loc="best", fontsize="small")
    _title(fig, f"Interaction {a} × {b} on {response}")
    return fig


def save_sn_plots(ds: xr.Dataset, responses: Sequence[str], folder: Path) -> list[Path]:
    """Write ``sn_<response>.png`` for each response into ``folder``."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    paths = []
    for name in responses:
        path = folder / sn_png(name)
        sn_figure(ds, name).savefig(path, dpi=DPI)
        paths.append(path)
    return paths


def save_interaction_plots(ds: xr.Dataset, responses: Sequence[str], folder: Path) -> list[Path]:
    """Write ``interaction_<response>_<a>_x_<b>.png`` per response and assigned interaction."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    paths = []
    for name in responses:
        for a, b in taguchi.interaction_pairs(ds):
            path = folder / interaction_png(name, a, b)
            interaction_figure(ds, name, a, b).savefig(path, dpi=DPI)
            paths.append(path)
    return paths
