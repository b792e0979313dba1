"""Figures of the ``reed`` scene: ``frequency_map.png`` (f₁ over length × thickness, band
edges and in-band cells marked; a scatter of every design point where a factor has too many
levels for cells, as under a sampled design), ``mode_shapes.png`` (stored mode shapes); the
Campbell diagram is :mod:`studies.scenes.reed.campbell`.
"""

from __future__ import annotations

import numpy as np
import xarray as xr
from matplotlib.figure import Figure

from studies.common.figure_layout import (
    Layout,
    design_factors,
    grid_of,
    level_values,
    many_levels,
    scatter_figure,
    spread_runs,
)
from studies.common.figure_style import text_colour


def frequency_map_figure(ds: xr.Dataset) -> Figure | None:
    """First natural frequency over length × thickness, excitation band marked."""
    if not {"length", "thickness"} <= set(design_factors(ds)) or "first_frequency" not in ds:
        return None
    if many_levels(ds, design_factors(ds)):
        return _frequency_scatter(ds)
    layout = Layout(ds, ["length", "thickness"])
    fig, axes = layout.figure((3.8, 3.2))
    x, y = level_values(ds, "length"), level_values(ds, "thickness")
    band = [float(ds[b].values[0]) for b in ("band_min", "band_max") if b in ds]
    f1_all = ds["first_frequency"].values
    norm_range = (np.nanmin(f1_all), np.nanmax(f1_all))
    mesh = None
    edges_drawn = False
    for i, j, where in layout.panels():
        ax = axes[i, j]
        f1 = grid_of(ds, "first_frequency", "length", "thickness", where)
        mesh = ax.pcolormesh(
            x, y, f1, shading="nearest", cmap="viridis", vmin=norm_range[0], vmax=norm_range[1]
        )
        if "first_margin" in ds:
            inside = grid_of(ds, "first_margin", "length", "thickness", where) <= 0
            ax.pcolormesh(
                x,
                y,
                np.where(inside, 1.0, np.nan),
                shading="nearest",
                cmap="Reds",
                vmin=0.0,
                vmax=1.5,
                alpha=0.6,
            )
        for (r, c), value in np.ndenumerate(f1):
            if np.isfinite(value):
                colour = text_colour(mesh.cmap(mesh.norm(value)))
                ax.text(
                    x[c], y[r], f"{value:.4g}", ha="center", va="center", fontsize=6, color=colour
                )
        complete = min(f1.shape) > 1 and np.isfinite(f1).all()
        crossed = sorted({b for b in band if complete and f1.min() < b < f1.max()})
        if crossed:
            edges_drawn = True
            contours = ax.contour(x, y, f1, levels=crossed, colors="red", linewidths=1.2)
            for label in ax.clabel(contours, fmt="%g Hz", fontsize="xx-small"):
                label.set_bbox({"facecolor": "white", "edgecolor": "none", "pad": 1.0})
        ax.set_title(layout.title(where), fontsize="small")
    for ax in axes[-1]:
        ax.set_xlabel("length [mm]")
    for ax in axes[:, 0]:
        ax.set_ylabel("thickness [mm]")
    if mesh is not None:
        fig.colorbar(mesh, ax=axes, label="first natural frequency [Hz]", shrink=0.8)
    band_text = f" {band[0]:g}–{band[-1]:g} Hz" if len(band) == 2 else ""
    band_text += " (red lines: its edges)" if edges_drawn else ""
    fig.suptitle(
        f"First natural frequency [Hz]\nexcitation band{band_text}; red cells lie "
        f"inside it{layout.held_note()}",
        fontsize="medium",
    )
    return fig


def _frequency_scatter(ds: xr.Dataset) -> Figure:
    """Every design point over length × thickness, coloured by f₁, ringed red inside the band."""
    runs = spread_runs(ds)
    f1 = ds["first_frequency"].isel(run=runs).values
    fig, ax = scatter_figure(ds, "length", "thickness", f1, "first natural frequency [Hz]")
    if "first_margin" in ds:
        inside = ds["first_margin"].isel(run=runs).values <= 0
        length = ds["length"].isel(run=runs).values
        thickness = ds["thickness"].isel(run=runs).values
        ax.scatter(length[inside], thickness[inside], s=40, facecolors="none", edgecolors="red",
                   lw=0.8)  # fmt: skip
    fig.suptitle(
        "First natural frequency at each design point\n(red rings: inside the excitation band; "
        "the other factors vary)",
        fontsize="medium",
    )
    return fig


def mode_shapes_figure(ds: xr.Dataset) -> Figure | None:
    """Stored mode shapes along the reed (they do not depend on the reed's dimensions)."""
    names = sorted(str(v) for v in ds.data_vars if str(v).startswith("mode_shape_"))
    if not names:
        return None
    fig = Figure(figsize=(5.0, 3.5), layout="constrained")
    ax = fig.subplots()
    for name in names:
        ax.plot(ds["position"].values, ds[name].values[0], label=name.replace("_", " "))
    ax.axhline(0.0, color="0.5", lw=0.8)
    ax.set_xlabel("position along the reed x/l")
    ax.set_ylabel("deflection (unit tip deflection)")
    ax.legend(fontsize="small")
    fig.suptitle("Clamped–free mode shapes")
    return fig
