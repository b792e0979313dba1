"""Figures of the ``cam`` scene: ``cam_curves.png`` (every stored curve over cam angle, a line
per design point in the order of the factor values; at most ``MAX_LINES`` of them, evenly spread
over that order, the title saying how many of how many).
"""

from __future__ import annotations

import json

import numpy as np
import xarray as xr
from matplotlib.figure import Figure

from studies.common.figure_layout import run_colours, shown_value, spread
from studies.common.figure_style import axis_label

MAX_LEGEND_RUNS = 12
MAX_LINES = 200
"""Design points drawn at most: more lines say nothing more and cost seconds each hundred."""


def cam_curves_figure(ds: xr.Dataset) -> Figure | None:
    """Every stored cam curve over cam angle, one panel per curve, one line per design point."""
    names = [str(v) for v in ds.data_vars if ds[v].dims == ("run", "cam_angle")]
    if not names:
        return None
    factors = json.loads(ds.attrs.get("factors", "[]"))
    fig = Figure(figsize=(6.0, 2.4 * len(names)), layout="constrained")
    axes = fig.subplots(len(names), 1, sharex=True, squeeze=False)[:, 0]
    # Colours and legend in the order of the factor values (the first factor varying slowest).
    order = np.lexsort([ds[f].values for f in reversed(factors)]) if factors else None
    runs = order if order is not None else np.arange(ds.sizes["run"])
    title = "Cam curves per design point"
    if runs.size > MAX_LINES:
        runs = runs[spread(runs.size, MAX_LINES)]
        title = (
            f"Cam curves of {runs.size} of {ds.sizes['run']} design points "
            "(evenly spread in the order of the factor values)"
        )
    colours = run_colours(runs.size)
    for ax, name in zip(axes, names, strict=True):
        for shade, run in enumerate(runs):
            label = ", ".join(f"{f} {shown_value(ds, f, ds[f].values[run])}" for f in factors)
            ax.plot(
                ds["cam_angle"], ds[name].isel(run=run), color=colours[shade], lw=1, label=label
            )
        ax.set_ylabel(axis_label(name, ds[name].attrs.get("units", "")))
    axes[-1].set_xlabel(
        axis_label("cam angle from the nose", ds["cam_angle"].attrs.get("units", ""))
    )
    if ds.sizes["run"] <= MAX_LEGEND_RUNS:
        axes[0].legend(fontsize="x-small", loc="upper right")
    fig.suptitle(title, fontsize="medium")
    return fig
