"""The figure the ``rocker`` and ``valve`` scenes share: ``valve_lift.png`` (stored valve-lift
curves, theoretical dashed and actual solid, a line per level of the first factor).
"""

from __future__ import annotations

import numpy as np
import xarray as xr
from matplotlib.figure import Figure

from studies.common.figure_layout import (
    Layout,
    design_factors,
    line_levels,
    runs_where,
)

VALVE_MARGIN_DEG = 10.0


def valve_lift_figure(ds: xr.Dataset) -> Figure | None:
    """Stored valve-lift curves (theoretical Y dashed, actual y solid), a line per first factor."""
    names = [
        c for c in ("valve_lift", "actual_lift") if c in ds.data_vars and "cam_angle" in ds[c].dims
    ]
    if not names:
        return None
    factors = design_factors(ds)
    line = "cam_speed" if "cam_speed" in factors else (factors[0] if factors else None)
    layout = Layout(ds, [line] if line else [])
    fig, axes = layout.figure((4.6, 3.2))
    angle = ds["cam_angle"].values
    shown = np.zeros(angle.size, dtype=bool)
    for name in names:
        shown |= (np.nan_to_num(ds[name].values) > 0.0).any(axis=0)
    if shown.any():
        span = angle[shown]
        axes[0, 0].set_xlim(span.min() - VALVE_MARGIN_DEG, span.max() + VALVE_MARGIN_DEG)
    for i, j, where in layout.panels():
        ax = axes[i, j]
        for k, (label, cond) in enumerate(line_levels(ds, line)):
            for n, run in enumerate(runs_where(ds, where | cond)):
                for name in names:
                    ax.plot(
                        angle,
                        ds[name].values[run],
                        color=f"C{k}",
                        lw=1.0,
                        ls="--" if name == "valve_lift" else "-",
                        label=label if n == 0 and name == names[-1] and label else None,
                    )
        ax.set_title(layout.title(where), fontsize="small")
        ax.grid(alpha=0.3)
    for ax in axes[-1]:
        ax.set_xlabel("cam angle [deg]")
    for ax in axes[:, 0]:
        ax.set_ylabel("valve lift [mm]")
    if line:
        axes[0, 0].legend(title=line, fontsize="x-small", title_fontsize="x-small")
    kinds = "\n(dashed: theoretical Y, solid: actual y)" if len(names) == 2 else ""
    fig.suptitle(f"Valve lift{kinds}{layout.held_note()}")
    return fig
