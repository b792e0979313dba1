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
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.ticker import MaxNLocator

from studies.analysis import taguchi
from studies.analysis.statistics import sweep_runs
from studies.common.figure_style import (
    LOG_DECADES,
    axis_label,
    map_scale,
    pretty_units,
    text_colour,
)

PANEL_SIZE = (3.0, 3.0)  # inches per factor panel
DPI = 120
TITLE_CHARS_PER_INCH = 11  # what fits at the default title size
MAP_TEXT_CELLS = 150  # maps with at most this many cells show their values
MAP_TICKS = 12  # level labels per map axis at most (every k-th level beyond)
MAP_MAX_SIZE = (10.0, 7.0)  # inches: a map of many levels stays a readable page
MARKER_LEVELS = 40  # from this many levels on, main effects are a line without markers
MAX_TICKS = 6  # level values as ticks up to this many levels; beyond, plain ticks
MAX_PANELS_PER_ROW = 3  # main-effect panels per row (more factors wrap to further rows)


def _title(fig: Figure, text: str) -> None:
    """A figure title wrapped to the figure's width (narrow sweeps have one panel)."""
    width = int(fig.get_figwidth() * TITLE_CHARS_PER_INCH)
    fig.suptitle(textwrap.fill(text, width), fontsize="medium")


def _label(name: str, units: str) -> str:
    return axis_label(name, units)


def main_effects_figure(an: xr.Dataset, response: str) -> Figure:
    """One panel per factor: level mean of ``response`` against the factor's value, from the
    analysis Dataset (:func:`studies.analysis.analyze.analyze`).

    The dashed line is the grand mean of the response. Factors without numeric values are
    plotted against their 1-based level number, named, as markers without lines; 40+ levels
    are drawn as a line without markers; pass/fail checks on a 0…1 share-passing axis.
    A level mean resting on runs without a value (:mod:`studies.analysis.missing`) is drawn hollow in
    red and labelled with how many of its runs were left out or counted at a bound; an
    operating factor's axis says so (its levels are conditions, not choices).
    """
    r = an.sel(response=response)
    names = [str(t) for t in an["term"].values if int(an["is_factor"].sel(term=t))]
    units = str(r.units.values)
    columns = min(len(names), MAX_PANELS_PER_ROW)
    rows = -(-len(names) // columns)
    fig = Figure(figsize=(PANEL_SIZE[0] * columns, PANEL_SIZE[1] * rows), layout="constrained")
    grid = fig.subplots(rows, columns, sharey=True, squeeze=False)
    for spare in grid.ravel()[len(names) :]:
        spare.set_axis_off()
    axes = grid.ravel()[: len(names)]
    for ax, f in zip(axes, names, strict=True):
        row = r.sel(term=f)
        k = row.k.values
        values = row.level_value.values
        present = np.isfinite(k)
        numeric = bool(np.isfinite(values[present]).all())
        x = values[present] if numeric else row.level.values[present] + 1
        marker = "o" if present.sum() < MARKER_LEVELS else None
        ax.plot(x, k[present], marker=marker, linestyle="-" if numeric else "none")
        ax.axhline(float(r.grand_mean), linestyle="--", color="0.5", label="grand mean")
        _mark_incomplete(ax, an, row, x, present)
        unit = str(row.term_units.values)
        role = str(an["term_role"].sel(term=f).values)
        fixed = f" ({role})" if role in ("operating", "model") else ""
        ax.set_xlabel((_label(f, unit) if numeric else f) + fixed)
        if not numeric:  # categorical: the level names at their (1-based) positions
            labels = [str(v) for v in row.level_label.values[present]]
            ax.set_xticks(x, labels, rotation=30, ha="right")
        else:
            _level_ticks(ax, x)
    for first in grid[:, 0]:
        first.set_ylabel(_label(response, units))
    axes[0].legend(loc="best", fontsize="small")
    k = r.k.values[np.isfinite(r.k.values)]
    if int(r.pass_fail):  # a pass/fail check: its level means are shares passing
        axes[0].set_ylim(-0.03, 1.03)
        for first in grid[:, 0]:
            first.set_ylabel(f"{response}: share passing")
    elif k.size and k.min() > 0 and k.max() > LOG_DECADES * k.min():
        axes[0].set_yscale("log")  # shared: level means over more than two decades
    _title(fig, f"Main effects on {response}: {r.long_name.values}")
    return fig


def _mark_incomplete(
    ax: Axes, an: xr.Dataset, row: xr.Dataset, x: np.ndarray, present: np.ndarray
) -> None:
    """Hollow red markers and counts at the levels whose mean rests on runs without a value."""
    runs = an["level_runs"].sel(term=row.term).values[present]
    left, bounded = row.left_out.values[present], row.bounded.values[present]
    meaning = str(row.none_means.values)
    for xi, ki, n, a, b in zip(x, row.k.values[present], runs, left, bounded, strict=True):
        if not (a or b):
            continue
        ax.plot([xi], [ki], marker="o", mfc="white", mec="C3", ms=7, linestyle="none", zorder=3)
        text = [f"{a}/{n} left out"] if a else []
        text += [f"{b}/{n} at {'bound' if meaning == 'unknown' else meaning}"] if b else []
        # At the first and last level the label grows inwards: centred, it would leave the axes.
        ha = "left" if xi == np.min(x) else "right" if xi == np.max(x) else "center"
        ax.annotate("\n".join(text), (xi, ki), xytext=(0, 6), textcoords="offset points",
                    ha=ha, fontsize="xx-small", color="C3")  # fmt: skip


def _level_ticks(ax: Axes, x: np.ndarray) -> None:
    """Ticks at the level values when they are few (labels %g, so 0 and 0.001 read as such),
    else at most ``MAX_TICKS`` plain ticks: labels never run into each other."""
    if x.size <= MAX_TICKS:
        ax.set_xticks(x, [f"{v:g}" for v in x], rotation=30 if x.size > 4 else 0)
    else:
        ax.xaxis.set_major_locator(MaxNLocator(MAX_TICKS))


def save_main_effects(an: xr.Dataset, responses: str | Sequence[str], folder: Path) -> list[Path]:
    """Write ``main_effects_<response>.png`` for each response into ``folder``."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    names = [responses] if isinstance(responses, str) else list(responses)
    paths = []
    for name in names:
        path = folder / f"main_effects_{name}.png"
        main_effects_figure(an, name).savefig(path, dpi=DPI)
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


def sn_figure(an: xr.Dataset, response: str) -> Figure:
    """Main effects on the S/N ratio [dB] of ``response`` (see :mod:`studies.analysis.taguchi`), from
    the analysis Dataset, which holds it as ``<response>_sn``."""
    name = taguchi.sn_name(response)
    fig = main_effects_figure(an, name)
    fig.axes[0].set_ylabel("S/N ratio [dB]")
    _title(fig, f"S/N ratio of {response}: {an['long_name'].sel(response=name).values}")
    return fig


def interaction_figure(an: xr.Dataset, response: str, a: str, b: str) -> Figure:
    """Mean ``response`` against the levels of ``a``, one line per level of ``b``.

    Parallel lines mean no interaction. Factors without numeric values are plotted against
    their 1-based level number.
    """
    r = an.sel(response=response, interaction=f"{a} x {b}")
    means = r.interaction_mean.values
    rows = np.isfinite(means).any(axis=1)
    cols = np.isfinite(means).any(axis=0)
    x = an["level_value"].sel(term=a).values[rows]
    numeric = bool(np.isfinite(x).all())
    if not numeric:
        x = np.flatnonzero(rows) + 1
    units_a = str(an["term_units"].sel(term=a).values)
    units_b = str(an["term_units"].sel(term=b).values)
    values_b = an["level_value"].sel(term=b).values
    fig = Figure(figsize=(1.5 * PANEL_SIZE[0], 1.3 * PANEL_SIZE[1]), layout="constrained")
    ax = fig.subplots()
    for j in np.flatnonzero(cols):
        labels_b = an["level_label"].sel(term=b).values
        shown = f"{values_b[j]:g}" if np.isfinite(values_b[j]) else str(labels_b[j])
        label = f"{b} = {shown} {pretty_units(units_b) if units_b != '1' else ''}".rstrip()
        ax.plot(x, means[rows, j], marker="o", label=label)
    ax.set_xlabel(_label(a, units_a) if numeric else a)
    if not numeric:  # categorical: the level names at their (1-based) positions
        ax.set_xticks(x, [str(v) for v in an["level_label"].sel(term=a).values[rows]])
    ax.set_ylabel(_label(str(r.long_name.values), str(r.units.values)))
    ax.legend(loc="best", fontsize="small")
    _title(fig, f"Interaction {a} × {b} on {response}")
    return fig


def save_sn_plots(an: xr.Dataset, responses: Sequence[str], folder: Path) -> list[Path]:
    """Write ``sn_<response>.png`` for each response into ``folder``."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    paths = []
    for name in responses:
        path = folder / sn_png(name)
        sn_figure(an, name).savefig(path, dpi=DPI)
        paths.append(path)
    return paths


def save_interaction_plots(an: xr.Dataset, responses: Sequence[str], folder: Path) -> list[Path]:
    """Write ``interaction_<response>_<a>_x_<b>.png`` per response and assigned interaction."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    pairs = list(zip(an["interaction_a"].values, an["interaction_b"].values, strict=True))
    paths = []
    for name in responses:
        for a, b in pairs:
            path = folder / interaction_png(name, a, b)
            interaction_figure(an, name, str(a), str(b)).savefig(path, dpi=DPI)
            paths.append(path)
    return paths


def map_png(response: str) -> str:
    return f"map_{response}.png"


def map_figure(an: xr.Dataset, response: str) -> Figure | None:
    """Heat map of ``response`` over the factor pair with the largest total-effect indices of
    a full factorial (mean over the other factors, if any); None when the analysis has no map.

    One equal cell per level pair, ticks named by the levels, the value written in each cell
    (up to ``MAP_TEXT_CELLS``); the colour scale is log, diverging or 0…1 as the values call
    for (:func:`studies.common.figure_style.map_scale`)."""
    if "map_mean" not in an:
        return None
    r = an.sel(response=response)
    fx, fy = str(r.map_x.values), str(r.map_y.values)
    if not fx:
        return None
    labels_x = _level_labels(an, fx)
    labels_y = _level_labels(an, fy)
    nx, ny = len(labels_x), len(labels_y)
    if nx < 2 or ny < 2:
        return None
    grid = r.map_mean.values[:ny, :nx]
    if ny > nx:  # the factor with more levels along the wider side: a map, not a strip
        fx, fy, labels_x, labels_y, nx, ny, grid = fy, fx, labels_y, labels_x, ny, nx, grid.T
    share = bool(int(r.pass_fail))
    norm, cmap = map_scale(grid, share)
    width = min(MAP_MAX_SIZE[0], max(5.2, 0.5 * nx + 2.6))
    height = min(MAP_MAX_SIZE[1], max(4.0, 0.3 * ny + 2.2))
    fig = Figure(figsize=(width, height), layout="constrained")
    ax = fig.subplots()
    mesh = ax.pcolormesh(
        np.arange(nx), np.arange(ny), grid, shading="nearest", cmap=cmap, norm=norm
    )
    units = str(r.units.values)
    fig.colorbar(mesh, ax=ax, label="share passing" if share else axis_label(response, units))
    if nx * ny <= MAP_TEXT_CELLS:
        for (row, col), value in np.ndenumerate(grid):
            if np.isfinite(value):
                colour = text_colour(mesh.cmap(mesh.norm(value)))
                ax.text(
                    col, row, f"{value:.3g}", ha="center", va="center", fontsize=7, color=colour
                )
    every_x, every_y = -(-nx // MAP_TICKS), -(-ny // MAP_TICKS)  # at most MAP_TICKS labels
    ax.set_xticks(np.arange(nx)[::every_x], labels_x[::every_x], rotation=30 if nx > 6 else 0)
    ax.set_yticks(np.arange(ny)[::every_y], labels_y[::every_y])
    ax.set_xlabel(axis_label(fx, str(an["term_units"].sel(term=fx).values)))
    ax.set_ylabel(axis_label(fy, str(an["term_units"].sel(term=fy).values)))
    others = an.sizes.get("factor", 0) > 2
    what = "mean over the other factors" if others else "value per design point"
    ax.set_title(f"{response}: {what}", fontsize="medium")
    return fig


def _level_labels(an: xr.Dataset, term: str) -> list[str]:
    """The names of a term's levels (its values as text), for tick labels."""
    values = an["level_value"].sel(term=term).values
    labels = an["level_label"].sel(term=term).values
    return [
        f"{v:.4g}" if np.isfinite(v) else str(label)
        for v, label in zip(values, labels, strict=True)
        if str(label)
    ]


def save_maps(an: xr.Dataset, responses: Sequence[str], folder: Path) -> list[Path]:
    """Write ``map_<response>.png`` for each response of a full factorial that has a map."""
    paths = []
    for name in responses:
        fig = map_figure(an, name)
        if fig is not None:
            path = Path(folder) / map_png(name)
            fig.savefig(path, dpi=DPI)
            paths.append(path)
    return paths
