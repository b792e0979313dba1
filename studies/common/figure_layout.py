"""What every scene's figures share: selecting runs by factor levels, laying out panels, and
labelling values, so a scene's ``figures.py`` (built-in or a plugin's) only draws.

A figure has one line per level of a "line" factor and one panel per combination of up to two
other factors (:class:`Layout`); further factors are held at their middle level (named in the
title). :func:`save_figures` writes the figures a scene declares (``Scene.figures``).
"""

from __future__ import annotations

import json
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr
from matplotlib import colormaps
from matplotlib.figure import Figure

from studies.common.blocks import blocks, first_run, runs_matching
from studies.common.figure_style import axis_label, pretty_units

DPI = 120
PANEL = (3.6, 2.8)  # inches per panel


def design_factors(ds: xr.Dataset) -> list[str]:
    return list(json.loads(ds.attrs.get("factors", "[]")))


def factor_levels(ds: xr.Dataset, factor: str) -> list[int]:
    """The level codes of ``factor`` that some run has (read a block of runs at a time)."""
    found: set[int] = set()
    for codes in blocks(ds[f"{factor}_level"].variable):
        found.update(np.unique(codes).tolist())
    return sorted(found)


def raw_value(ds: xr.Dataset, factor: str, level: int):
    """The factor's value at a level (taken from the first run at that level)."""
    run = first_run(ds[f"{factor}_level"].variable, level)
    if run < 0:
        raise IndexError(f"no run at level {level} of {factor}")
    return ds[factor].variable[run].values[()]


def value_text(ds: xr.Dataset, factor: str, level: int) -> str:
    return shown_value(ds, factor, raw_value(ds, factor, level))


def shown_value(ds: xr.Dataset, factor: str, value: object) -> str:
    """A factor's value as a person reads it: a number with its units (printed as in axis
    labels: m/s²), or a level's name."""
    units = str(ds[factor].attrs.get("units", ""))
    shown = f"{value:g}" if isinstance(value, (int, float, np.number)) else str(value)
    return f"{shown} {pretty_units(units)}" if units not in ("", "1") else shown


def runs_where(ds: xr.Dataset, where: dict[str, int]) -> np.ndarray:
    """The runs at the levels ``where`` (factor → level), a block of runs at a time."""
    conditions = [(ds[f"{f}_level"].variable, level) for f, level in where.items()]
    return runs_matching(conditions, ds.sizes["run"])


class Layout:
    """Panels (row × column factor levels) and held factors for a figure. ``names``: what a
    level means where its value would mislead, e.g. ``{("tolerance", 0.0): "fixed step"}``."""

    def __init__(
        self,
        ds: xr.Dataset,
        used: Sequence[str],
        names: dict[tuple[str, object], str] | None = None,
    ) -> None:
        self.names = names or {}
        others = [f for f in design_factors(ds) if f not in used]
        self.row = others[0] if len(others) > 1 else None
        self.col = others[1] if len(others) > 1 else others[0] if others else None
        self.held = {
            f: factor_levels(ds, f)[(len(factor_levels(ds, f)) - 1) // 2] for f in others[2:]
        }
        self.rows = factor_levels(ds, self.row) if self.row else [0]
        self.cols = factor_levels(ds, self.col) if self.col else [0]
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
        shown = [self.level(f, lv) for f, lv in where.items() if f in (self.row, self.col)]
        return ", ".join(shown)

    def level(self, factor: str, level: int) -> str:
        """``factor = value units``, or the level's name from ``names``."""
        named = self.names.get((factor, raw_value(self.ds, factor, level).item()))
        return named or f"{factor} = {value_text(self.ds, factor, level)}"

    def held_note(self) -> str:
        if not self.held:
            return ""
        return " (held: " + ", ".join(self.level(f, lv) for f, lv in self.held.items()) + ")"


def line_levels(ds: xr.Dataset, factor: str | None) -> list[tuple[str, dict[str, int]]]:
    """(label, level condition) per line; one unlabelled line when there is no line factor."""
    if factor is None or factor not in design_factors(ds):
        return [("", {})]
    return [(value_text(ds, factor, lv), {factor: lv}) for lv in factor_levels(ds, factor)]


def long_label(da: xr.DataArray, name: str) -> str:
    units = da.attrs.get("units", "")
    return axis_label(da.attrs.get("long_name", name), units) if units else name


def short_label(ds: xr.Dataset, name: str) -> str:
    return axis_label(name, ds[name].attrs.get("units", ""))


def grid_of(ds: xr.Dataset, name: str, x: str, y: str, where: dict[str, int]) -> np.ndarray:
    """Values of ``name`` on the (y level, x level) grid of the runs matching ``where``."""
    grid = np.full((len(factor_levels(ds, y)), len(factor_levels(ds, x))), np.nan)
    for run in runs_where(ds, where):
        grid[int(ds[f"{y}_level"].values[run]), int(ds[f"{x}_level"].values[run])] = float(
            ds[name].values[run]
        )
    return grid


def level_values(ds: xr.Dataset, factor: str) -> np.ndarray:
    return np.array([float(raw_value(ds, factor, lv)) for lv in factor_levels(ds, factor)])


def level_ticks(ds: xr.Dataset, factor: str) -> tuple[np.ndarray, list[str]]:
    """Cell positions 0, 1, … of a factor's levels and their values as tick labels (numbers or
    names such as a lift law), so a map has equal cells however the levels are spaced."""
    values = [raw_value(ds, factor, lv) for lv in factor_levels(ds, factor)]
    labels = [f"{v:g}" if isinstance(v, (int, float, np.number)) else str(v) for v in values]
    return np.arange(len(values), dtype=float), labels


def run_colours(n: int) -> list[tuple[float, float, float, float]]:

    cmap = colormaps["viridis"]
    return [cmap(i / max(n - 1, 1)) for i in range(n)]


def apart_labels(points: list[tuple[float, float, Any]], box: tuple[float, float] = (0.14, 0.07)):
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


def save_figures(
    ds: xr.Dataset, folder: Path, builders: dict[str, Callable[[xr.Dataset], Figure | None]]
) -> list[Path]:
    """Write ``<name>.png`` for each builder that draws a figure from ``ds`` (a builder returns
    None when the Dataset lacks its variables); return the paths."""
    folder = Path(folder)
    paths = []
    for name, build in builders.items():
        fig = build(ds)
        if fig is None:
            continue
        folder.mkdir(parents=True, exist_ok=True)
        path = folder / f"{name}.png"
        fig.savefig(path, dpi=DPI)
        paths.append(path)
    return paths
