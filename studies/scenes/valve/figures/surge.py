"""Figure of the spring responses over camshaft speed: ``surge_sweep.png`` (physics §4 [V4]).

Top: surge amplitude against camshaft speed, a line per spring-model rung (or per level of the
other factor); bottom: the smallest retainer force over the static spring force. Dotted lines
mark the speeds where a cam harmonic order j meets the spring's first surge frequency,
``j · n_cam/60 = f_1`` (f_1 of the finest rung, from ``surge_frequency``; labels only where they stay apart); solid lines the jump
speed of each line, where the study asked for it.
"""

from __future__ import annotations

import numpy as np
import xarray as xr
from matplotlib.figure import Figure

from studies.common.figure_layout import design_factors, line_levels, runs_where, short_label

SECONDS_PER_MINUTE = 60.0
PANELS = ("surge_amplitude", "min_retainer_force_ratio")
LABEL_GAP = 0.03  # order labels closer than this share of the speed range are left out


def _order_speeds(ds: xr.Dataset, low: float, high: float) -> list[tuple[int, float]]:
    """(order j, camshaft speed [rpm]) where j · n/60 = f_1, inside [low, high]."""
    if "surge_frequency" not in ds:
        return []
    frequency = ds["surge_frequency"].values
    if "spring_masses" in ds:
        rungs = ds["spring_masses"].values
        frequency = frequency[rungs == rungs.max()]
    f1 = float(np.nanmedian(frequency))
    first, last = int(np.ceil(SECONDS_PER_MINUTE * f1 / high)), int(SECONDS_PER_MINUTE * f1 / low)
    return [(j, SECONDS_PER_MINUTE * f1 / j) for j in range(max(first, 1), last + 1)]


def surge_sweep_figure(ds: xr.Dataset) -> Figure | None:
    """Surge amplitude and retainer force ratio over camshaft speed, order lines marked."""
    factors = design_factors(ds)
    names = [n for n in PANELS if n in ds.data_vars]
    if "cam_speed" not in factors or "surge_amplitude" not in names:
        return None
    others = [f for f in factors if f != "cam_speed"]
    if len(others) > 1:
        return None
    line_factor = others[0] if others else None
    speed = ds["cam_speed"].values
    low, high = float(speed.min()), float(speed.max())
    fig = Figure(figsize=(8.0, 2.6 * len(names) + 0.8), layout="constrained")
    axes = fig.subplots(len(names), 1, squeeze=False, sharex=True)[:, 0]
    orders = _order_speeds(ds, low, high)
    for ax, name in zip(axes, names, strict=True):
        for k, (label, cond) in enumerate(line_levels(ds, line_factor)):
            runs = runs_where(ds, cond)
            runs = runs[np.argsort(speed[runs])]
            ax.plot(speed[runs], ds[name].values[runs], color=f"C{k}", label=label or None)
            if "jump_speed" in ds:
                jump = ds["jump_speed"].values[runs]
                if np.isfinite(jump).any():
                    ax.axvline(float(np.nanmedian(jump)), color=f"C{k}", lw=1.2, alpha=0.7)
        for n, (j, at) in enumerate(orders):
            ax.axvline(at, color="grey", ls=":", lw=0.8)
            gap = orders[n - 1][1] - at if n else high - low
            if ax is axes[0] and gap > LABEL_GAP * (high - low):
                ax.annotate(
                    f"j={j}",
                    (at, 1.0),
                    xycoords=("data", "axes fraction"),
                    fontsize="xx-small",
                    ha="center",
                    va="bottom",
                )
        ax.set_ylabel(short_label(ds, name))
        ax.grid(alpha=0.3)
    axes[-1].set_xlabel(short_label(ds, "cam_speed"))
    if line_factor:
        axes[0].legend(title=line_factor, fontsize="x-small", title_fontsize="x-small")
    fig.suptitle(
        "Spring surge over camshaft speed (dotted: order j meets f_1, j·n/60 = f_1; "
        "solid: jump speed)",
        fontsize="medium",
    )
    return fig
