"""Figures of the ``luffing`` scene: ``pass_fail_map.png`` (every design point: passes, or
which checks fail) and ``motor_power.png`` (required motor power against the rated sizes).
Where a factor has too many levels for panels, lines or cells (a sampled design), each is a
scatter of every design point instead.
"""

from __future__ import annotations

import numpy as np
import xarray as xr
from matplotlib import colormaps
from matplotlib.colors import BoundaryNorm, ListedColormap, to_rgba
from matplotlib.figure import Figure

from studies.common.figure_layout import (
    Layout,
    design_factors,
    factor_levels,
    line_levels,
    long_label,
    many_levels,
    raw_value,
    runs_where,
    scatter_figure,
    spread_runs,
)
from studies.common.figure_style import text_colour

LUFFING_CHECKS = ("motor", "ratio", "coupling", "deflection", "slope", "key", "bearing")


def pass_fail_map_figure(ds: xr.Dataset) -> Figure | None:
    """Every design point on the first two factors: the checks that fail (none = green)."""
    flags = [c for c in LUFFING_CHECKS if f"{c}_ok" in ds]
    factors = design_factors(ds)
    if not flags or len(factors) < 2:
        return None
    x, y = factors[0], factors[1]
    if many_levels(ds, factors):
        return _pass_fail_scatter(ds, x, y, flags)
    layout = Layout(ds, [x, y])
    fig, axes = layout.figure((3.8, 3.2))
    xs = [str(raw_value(ds, x, lv)) for lv in factor_levels(ds, x)]
    ys = [str(raw_value(ds, y, lv)) for lv in factor_levels(ds, y)]
    cmap, norm = _failure_colours(len(flags))
    mesh = None
    for i, j, where in layout.panels():
        ax = axes[i, j]
        failing = np.full((len(ys), len(xs)), np.nan)
        notes = np.full(failing.shape, "", dtype=object)
        for run in runs_where(ds, where):
            r, c = int(ds[f"{y}_level"].values[run]), int(ds[f"{x}_level"].values[run])
            failed = [f for f in flags if ds[f"{f}_ok"].values[run] == 0]
            failing[r, c] = len(failed)
            notes[r, c] = "\n".join(failed) or "all pass"
        mesh = ax.pcolormesh(
            np.arange(len(xs)),
            np.arange(len(ys)),
            failing,
            shading="nearest",
            cmap=cmap,
            norm=norm,
        )
        for (r, c), text in np.ndenumerate(notes):
            colour = text_colour(mesh.cmap(mesh.norm(failing[r, c])))
            ax.text(c, r, text, ha="center", va="center", fontsize=6, color=colour)
        ax.set_xticks(np.arange(len(xs)), xs)
        ax.set_yticks(np.arange(len(ys)), ys)
        ax.set_title(layout.title(where), fontsize="small")
    for ax in axes[-1]:
        ax.set_xlabel(long_label(ds[x], x))
    for ax in axes[:, 0]:
        ax.set_ylabel(long_label(ds[y], y))
    if mesh is not None:
        bar = fig.colorbar(mesh, ax=axes, label="number of failing checks", shrink=0.8)
        bar.set_ticks(list(range(len(flags) + 1)))
    fig.suptitle(
        f"Design checks that fail at each design point\n(checked: {', '.join(flags)})"
        f"{layout.held_note()}",
        fontsize="medium",
    )
    return fig


def _pass_fail_scatter(ds: xr.Dataset, x: str, y: str, flags: list[str]) -> Figure:
    """Every design point on the first two factors, coloured by its number of failing checks."""
    runs = spread_runs(ds)
    failing = sum(ds[f"{f}_ok"].isel(run=runs).values == 0 for f in flags)
    cmap, norm = _failure_colours(len(flags))
    count = "number of failing checks"
    ticks = range(len(flags) + 1)
    fig, _ = scatter_figure(ds, x, y, failing, count, ticks, cmap=cmap, norm=norm)
    fig.suptitle(
        f"Design checks that fail at each design point\n(checked: {', '.join(flags)}; "
        "the other factors vary)",
        fontsize="medium",
    )
    return fig


def _failure_colours(checks: int) -> tuple[ListedColormap, BoundaryNorm]:
    """Green for "every check passes" only; any failing check from orange (one) to dark red
    (all), one colour per count."""
    reds = colormaps["YlOrRd"](np.linspace(0.35, 1.0, max(checks, 1)))
    colours = np.vstack([to_rgba("tab:green"), reds])
    return ListedColormap(colours), BoundaryNorm(np.arange(-0.5, checks + 1.0), checks + 1)


def motor_power_figure(ds: xr.Dataset) -> Figure | None:
    """Required motor power against the first factor, a line per level of the second."""
    factors = design_factors(ds)
    if "motor_power" not in ds or not factors:
        return None
    x = factors[0]
    line = factors[1] if len(factors) > 1 else None
    if many_levels(ds, factors):
        return _motor_power_scatter(ds, x, line)
    layout = Layout(ds, [x, *([line] if line else [])])
    fig, axes = layout.figure()
    for i, j, where in layout.panels():
        ax = axes[i, j]
        for k, (label, cond) in enumerate(line_levels(ds, line)):
            runs = runs_where(ds, where | cond)
            runs = runs[np.argsort(ds[x].values[runs])]
            ax.plot(
                ds[x].values[runs],
                ds["motor_power"].values[runs],
                marker="o",
                color=f"C{k}",
                label=label or None,
            )
            if "motor_rated_power" in ds:
                ax.step(
                    ds[x].values[runs],
                    ds["motor_rated_power"].values[runs],
                    where="mid",
                    color=f"C{k}",
                    ls=":",
                    lw=0.8,
                )
        ax.set_title(layout.title(where), fontsize="small")
        ax.grid(alpha=0.3)
    for ax in axes[-1]:
        ax.set_xlabel(long_label(ds[x], x))
    for ax in axes[:, 0]:
        ax.set_ylabel(long_label(ds["motor_power"], "motor_power"), fontsize="small")
    if line:
        axes[0, 0].legend(title=line, fontsize="x-small", title_fontsize="x-small")
    fig.suptitle(f"Required motor power (dotted: the rated motor chosen){layout.held_note()}")
    return fig


def _motor_power_scatter(ds: xr.Dataset, x: str, line: str | None) -> Figure:
    """Required motor power of every design point against the first factor, coloured by the
    second (by the power itself when there is none)."""
    shade = line or "motor_power"
    runs = spread_runs(ds)
    fig, ax = scatter_figure(
        ds, x, "motor_power", ds[shade].isel(run=runs).values, long_label(ds[shade], shade)
    )
    rated = "motor_rated_power" in ds
    if rated:
        chosen = ds["motor_rated_power"].isel(run=runs).values
        ax.scatter(ds[x].isel(run=runs).values, chosen, marker="_", color="0.4", lw=0.8)
    note = "grey dashes: the rated motor chosen; " if rated else ""
    fig.suptitle(
        f"Required motor power at each design point\n({note}the other factors vary)",
        fontsize="medium",
    )
    return fig
