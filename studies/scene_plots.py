"""Figures a user of a particular scene wants, beside the generic main-effect plots.

:func:`save_scene_figures` dispatches on the ``scene`` attribute of a results Dataset and writes
what the stored variables allow (nothing for scenes or studies without them):

* ``cam`` — ``cam_curves.png`` (every stored curve over cam angle, a line per design point);
* ``crank`` — ``torque_curve.png`` (engine or cylinder torque over crank angle, one line per
  engine speed), ``torque_harmonics.png`` (harmonic orders of the engine torque, FFT of the
  stored curve), ``approximation_error.png`` (two-term error vs λ, one line per speed);
* ``reed`` — ``frequency_map.png`` (f₁ over length × thickness, band edges and in-band cells
  marked), ``mode_shapes.png`` (stored mode shapes);
* ``luffing`` — ``pass_fail_map.png`` (every design point: passes, or which checks fail) and
  ``motor_power.png`` (required motor power against the rated sizes);
* ``rocker``, ``valve`` — ``valve_lift.png`` (stored valve-lift curves, theoretical and
  actual), ``jump_speed_map.png`` (jump speed over the first two factors);
* ``valve_accuracy`` — ``error_vs_cost.png`` (error against the reference vs cost per case,
  a line per integrator, points labelled by step).

A figure has one line per level of a "line" factor and one panel per combination of up to two
other factors; further factors are held at their middle level (named in the title).
"""

from __future__ import annotations

import json
from collections.abc import Callable, Sequence
from pathlib import Path

import numpy as np
import xarray as xr
from matplotlib import colormaps
from matplotlib.colors import BoundaryNorm, ListedColormap, to_rgba
from matplotlib.figure import Figure

from studies.campbell import campbell_figure
from studies.figure_style import axis_label, text_colour

DPI = 120
PANEL = (3.6, 2.8)  # inches per panel
CRANK_CYCLE_DEG = 720.0
VALVE_MARGIN_DEG = 10.0
LUFFING_CHECKS = ("motor", "ratio", "coupling", "deflection", "slope", "key", "bearing")


# --- selection helpers ----------------------------------------------------------------------
def _factors(ds: xr.Dataset) -> list[str]:
    return list(json.loads(ds.attrs.get("factors", "[]")))


def _levels(ds: xr.Dataset, factor: str) -> list[int]:
    return sorted({int(v) for v in ds[f"{factor}_level"].values})


def _raw_value(ds: xr.Dataset, factor: str, level: int):
    """The factor's value at a level (taken from the first run at that level)."""
    run = int(np.flatnonzero(ds[f"{factor}_level"].values == level)[0])
    return ds[factor].values[run]


def _value(ds: xr.Dataset, factor: str, level: int) -> str:
    return _shown(ds, factor, _raw_value(ds, factor, level))


def _shown(ds: xr.Dataset, factor: str, value: object) -> str:
    """A factor's value as a person reads it: a number with its units, or a level's name."""
    units = ds[factor].attrs.get("units", "")
    shown = f"{value:g}" if isinstance(value, (int, float, np.number)) else str(value)
    return f"{shown} {units}" if units not in ("", "1") else shown


def _runs(ds: xr.Dataset, where: dict[str, int]) -> np.ndarray:
    keep = np.ones(ds.sizes["run"], dtype=bool)
    for f, level in where.items():
        keep &= ds[f"{f}_level"].values == level
    return np.flatnonzero(keep)


class _Layout:
    """Panels (row × column factor levels) and held factors for a figure."""

    def __init__(self, ds: xr.Dataset, used: Sequence[str]) -> None:
        others = [f for f in _factors(ds) if f not in used]
        self.row = others[0] if len(others) > 1 else None
        self.col = others[1] if len(others) > 1 else others[0] if others else None
        self.held = {f: _levels(ds, f)[(len(_levels(ds, f)) - 1) // 2] for f in others[2:]}
        self.rows = _levels(ds, self.row) if self.row else [0]
        self.cols = _levels(ds, self.col) if self.col else [0]
        self.ds = ds

    def figure(self, size: tuple[float, float] = PANEL) -> tuple[Figure, np.ndarray]:
        fig = Figure(
            figsize=(size[0] * len(self.cols), size[1] * len(self.rows) + 0.6), layout="constrained"
        )
        axes = fig.subplots(len(self.rows), len(self.cols), squeeze=False, sharex=True, sharey=True)
        return fig, axes

    def panels(self):
        for i, r in enumerate(self.rows):
            for j, c in enumerate(self.cols):
                where = dict(self.held)
                if self.row:
                    where[self.row] = r
                if self.col:
                    where[self.col] = c
                yield i, j, where

    def title(self, where: dict[str, int]) -> str:
        shown = [
            f"{f} = {_value(self.ds, f, lv)}"
            for f, lv in where.items()
            if f in (self.row, self.col)
        ]
        return ", ".join(shown)

    def held_note(self) -> str:
        if not self.held:
            return ""
        return (
            " (held: "
            + ", ".join(f"{f} = {_value(self.ds, f, lv)}" for f, lv in self.held.items())
            + ")"
        )


def _lines(ds: xr.Dataset, factor: str | None) -> list[tuple[str, dict[str, int]]]:
    """(label, level condition) per line; one unlabelled line when there is no line factor."""
    if factor is None or factor not in _factors(ds):
        return [("", {})]
    return [(_value(ds, factor, lv), {factor: lv}) for lv in _levels(ds, factor)]


def _label(da: xr.DataArray, name: str) -> str:
    units = da.attrs.get("units", "")
    return axis_label(da.attrs.get("long_name", name), units) if units else name


# --- crank ----------------------------------------------------------------------------------
def torque_curve_figure(ds: xr.Dataset) -> Figure | None:
    """Torque over crank angle, one line per engine speed, one panel per other factor level."""
    name = next((c for c in ("engine_torque", "cylinder_torque") if c in ds), None)
    if name is None:
        return None
    speed = "engine_speed" if "engine_speed" in _factors(ds) else None
    layout = _Layout(ds, [speed] if speed else [])
    fig, axes = layout.figure()
    angle = ds["crank_angle"].values
    for i, j, where in layout.panels():
        ax = axes[i, j]
        for k, (label, cond) in enumerate(_lines(ds, speed)):
            for run in _runs(ds, where | cond):
                values = ds[name].values[run]
                ax.plot(angle, values, color=f"C{k}", lw=1.0, label=label or None)
                ax.axhline(values.mean(), color=f"C{k}", lw=0.8, ls="--")
        ax.set_title(layout.title(where), fontsize="small")
        ax.set_xticks(np.arange(0.0, CRANK_CYCLE_DEG + 1, 180.0))
        ax.grid(alpha=0.3)
    for ax in axes[-1]:
        ax.set_xlabel(axis_label("crank angle", ds["crank_angle"].attrs.get("units", "")))
    for ax in axes[:, 0]:
        ax.set_ylabel(_label(ds[name], name))
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
    speed = "engine_speed" if "engine_speed" in _factors(ds) else None
    layout = _Layout(ds, [speed] if speed else [])
    fig, axes = layout.figure()
    torque = ds["engine_torque"].values
    m = torque.shape[1]
    halves = np.arange(1, int(2 * max_order) + 1)
    amplitude = 2.0 * np.abs(np.fft.rfft(torque, axis=1))[:, halves] / m
    lines = _lines(ds, speed)
    width = 0.45 / len(lines)
    for i, j, where in layout.panels():
        ax = axes[i, j]
        for k, (label, cond) in enumerate(lines):
            for run in _runs(ds, where | cond):
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
    if "rod_ratio" not in _factors(ds) or not names:
        return None
    speed = "engine_speed" if "engine_speed" in _factors(ds) else None
    others = [f for f in _factors(ds) if f not in ("rod_ratio", speed)]
    held = {f: _levels(ds, f)[(len(_levels(ds, f)) - 1) // 2] for f in others}
    cols = min(3, len(names))
    rows = -(-len(names) // cols)
    fig = Figure(figsize=(PANEL[0] * cols, PANEL[1] * rows + 0.6), layout="constrained")
    axes = fig.subplots(rows, cols, squeeze=False).ravel()
    for ax, name in zip(axes, names, strict=False):
        lines = []
        for k, (label, cond) in enumerate(_lines(ds, speed)):
            runs = _runs(ds, held | cond)
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
    note = ", ".join(f"{f} = {_value(ds, f, lv)}" for f, lv in held.items())
    fig.suptitle("Error of the two-term approximation vs λ" + (f" ({note})" if note else ""))
    return fig


# --- reed -----------------------------------------------------------------------------------
def _grid(ds: xr.Dataset, name: str, x: str, y: str, where: dict[str, int]) -> np.ndarray:
    """Values of ``name`` on the (y level, x level) grid of the runs matching ``where``."""
    grid = np.full((len(_levels(ds, y)), len(_levels(ds, x))), np.nan)
    for run in _runs(ds, where):
        grid[int(ds[f"{y}_level"].values[run]), int(ds[f"{x}_level"].values[run])] = float(
            ds[name].values[run]
        )
    return grid


def _level_values(ds: xr.Dataset, factor: str) -> np.ndarray:
    return np.array([float(_raw_value(ds, factor, lv)) for lv in _levels(ds, factor)])


def _level_ticks(ds: xr.Dataset, factor: str) -> tuple[np.ndarray, list[str]]:
    """Cell positions 0, 1, … of a factor's levels and their values as tick labels (numbers or
    names such as a lift law), so a map has equal cells however the levels are spaced."""
    values = [_raw_value(ds, factor, lv) for lv in _levels(ds, factor)]
    labels = [f"{v:g}" if isinstance(v, (int, float, np.number)) else str(v) for v in values]
    return np.arange(len(values), dtype=float), labels


def frequency_map_figure(ds: xr.Dataset) -> Figure | None:
    """First natural frequency over length × thickness, excitation band marked."""
    if not {"length", "thickness"} <= set(_factors(ds)) or "first_frequency" not in ds:
        return None
    layout = _Layout(ds, ["length", "thickness"])
    fig, axes = layout.figure((3.8, 3.2))
    x, y = _level_values(ds, "length"), _level_values(ds, "thickness")
    band = [float(ds[b].values[0]) for b in ("band_min", "band_max") if b in ds]
    f1_all = ds["first_frequency"].values
    norm_range = (np.nanmin(f1_all), np.nanmax(f1_all))
    mesh = None
    edges_drawn = False
    for i, j, where in layout.panels():
        ax = axes[i, j]
        f1 = _grid(ds, "first_frequency", "length", "thickness", where)
        mesh = ax.pcolormesh(
            x, y, f1, shading="nearest", cmap="viridis", vmin=norm_range[0], vmax=norm_range[1]
        )
        if "first_margin" in ds:
            inside = _grid(ds, "first_margin", "length", "thickness", where) <= 0
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


# --- luffing --------------------------------------------------------------------------------
def pass_fail_map_figure(ds: xr.Dataset) -> Figure | None:
    """Every design point on the first two factors: the checks that fail (none = green)."""
    flags = [c for c in LUFFING_CHECKS if f"{c}_ok" in ds]
    factors = _factors(ds)
    if not flags or len(factors) < 2:
        return None
    x, y = factors[0], factors[1]
    layout = _Layout(ds, [x, y])
    fig, axes = layout.figure((3.8, 3.2))
    xs = [str(_raw_value(ds, x, lv)) for lv in _levels(ds, x)]
    ys = [str(_raw_value(ds, y, lv)) for lv in _levels(ds, y)]
    cmap, norm = _failure_colours(len(flags))
    mesh = None
    for i, j, where in layout.panels():
        ax = axes[i, j]
        failing = np.full((len(ys), len(xs)), np.nan)
        notes = np.full(failing.shape, "", dtype=object)
        for run in _runs(ds, where):
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
        ax.set_xlabel(_label(ds[x], x))
    for ax in axes[:, 0]:
        ax.set_ylabel(_label(ds[y], y))
    if mesh is not None:
        bar = fig.colorbar(mesh, ax=axes, label="number of failing checks", shrink=0.8)
        bar.set_ticks(list(range(len(flags) + 1)))
    fig.suptitle(
        f"Design checks that fail at each design point\n(checked: {', '.join(flags)})"
        f"{layout.held_note()}",
        fontsize="medium",
    )
    return fig


def motor_power_figure(ds: xr.Dataset) -> Figure | None:
    """Required motor power against the first factor, a line per level of the second."""
    factors = _factors(ds)
    if "motor_power" not in ds or not factors:
        return None
    x = factors[0]
    line = factors[1] if len(factors) > 1 else None
    layout = _Layout(ds, [x, *([line] if line else [])])
    fig, axes = layout.figure()
    for i, j, where in layout.panels():
        ax = axes[i, j]
        for k, (label, cond) in enumerate(_lines(ds, line)):
            runs = _runs(ds, where | cond)
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
        ax.set_xlabel(_label(ds[x], x))
    for ax in axes[:, 0]:
        ax.set_ylabel(_label(ds["motor_power"], "motor_power"), fontsize="small")
    if line:
        axes[0, 0].legend(title=line, fontsize="x-small", title_fontsize="x-small")
    fig.suptitle(f"Required motor power (dotted: the rated motor chosen){layout.held_note()}")
    return fig


# --- rocker and valve -----------------------------------------------------------------------
def _short(ds: xr.Dataset, name: str) -> str:
    return axis_label(name, ds[name].attrs.get("units", ""))


def valve_lift_figure(ds: xr.Dataset) -> Figure | None:
    """Stored valve-lift curves (theoretical Y dashed, actual y solid), a line per first factor."""
    names = [
        c for c in ("valve_lift", "actual_lift") if c in ds.data_vars and "cam_angle" in ds[c].dims
    ]
    if not names:
        return None
    factors = _factors(ds)
    line = "cam_speed" if "cam_speed" in factors else (factors[0] if factors else None)
    layout = _Layout(ds, [line] if line else [])
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
        for k, (label, cond) in enumerate(_lines(ds, line)):
            for n, run in enumerate(_runs(ds, where | cond)):
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


def jump_speed_map_figure(ds: xr.Dataset) -> Figure | None:
    """Jump speed over the first two factors, values written in the cells."""
    factors = _factors(ds)
    if "jump_speed" not in ds or len(factors) < 2:
        return None
    x, y = factors[0], factors[1]
    layout = _Layout(ds, [x, y])
    fig, axes = layout.figure((4.6, 3.6))
    (xs, x_labels), (ys, y_labels) = _level_ticks(ds, x), _level_ticks(ds, y)
    values = ds["jump_speed"].values
    finite = values[np.isfinite(values)]
    low, high = (finite.min(), finite.max()) if finite.size else (0.0, 1.0)
    mesh = None
    for i, j, where in layout.panels():
        ax = axes[i, j]
        grid = _grid(ds, "jump_speed", x, y, where)
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
        ax.set_xlabel(_short(ds, x))
    for ax in axes[:, 0]:
        ax.set_ylabel(_short(ds, y))
    if mesh is not None:
        fig.colorbar(mesh, ax=axes, label=_short(ds, "jump_speed"), shrink=0.8)
    fig.suptitle(
        "Jump speed: lowest camshaft speed with separation\n"
        "(none: none in the searched range, or not run)"
        f"{layout.held_note()}",
        fontsize="medium",
    )
    return fig


def error_vs_cost_figure(ds: xr.Dataset) -> Figure | None:
    """Error against the reference vs measured cost per case, a line per integrator."""
    factors = _factors(ds)
    if not {"reference_error", "cost_per_case"} <= set(ds.data_vars):
        return None
    if not {"integrator", "angle_step"} <= set(factors):
        return None
    layout = _Layout(ds, ["integrator", "angle_step"])
    fig, axes = layout.figure((3.8, 3.0))
    for i, j, where in layout.panels():
        ax = axes[i, j]
        points = []
        for k, (label, cond) in enumerate(_lines(ds, "integrator")):
            runs = _runs(ds, where | cond)
            runs = runs[np.argsort(-ds["angle_step"].values[runs])]
            cost, error = ds["cost_per_case"].values[runs], ds["reference_error"].values[runs]
            ax.loglog(cost, error, marker="o", color=f"C{k}", label=label)
            steps = ds["angle_step"].values[runs]
            points += list(zip(cost, error, steps, strict=True))
        for cx, ey, step in _apart(points):
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
        ax.set_xlabel(f"{_short(ds, 'cost_per_case')} (timing)")
    for ax in axes[:, 0]:
        ax.set_ylabel(f"{_short(ds, 'reference_error')}: max |y − y_ref|")
    axes[0, 0].legend(title="integrator", fontsize="x-small", title_fontsize="x-small")
    fig.suptitle(
        "Error against the scipy reference vs cost per case (labels: RK4 step, where apart)"
        f"{layout.held_note()}",
        fontsize="medium",
    )
    return fig


# --- cam ------------------------------------------------------------------------------------
MAX_LEGEND_RUNS = 12


def cam_curves_figure(ds: xr.Dataset) -> Figure | None:
    """Every stored cam curve over cam angle, one panel per curve, one line per design point."""
    names = [str(v) for v in ds.data_vars if ds[v].dims == ("run", "cam_angle")]
    if not names:
        return None
    factors = json.loads(ds.attrs.get("factors", "[]"))
    fig = Figure(figsize=(6.0, 2.4 * len(names)), layout="constrained")
    axes = fig.subplots(len(names), 1, sharex=True, squeeze=False)[:, 0]
    colours = _run_colours(ds.sizes["run"])
    # Colours and legend in the order of the factor values (the first factor varying slowest).
    order = np.lexsort([ds[f].values for f in reversed(factors)]) if factors else None
    runs = order if order is not None else np.arange(ds.sizes["run"])
    for ax, name in zip(axes, names, strict=True):
        for shade, run in enumerate(runs):
            label = ", ".join(f"{f} {_shown(ds, f, ds[f].values[run])}" for f in factors)
            ax.plot(
                ds["cam_angle"], ds[name].isel(run=run), color=colours[shade], lw=1, label=label
            )
        ax.set_ylabel(axis_label(name, ds[name].attrs.get("units", "")))
    axes[-1].set_xlabel(
        axis_label("cam angle from the nose", ds["cam_angle"].attrs.get("units", ""))
    )
    if ds.sizes["run"] <= MAX_LEGEND_RUNS:
        axes[0].legend(fontsize="x-small", loc="upper right")
    fig.suptitle("Cam curves per design point", fontsize="medium")
    return fig


def _apart(points: list[tuple[float, float, float]], box: tuple[float, float] = (0.14, 0.07)):
    """The points (x, y, label) whose labels do not overlap on log axes: a label is kept only
    if no kept one lies within ``box`` (fractions of the panel's log10 span in x and y; a
    label is wider than it is tall)."""
    finite = [p for p in points if p[0] > 0 and p[1] > 0 and np.isfinite(p[:2]).all()]
    if not finite:
        return []
    logs = np.log10(np.array([p[:2] for p in finite]))
    scaled = logs / np.maximum(np.ptp(logs, axis=0), 1e-12) / np.asarray(box)
    kept: list[int] = []
    for i, xy in enumerate(scaled):
        if all(np.abs(xy - scaled[j]).max() >= 1.0 for j in kept):
            kept.append(i)
    return [finite[i] for i in kept]


def _failure_colours(checks: int) -> tuple[ListedColormap, BoundaryNorm]:
    """Green for "every check passes" only; any failing check from orange (one) to dark red
    (all), one colour per count."""
    reds = colormaps["YlOrRd"](np.linspace(0.35, 1.0, max(checks, 1)))
    colours = np.vstack([to_rgba("tab:green"), reds])
    return ListedColormap(colours), BoundaryNorm(np.arange(-0.5, checks + 1.0), checks + 1)


def _run_colours(n: int) -> list[tuple[float, float, float, float]]:

    cmap = colormaps["viridis"]
    return [cmap(i / max(n - 1, 1)) for i in range(n)]


# --- dispatch -------------------------------------------------------------------------------
FIGURES: dict[str, dict[str, Callable[[xr.Dataset], Figure | None]]] = {
    "cam": {"cam_curves": cam_curves_figure},
    "crank": {
        "torque_curve": torque_curve_figure,
        "torque_harmonics": torque_harmonics_figure,
        "approximation_error": approximation_error_figure,
    },
    "reed": {
        "frequency_map": frequency_map_figure,
        "mode_shapes": mode_shapes_figure,
        "campbell": campbell_figure,
    },
    "luffing": {"pass_fail_map": pass_fail_map_figure, "motor_power": motor_power_figure},
    "rocker": {"valve_lift": valve_lift_figure},
    "valve": {"valve_lift": valve_lift_figure, "jump_speed_map": jump_speed_map_figure},
    "valve_accuracy": {"error_vs_cost": error_vs_cost_figure},
}


def save_scene_figures(ds: xr.Dataset, folder: Path) -> list[Path]:
    """Write the scene's figures that the Dataset's variables allow; return their paths."""
    folder = Path(folder)
    paths = []
    for name, build in FIGURES.get(str(ds.attrs.get("scene", "")), {}).items():
        fig = build(ds)
        if fig is None:
            continue
        folder.mkdir(parents=True, exist_ok=True)
        path = folder / f"{name}.png"
        fig.savefig(path, dpi=DPI)
        paths.append(path)
    return paths
