"""``compare --plot``: the main effects of several runs overlaid, one figure per response.

Each panel is one factor the runs share: the mean of the response at each of the factor's
values (in SI), over the design points the runs have in common, one line per run, labelled
with what differs between the runs (``reference_rtol 1e-10``), not their ids.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from studies.common.figure_style import axis_label
from studies.common.units import UNITS, si_unit
from studies.compare.runs import Comparison, matched_points
from studies.report.plots import DPI, PANEL_SIZE


def overlay_figure(c: Comparison, response: str) -> Figure:
    """One panel per shared factor, a line per run."""
    factors = c.matched_on
    fig = Figure(figsize=(PANEL_SIZE[0] * len(factors), PANEL_SIZE[1]), layout="constrained")
    axes = fig.subplots(1, len(factors), sharey=True, squeeze=False)[0]
    reference = c.runs[0].results
    for i, run in enumerate(c.runs):
        common = matched_points(reference, run.results, factors).reset_index()
        column = response if i == 0 else f"{response}_other"
        for ax, f in zip(axes, factors, strict=True):
            means = common.groupby(f, sort=True)[column].mean()
            x = means.index.to_numpy()
            positions = x if np.issubdtype(x.dtype, np.number) else np.arange(x.size)
            ax.plot(positions, means.to_numpy(), marker="o", label=c.label(i))
            if positions is not x:
                ax.set_xticks(positions, [str(v) for v in x])
    for ax, f in zip(axes, factors, strict=True):
        ax.set_xlabel(axis_label(f, _si_units(str(reference[f].attrs.get("units", "")))))
    axes[0].set_ylabel(axis_label(response, reference[response].attrs.get("units", "")))
    axes[0].legend(fontsize="small")
    fig.suptitle(f"Main effects on {response}: {len(c.runs)} runs on their common points")
    return fig


def _si_units(units: str) -> str:
    return si_unit(units) if units in UNITS else units


def save_overlays(c: Comparison, folder: Path) -> list[Path]:
    """Write ``compare_<response>.png`` per shared response into ``folder``."""
    folder.mkdir(parents=True, exist_ok=True)
    paths = []
    for response in dict.fromkeys(ch.response for ch in c.changes):
        path = folder / f"compare_{response}.png"
        overlay_figure(c, response).savefig(path, dpi=DPI)
        paths.append(path)
    return paths
