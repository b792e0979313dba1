"""Figures of the ``valve`` and ``valve_accuracy`` scenes: ``jump_speed_map.png`` (jump speed
over the first two factors; a scatter of every design point where a factor has too many levels
for cells, as under a sampled design) and ``error_vs_cost.png`` (error against the reference vs cost
per case, a line per integrator, points labelled by step where the labels stay apart).
"""

from __future__ import annotations

import numpy as np
import xarray as xr
from matplotlib.figure import Figure
from matplotlib.ticker import NullFormatter

from studies.common.figure_layout import (
    Layout,
    apart_labels,
    design_factors,
    grid_of,
    level_ticks,
    line_levels,
    many_levels,
    runs_where,
    scatter_figure,
    short_label,
    spread_runs,
)
from studies.common.figure_style import text_colour


def jump_speed_map_figure(ds: xr.Dataset) -> Figure | None:
    """Jump speed over the first two factors, values written in the cells."""
    factors = design_factors(ds)
    if "jump_speed" not in ds or len(factors) < 2:
        return None
    x, y = factors[0], factors[1]
    if many_levels(ds, factors):
        return _jump_speed_scatter(ds, x, y)
    layout = Layout(ds, [x, y])
    fig, axes = layout.figure((4.6, 3.6))
    (xs, x_labels), (ys, y_labels) = level_ticks(ds, x), level_ticks(ds, y)
    values = ds["jump_speed"].values
    finite = values[np.isfinite(values)]
    low, high = (finite.min(), finite.max()) if finite.size else (0.0, 1.0)
    mesh = None
    for i, j, where in layout.panels():
        ax = axes[i, j]
        grid = grid_of(ds, "jump_speed", x, y, where)
        mesh = ax.pcolormesh(
            xs,
            ys,
            grid,
            shading="nearest",
            cmap="viridis",
            vmin=low,
            vmax=high,
        )
        ax.set_xticks(xs, x_labels, fontsize="x-small")
        ax.set_yticks(ys, y_labels, fontsize="x-small")
        for (r, c), value in np.ndenumerate(grid):
            finite_cell = np.isfinite(value)
            ax.text(
                xs[c],
                ys[r],
                f"{value:.0f}" if finite_cell else "none",
                ha="center",
                va="center",
                fontsize=6,
                color=text_colour(mesh.cmap(mesh.norm(value))) if finite_cell else "black",
            )
        ax.set_title(layout.title(where), fontsize="small")
    for ax in axes[-1]:
        ax.set_xlabel(short_label(ds, x))
    for ax in axes[:, 0]:
        ax.set_ylabel(short_label(ds, y))
    if mesh is not None:
        fig.colorbar(mesh, ax=axes, label=short_label(ds, "jump_speed"), shrink=0.8)
    fig.suptitle(
        "Jump speed: lowest camshaft speed with separation\n"
        "(none: none in the searched range, or not run)"
        f"{layout.held_note()}",
        fontsize="medium",
    )
    return fig


def _jump_speed_scatter(ds: xr.Dataset, x: str, y: str) -> Figure:
    """Every design point over the first two factors, coloured by its jump speed (grey crosses:
    none)."""
    runs = spread_runs(ds)
    jump = ds["jump_speed"].isel(run=runs).values
    fig, ax = scatter_figure(ds, x, y, jump, short_label(ds, "jump_speed"))
    none = ~np.isfinite(jump)
    ax.scatter(ds[x].isel(run=runs).values[none], ds[y].isel(run=runs).values[none], s=14,
               marker="x", color="0.5", lw=0.8)  # fmt: skip
    fig.suptitle(
        "Jump speed at each design point\n(grey crosses: none in the searched range, or not "
        "run; the other factors vary)",
        fontsize="medium",
    )
    return fig


def error_vs_cost_figure(ds: xr.Dataset) -> Figure | None:
    """Error against the reference vs measured cost per case, a line per integrator."""
    factors = design_factors(ds)
    if not {"reference_error", "cost_per_case"} <= set(ds.data_vars):
        return None
    if not {"integrator", "angle_step"} <= set(factors):
        return None
    layout = Layout(ds, ["integrator", "angle_step"], {("tolerance", 0.0): "fixed step"})
    fig, axes = layout.figure((3.8, 3.0))
    spread = ds["cost_per_case_iqr"].values if "cost_per_case_iqr" in ds else None
    for i, j, where in layout.panels():
        ax = axes[i, j]
        points = []
        for k, (label, cond) in enumerate(line_levels(ds, "integrator")):
            runs = runs_where(ds, where | cond)
            runs = runs[np.argsort(-ds["angle_step"].values[runs])]
            cost, error = ds["cost_per_case"].values[runs], ds["reference_error"].values[runs]
            half = None if spread is None else 0.5 * spread[runs]
            ax.errorbar(cost, error, xerr=half, marker="o", color=f"C{k}", label=label,
                        elinewidth=0.8, capsize=2)  # fmt: skip
            ax.set_xscale("log")
            ax.set_yscale("log")
            ax.xaxis.set_minor_formatter(NullFormatter())
            steps = ds["angle_step"].values[runs]
            points += list(zip(cost, error, steps, strict=True))
        for cx, ey, step in apart_labels(points):
            ax.annotate(
                f"{step:g}°",
                (cx, ey),
                fontsize="xx-small",
                xytext=(3, 3),
                textcoords="offset points",
            )
        ax.set_title(layout.title(where), fontsize="small")
        ax.grid(alpha=0.3, which="both")
    for ax in axes[-1]:
        ax.set_xlabel(f"{short_label(ds, 'cost_per_case')} (median)")
    for ax in axes[:, 0]:
        ax.set_ylabel(f"{short_label(ds, 'reference_error')}: max |y − y_ref|")
    axes[0, 0].legend(title="integrator", fontsize="x-small", title_fontsize="x-small")
    fig.suptitle(
        "Error against the scipy reference vs cost per case (labels: RK4 step, where apart"
        + ("; bars: interquartile range of the timings" if spread is not None else "")
        + f")\n{layout.held_note().strip()}",
        fontsize="medium",
    )
    return fig
