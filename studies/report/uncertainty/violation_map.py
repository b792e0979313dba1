"""Renderers of the probability-of-violation map (:mod:`studies.analysis.uncertainty.violation_map`): a
heat map of P per level pair of the two strongest control factors, the limit and the response
in its title, and the sentence that says how the factors were chosen. Every number comes from
the analysis Dataset."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import xarray as xr
from matplotlib.figure import Figure

from studies.analysis.uncertainty.noise_statistics import DIM
from studies.common.figure_style import axis_label
from studies.report.markdown_format import aligned, levels_of, num


def mapped(an: xr.Dataset) -> list[str]:
    """The responses with a map."""
    if "violation_map" not in an:
        return []
    return [str(n) for n, x in zip(an[DIM].values, an["violation_map_x"].values, strict=True) if x]


def figure_name(response: str) -> str:
    return f"violation_{response}.png"


def _units(an: xr.Dataset, term: str) -> str:
    units = str(an["term_units"].sel(term=term).values)
    return "" if units in ("", "1") else units


def sentence(an: xr.Dataset, name: str, limit: str) -> str:
    """How the map was made (for the text and the report)."""
    row = an.sel({DIM: name})
    x, y = str(row["violation_map_x"].values), str(row["violation_map_y"].values)
    counts = row["violation_map_runs"].values
    counts = np.unique(counts[counts > 0])
    each = (
        f"{counts[0]} design point{'s' if counts[0] > 1 else ''}"
        if counts.size == 1
        else f"{counts.min()} to {counts.max()} design points"
    )
    return (
        f"P({limit}) over {x} × {y}, the two control factors with the largest range in the "
        f"{row['violation_map_basis'].values}: each cell is the mean of the probabilities of "
        f"the design points at that level pair ({each} per cell, over the other factors)"
    )


def map_lines(an: xr.Dataset, name: str) -> list[str]:
    """The map as rows of text: one row per level of the first factor."""
    row = an.sel({DIM: name})
    x, y = str(row["violation_map_x"].values), str(row["violation_map_y"].values)
    lx, ly = levels_of(an, x), levels_of(an, y)
    grid = row["violation_map"].values
    head = [f"{x} \\ {y}", *(_shown(v) for v in ly.values())]
    rows = [[_shown(v), *(num(float(grid[i, j]), 3) for j in ly)] for i, v in lx.items()]
    return aligned(head, rows)


def _shown(value: object) -> str:
    return num(value) if isinstance(value, float) else str(value)


def save_violation_maps(an: xr.Dataset, folder: Path, limits: dict[str, str]) -> list[Path]:
    """``violation_<response>.png`` per mapped response; ``limits`` words the limit per
    response ("jump_speed < 4500 rpm")."""
    paths = []
    for name in mapped(an):
        row = an.sel({DIM: name})
        x, y = str(row["violation_map_x"].values), str(row["violation_map_y"].values)
        lx, ly = levels_of(an, x), levels_of(an, y)
        grid = row["violation_map"].values[np.ix_(list(lx), list(ly))]
        fig = Figure(figsize=(6.4, 4.8))  # Agg on save, no pyplot state
        ax = fig.add_subplot()
        image = ax.pcolormesh(
            np.arange(len(ly)), np.arange(len(lx)), grid, shading="nearest", cmap="Reds",
            vmin=0.0, vmax=1.0,
        )  # fmt: skip
        for i in range(len(lx)):
            for j in range(len(ly)):
                if np.isfinite(grid[i, j]):
                    dark = grid[i, j] > 0.6
                    ax.text(j, i, num(float(grid[i, j]), 2), ha="center", va="center",
                            color="white" if dark else "black")  # fmt: skip
        ax.set_xticks(np.arange(len(ly)), [_shown(v) for v in ly.values()])
        ax.set_yticks(np.arange(len(lx)), [_shown(v) for v in lx.values()])
        ax.set_xlabel(axis_label(y, _units(an, y)))
        ax.set_ylabel(axis_label(x, _units(an, x)))
        ax.set_title(f"P({limits[name]}) per level pair\n(mean over the other factors' runs)")
        fig.colorbar(image, ax=ax, label="probability of violation")
        fig.tight_layout()
        path = folder / figure_name(name)
        fig.savefig(path, dpi=100)
        paths.append(path)
    return paths
