"""Figure of a benchmark: every timing as a bar of cases/s (log scale), beside its JSON."""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

from matplotlib.figure import Figure
from matplotlib.patches import Patch

BAR_HEIGHT_INCHES = 0.28
DPI = 120
SOURCES = {  # what a timing measures → bar colour
    "Numba kernels and study engine": "tab:blue",
    "C reference (studies/reference)": "tab:orange",
    "scipy reference": "tab:gray",
}


def source(name: str) -> str:
    """Which kind of code a timing measures, from its name (``..._c_...``: C, ``scipy_``)."""
    key = name.rsplit(": ", 1)[-1]
    if key.startswith("scipy"):
        return "scipy reference"
    if re.search(r"(^|_)c_", key):
        return "C reference (studies/reference)"
    return "Numba kernels and study engine"


def timings(figures: dict[str, Any], prefix: str = "") -> list[tuple[str, float]]:
    """(name, cases/s) of every timing in the figures, nested groups flattened in order."""
    found = []
    for key, value in figures.items():
        if isinstance(value, dict) and "cases_per_s" in value:
            found.append((prefix + key, float(value["cases_per_s"])))
        elif isinstance(value, dict):
            found += timings(value, f"{prefix}{key}: ")
    return found


def save_bench_figure(title: str, figures: dict[str, Any], path: Path) -> Path | None:
    """Horizontal bars of cases/s, one per timing; None if there are no timings."""
    rows = timings(figures)
    if not rows:
        return None
    names, rates = zip(*rows, strict=True)
    fig = Figure(figsize=(8.0, 1.2 + BAR_HEIGHT_INCHES * len(rows)), layout="constrained")
    ax = fig.add_subplot()
    positions = range(len(rows))
    kinds = [source(n) for n in names]
    ax.barh(positions, rates, color=[SOURCES[k] for k in kinds])
    handles = [Patch(color=SOURCES[k], label=k) for k in dict.fromkeys(kinds)]
    ax.legend(handles=handles, fontsize="small", loc="lower right")
    ax.set_yticks(list(positions), names, fontsize="small")
    ax.invert_yaxis()
    ax.set_xscale("log")
    ax.set_xlabel("design points per second [1/s] (log scale)")
    ax.grid(axis="x", which="both", alpha=0.3)
    for y, rate in zip(positions, rates, strict=True):
        ax.text(rate, y, f" {rate:,.0f}", va="center", fontsize="x-small")
    ax.set_title(title, fontsize="medium")
    fig.savefig(path, dpi=DPI)
    return path
