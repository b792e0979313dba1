"""Figures of the ``crank`` scene: ``torque_curve.png`` (engine or cylinder torque over crank
angle, a line per engine speed), ``torque_harmonics.png`` (harmonic orders of the engine
torque, FFT of the stored curve), ``approximation_error.png`` (two-term error vs λ).
"""

from __future__ import annotations

import numpy as np
import xarray as xr
from matplotlib.figure import Figure

from studies.common.figure_layout import (
    PANEL,
    Layout,
    design_factors,
    few_levels,
    line_levels,
    long_label,
    middle_level,
    runs_where,
    value_text,
)
from studies.common.figure_style import axis_label

CRANK_CYCLE_DEG = 720.0


def torque_curve_figure(ds: xr.Dataset) -> Figure | None:
    """Torque over crank angle, one line per engine speed, one panel per other factor level."""
    name = next((c for c in ("engine_torque", "cylinder_torque") if c in ds), None)
    if name is None:
        return None
    speed = "engine_speed" if "engine_speed" in design_factors(ds) else None
    layout = Layout(ds, [speed] if speed else [])
    fig, axes = layout.figure()
    angle = ds["crank_angle"].values
    for i, j, where in layout.panels():
        ax = axes[i, j]
        for k, (label, cond) in enumerate(line_levels(ds, speed)):
            for run in runs_where(ds, where | cond):
                values = ds[name].values[run]
                ax.plot(angle, values, color=f"C{k}", lw=1.0, label=label or None)
                ax.axhline(values.mean(), color=f"C{k}", lw=0.8, ls="--")
        ax.set_title(layout.title(where), fontsize="small")
        ax.set_xticks(np.arange(0.0, CRANK_CYCLE_DEG + 1, 180.0))
        ax.grid(alpha=0.3)
    for ax in axes[-1]:
        ax.set_xlabel(axis_label("crank angle", ds["crank_angle"].attrs.get("units", "")))
    for ax in axes[:, 0]:
        ax.set_ylabel(long_label(ds[name], name))
    if speed:
        axes[0, 0].legend(title="engine speed", fontsize="x-small", title_fontsize="x-small")
    fig.suptitle(
        f"{ds[name].attrs.get('long_name', name)} over the cycle\n(dashed: mean)"
        f"{layout.held_note()}",
        fontsize="medium",
    )
    return fig


def torque_harmonics_figure(ds: xr.Dataset, max_order: float = 12.0) -> Figure | None:
    """Amplitude of the engine-torque harmonic orders (FFT of the stored curve), per speed."""
    if "engine_torque" not in ds:
        return None
    speed = "engine_speed" if "engine_speed" in design_factors(ds) else None
    layout = Layout(ds, [speed] if speed else [])
    fig, axes = layout.figure()
    torque = ds["engine_torque"].values
    m = torque.shape[1]
    halves = np.arange(1, int(2 * max_order) + 1)
    amplitude = 2.0 * np.abs(np.fft.rfft(torque, axis=1))[:, halves] / m
    lines = line_levels(ds, speed)
    width = 0.45 / len(lines)
    for i, j, where in layout.panels():
        ax = axes[i, j]
        for k, (label, cond) in enumerate(lines):
            for run in runs_where(ds, where | cond):
                ax.bar(
                    halves / 2 + (k - (len(lines) - 1) / 2) * width,
                    amplitude[run],
                    width,
                    color=f"C{k}",
                    label=label or None,
                )
        ax.set_title(layout.title(where), fontsize="small")
        ax.set_xticks(np.arange(0.0, max_order + 0.5, 1.0))
        ax.grid(alpha=0.3, axis="y")
    for ax in axes[-1]:
        ax.set_xlabel("engine order (per crank revolution)")
    for ax in axes[:, 0]:
        ax.set_ylabel(axis_label("amplitude", ds["engine_torque"].attrs.get("units", "")))
    if speed:
        axes[0, 0].legend(title="engine speed", fontsize="x-small", title_fontsize="x-small")
    fig.suptitle(f"Harmonic orders of the engine torque{layout.held_note()}")
    return fig


def approximation_error_figure(ds: xr.Dataset) -> Figure | None:
    """Two-term approximation error vs λ, one panel per error response, one line per speed."""
    names = [v for v in ds.data_vars if str(v).startswith("approx_error_")]
    if "rod_ratio" not in design_factors(ds) or not names:
        return None
    speed = "engine_speed" if "engine_speed" in design_factors(ds) else None
    others = [f for f in design_factors(ds) if f not in ("rod_ratio", speed)]
    held = {f: middle_level(few_levels(ds, f)) for f in others}
    cols = min(3, len(names))
    rows = -(-len(names) // cols)
    fig = Figure(figsize=(PANEL[0] * cols, PANEL[1] * rows + 0.6), layout="constrained")
    axes = fig.subplots(rows, cols, squeeze=False).ravel()
    for ax, name in zip(axes, names, strict=False):
        lines = []
        for k, (label, cond) in enumerate(line_levels(ds, speed)):
            runs = runs_where(ds, held | cond)
            order = np.argsort(ds["rod_ratio"].values[runs])
            runs = runs[order]
            lines.append(ds[name].values[runs])
            ax.plot(
                ds["rod_ratio"].values[runs],
                lines[-1],
                marker="o",
                color=f"C{k}",
                label=label or None,
            )
        ax.set_yscale("log")
        ax.set_xlabel("λ = r/l")
        what = str(name).removeprefix("approx_error_").replace("_", " ")
        same = len(lines) > 1 and all(np.allclose(y, lines[0], rtol=1e-9) for y in lines)
        ax.set_title(f"{what} error{' (speed-independent)' if same else ''}", fontsize="small")
        relative = str(name).endswith("_relative")
        ax.set_ylabel(
            ds[name].attrs.get("long_name", "")
            if relative
            else axis_label("max |exact − two-term|", ds[name].attrs.get("units", "")),
            fontsize="x-small" if relative else "small",
        )
        ax.grid(alpha=0.3, which="both")
    for ax in axes[len(names) :]:
        ax.set_visible(False)
    if speed:
        axes[0].legend(title="engine speed", fontsize="x-small", title_fontsize="x-small")
    note = ", ".join(f"{f} = {value_text(ds, f, lv)}" for f, lv in held.items())
    fig.suptitle("Error of the two-term approximation vs λ" + (f" ({note})" if note else ""))
    return fig
