"""What every scene's figures share: selecting runs by factor levels, laying out panels, and
labelling values, so a scene's ``figures.py`` (built-in or a plugin's) only draws.

A figure has one line per level of a "line" factor and one panel per combination of up to two
other factors (:class:`Layout`); further factors are held at their middle level (named in the
title). A factor of more than ``MAX_LEVELS`` levels (under a sampled design every sampled value
is a level) is neither laid out nor held: :func:`many_levels` tells a figure to draw every
design point instead (:func:`scatter_figure`), and where it cannot, :class:`Layout` and
:func:`line_levels` raise :class:`NotDrawn`, which the run records as a warning.
:func:`save_figures` writes the figures a scene declares (``Scene.figures``).
"""

from __future__ import annotations

import json
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr
from matplotlib import colormaps
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from studies.common.blocks import blocks, first_run, runs_matching
from studies.common.design_kinds import SAMPLING_DESIGNS
from studies.common.errors import NotDrawn
from studies.common.figure_style import axis_label, pretty_units

DPI = 120
PANEL = (3.6, 2.8)  # inches per panel
MAX_LEVELS = 12  # levels of a factor laid out as panels or lines, or held, at most
MAX_POINTS = 20_000  # design points a scatter draws at most (evenly spread over the runs)


def design_factors(ds: xr.Dataset) -> list[str]:
    return list(json.loads(ds.attrs.get("factors", "[]")))


def factor_levels(ds: xr.Dataset, factor: str) -> list[int]:
    """The level codes of ``factor`` that some run has (read a block of runs at a time)."""
    found: set[int] = set()
    for codes in blocks(ds[f"{factor}_level"].variable):
        found.update(np.unique(codes).tolist())
    return sorted(found)


def many_levels(ds: xr.Dataset, factors: Sequence[str | None]) -> bool:
    """Whether one of ``factors`` has more than ``MAX_LEVELS`` levels, or is sampled (a
    sampled design's points share no value: a panel per value holds one point)."""
    if ds.attrs.get("design") in SAMPLING_DESIGNS:
        return any(f is not None for f in factors)
    return any(f is not None and len(factor_levels(ds, f)) > MAX_LEVELS for f in factors)


def few_levels(ds: xr.Dataset, factor: str) -> list[int]:
    """The level codes of ``factor``, to lay out or hold; :class:`NotDrawn` when it has more
    than ``MAX_LEVELS`` or is sampled (holding one sampled value of it and one of another
    factor selects no design point: every panel was empty)."""
    levels = factor_levels(ds, factor)
    design = str(ds.attrs.get("design", ""))
    if design in SAMPLING_DESIGNS:
        raise NotDrawn(
            f"{factor} is sampled ({len(levels)} distinct values in a {design} design): no "
            "panel or line per value, and no value to hold"
        )
    if len(levels) > MAX_LEVELS:
        raise NotDrawn(
            f"{factor} has {len(levels)} distinct values (more than {MAX_LEVELS}): too many to "
            "lay out a panel or line per value, or to hold one"
        )
    return levels


def middle_level(levels: Sequence[int]) -> int:
    """The level a figure holds a factor at: the middle one (the lower of two middles)."""
    return levels[(len(levels) - 1) // 2]


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
        levels = {f: few_levels(ds, f) for f in others}
        self.row = others[0] if len(others) > 1 else None
        self.col = others[1] if len(others) > 1 else others[0] if others else None
        self.held = {f: middle_level(levels[f]) for f in others[2:]}
        self.rows = levels[self.row] if self.row else [0]
        self.cols = levels[self.col] if self.col else [0]
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
    """(label, level condition) per line; one unlabelled line when there is no line factor;
    :class:`NotDrawn` when it has more than ``MAX_LEVELS`` levels."""
    if factor is None or factor not in design_factors(ds):
        return [("", {})]
    return [(value_text(ds, factor, lv), {factor: lv}) for lv in few_levels(ds, factor)]


def spread(count: int, limit: int) -> np.ndarray:
    """Indices 0 … count − 1, or ``limit`` of them evenly spread (first and last kept) when
    there are more."""
    return np.unique(np.linspace(0, count - 1, min(count, limit)).astype(np.int64))


def spread_runs(ds: xr.Dataset) -> np.ndarray:
    """Every run, or ``MAX_POINTS`` of them evenly spread over the runs when there are more."""
    return spread(ds.sizes["run"], MAX_POINTS)


def scatter_figure(
    ds: xr.Dataset,
    x: str,
    y: str,
    colour: np.ndarray,
    label: str,
    ticks: Sequence[float] | None = None,
    **style: Any,
) -> tuple[Figure, Axes]:
    """Every design point (:func:`spread_runs`) at its ``x`` and ``y``, coloured by ``colour``
    (a value per run drawn, ``style`` passed to ``scatter``) with a colour bar ``label`` (at
    ``ticks``, if given): the picture of factors with too many levels for panels or lines
    (:func:`many_levels`)."""
    runs = spread_runs(ds)
    fig = Figure(figsize=(5.8, 4.4), layout="constrained")
    ax = fig.subplots()
    dots = ax.scatter(
        ds[x].isel(run=runs).values, ds[y].isel(run=runs).values, c=colour, s=10, **style
    )
    fig.colorbar(dots, ax=ax, label=label, ticks=ticks)
    ax.set_xlabel(long_label(ds[x], x))
    ax.set_ylabel(long_label(ds[y], y))
    ax.grid(alpha=0.3)
    return fig, ax


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
    None when the Dataset lacks its variables); return the paths. A builder's
    :class:`NotDrawn` is raised again naming the figure (the run draws one builder per call)."""
    folder = Path(folder)
    paths = []
    for name, build in builders.items():
        try:
            fig = build(ds)
        except NotDrawn as exc:
            raise NotDrawn(f"{name}.png not drawn: {exc}") from None
        if fig is None:
            continue
        folder.mkdir(parents=True, exist_ok=True)
        path = folder / f"{name}.png"
        fig.savefig(path, dpi=DPI)
        paths.append(path)
    return paths
