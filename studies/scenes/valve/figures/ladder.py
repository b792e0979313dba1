"""Figure of the ``valve_spring_ladder`` scene: ``spring_model_ladder.png``.

One panel per compared response: the change of the answer from the finest rung of the study
(the most coil masses) against the measured cost per case, a line per combination of the
other factors, each point labelled by its rung (``lumped`` or ``N``) where labels do not
collide; on the log axis the finest rung itself (change 0) has no point. The cost is a timing:
the median of repeats, with a horizontal bar over their interquartile range
(``cost_per_case_iqr``) — costs whose bars overlap are not different.
"""

from __future__ import annotations

import itertools
import math

import numpy as np
import xarray as xr
from matplotlib.figure import Figure
from matplotlib.ticker import NullFormatter

from studies.common.errors import NotDrawn
from studies.common.figure_layout import (
    apart_labels,
    design_factors,
    factor_levels,
    runs_where,
    value_text,
)
from studies.common.figure_style import axis_label

COMPARED = (
    "jump_speed",
    "seating_velocity",
    "min_retainer_force_ratio",
    "surge_amplitude",
    "bounce_height",
)
PANEL = (3.6, 3.0)
COLUMNS = 3
MAX_LINES = 128  # combinations of the other factors drawn (ohc125_spring_surge: 101 speeds)


def _rung_label(masses: float) -> str:
    return "lumped" if masses == 0 else f"N={masses:g}"


def ladder_figure(ds: xr.Dataset) -> Figure | None:
    """Change from the finest rung vs cost per case, per compared response."""
    names = [n for n in COMPARED if n in ds.data_vars]
    if "cost_per_case" not in ds or "spring_masses" not in design_factors(ds) or not names:
        return None
    others = [f for f in design_factors(ds) if f != "spring_masses"]
    levels = [factor_levels(ds, f) for f in others]
    lines = math.prod(len(lv) for lv in levels)
    if lines > MAX_LINES:
        raise NotDrawn(
            f"{', '.join(others)} make {lines} combinations (more than {MAX_LINES}): too many "
            "to draw a line each"
        )
    combos = list(itertools.product(*levels))
    columns = min(len(names), COLUMNS)
    rows = -(-len(names) // columns)
    fig = Figure(figsize=(PANEL[0] * columns, PANEL[1] * rows + 0.8), layout="constrained")
    grid = fig.subplots(rows, columns, squeeze=False).ravel()
    for spare in grid[len(names) :]:
        spare.set_axis_off()
    axes = grid[: len(names)]
    masses = ds["spring_masses"].values
    for ax, name in zip(axes, names, strict=True):
        values = ds[name].values.astype(float)
        points: list[tuple[float, float, str]] = []
        for k, combo in enumerate(combos):
            where = dict(zip(others, combo, strict=True))
            runs = runs_where(ds, where)
            runs = runs[np.argsort(masses[runs])]
            finest = values[runs[-1]]
            change = np.abs(values[runs] - finest)
            cost = ds["cost_per_case"].values[runs]
            shown = np.where(change > 0, change, np.nan)
            label = ", ".join(value_text(ds, f, lv) for f, lv in where.items()) or None
            ax.errorbar(cost, shown, xerr=_half_spread(ds, runs), marker="o", color=f"C{k % 10}",
                        label=label, elinewidth=0.8, capsize=2)  # fmt: skip
            points += [
                (x, y, _rung_label(m)) for x, y, m in zip(cost, shown, masses[runs], strict=True)
            ]
        for x, y, text in apart_labels(points):
            ax.annotate(
                text, (x, y), fontsize="xx-small", xytext=(3, 3), textcoords="offset points"
            )
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.xaxis.set_minor_formatter(NullFormatter())  # a narrow decade: no crowded minor labels
        ax.grid(alpha=0.3, which="both")
        units = ds[name].attrs.get("units", "")
        ax.set_title(name, fontsize="small")
        ax.set_ylabel(axis_label("|change| from the finest rung", units))
        ax.set_xlabel(axis_label("cost per case (median)", ds["cost_per_case"].attrs["units"]))
    if len(combos) > 1:
        handles, labels = axes[0].get_legend_handles_labels()
        spare = len(grid) > len(names)
        (grid[-1] if spare else axes[0]).legend(
            handles,
            labels,
            title=", ".join(others),
            loc="center" if spare else "best",
            fontsize="small" if spare else "xx-small",
        )
    spread = "bars: interquartile range of the timings; " if "cost_per_case_iqr" in ds else ""
    fig.suptitle(
        "Spring-model ladder: change of each answer from the finest rung "
        f"(N={masses.max():g}) vs cost per case\n({spread}lumped = m_s/3 on the valve)",
        fontsize="medium",
    )
    return fig


def _half_spread(ds: xr.Dataset, runs: np.ndarray) -> np.ndarray | None:
    """Half the interquartile range of the timings (an error bar of that total length)."""
    if "cost_per_case_iqr" not in ds:
        return None
    return 0.5 * ds["cost_per_case_iqr"].values[runs]
