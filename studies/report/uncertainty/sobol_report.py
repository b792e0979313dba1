"""Renderers of a Saltelli design's Sobol' indices (:mod:`studies.analysis.uncertainty.sobol_indices`): a
table per response (text and Markdown), with a table of the second-order indices where the
study asked for them, and a tornado figure of S1 and ST with their bootstrap
intervals. Every number comes from the analysis Dataset."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import xarray as xr
from matplotlib.figure import Figure

from studies.common.text_safety import md_escape
from studies.report.markdown_format import aligned, figure, num, table

HEADER = ["factor", "S1", "± S1_conf", "ST", "± ST_conf"]
PAIR_HEADER = ["factors", "S2", "± S2_conf"]


def _rows(an: xr.Dataset, response: str) -> list[list[str]]:
    r = an.sel(response=response)
    order = np.argsort(-np.nan_to_num(r["ST"].values, nan=-np.inf), kind="stable")
    return [
        [str(r["factor"].values[i])]
        + [num(float(r[k].values[i]), 3) for k in ("S1", "S1_conf", "ST", "ST_conf")]
        for i in order
    ]


def _pairs(an: xr.Dataset, response: str) -> list[list[str]]:
    """The second-order indices (asked with ``second_order``), largest first ([] if none)."""
    if "S2" not in an:
        return []
    r = an.sel(response=response)
    s2, conf = r["S2"].values, r["S2_conf"].values
    i, j = np.triu_indices(s2.shape[0], k=1)
    order = np.argsort(-np.nan_to_num(s2[i, j], nan=-np.inf), kind="stable")
    names = [str(f) for f in r["factor"].values]
    return [
        [
            f"{names[i[k]]} × {names[j[k]]}",
            num(float(s2[i[k], j[k]]), 3),
            num(float(conf[i[k], j[k]]), 3),
        ]
        for k in order
    ]


PAIR_INTRO = "Second-order indices (Saltelli 2002) of each factor pair, largest first"


def _intro(an: xr.Dataset, response: str) -> str:
    rows = int(an["rows_used"].sel(response=response))
    return (
        f"Sobol' indices of {response} (Saltelli 2010 first order, Jansen total effect) from "
        f"{rows} base rows; ± is the half width of the {100 * an.attrs['confidence']:g} % "
        f"bootstrap interval ({an.attrs['resamples']} resamples)"
    )


def sobol_text(an: xr.Dataset) -> list[str]:
    """One block of text per response (``analysis.txt``)."""
    out = []
    for response in an["response"].values:
        lines = [_intro(an, str(response)), *aligned(HEADER, _rows(an, str(response)))]
        pairs = _pairs(an, str(response))
        if pairs:
            lines += [PAIR_INTRO, *aligned(PAIR_HEADER, pairs)]
        out.append("\n".join(lines))
    return out


def sobol_markdown(an: xr.Dataset, figures: set[str]) -> list[str]:
    """The ``report.md`` sections of a Saltelli design."""
    lines = []
    for response in an["response"].values:
        name = str(response)
        lines += [f"## {md_escape(name)}: Sobol' indices", "", md_escape(_intro(an, name)), ""]
        lines += [table(HEADER, _rows(an, name)), ""]
        pairs = _pairs(an, name)
        if pairs:
            lines += [md_escape(PAIR_INTRO), "", table(PAIR_HEADER, pairs), ""]
        lines += figure(f"tornado_{name}.png", f"S1 and ST of {name}", figures)
    return lines


def save_tornado(an: xr.Dataset, folder: Path) -> list[Path]:
    """``tornado_<response>.png``: S1 and ST per factor with their intervals, largest ST on top."""
    paths = []
    for response in an["response"].values:
        r = an.sel(response=response)
        order = np.argsort(np.nan_to_num(r["ST"].values, nan=-np.inf), kind="stable")
        y = np.arange(order.size)
        fig = Figure(figsize=(6.0, 1.5 + 0.45 * order.size))  # Agg on save, no pyplot state
        ax = fig.add_subplot()
        ax.barh(y + 0.2, r["ST"].values[order], 0.4, xerr=r["ST_conf"].values[order], label="ST")
        ax.barh(y - 0.2, r["S1"].values[order], 0.4, xerr=r["S1_conf"].values[order], label="S1")
        ax.set_yticks(y, [str(f) for f in r["factor"].values[order]])
        ax.set_xlabel("Sobol' index (bars: 95 % bootstrap interval)")
        ax.set_title(f"Sensitivity of {response}")
        ax.legend(loc="lower right")
        fig.tight_layout()
        path = folder / f"tornado_{response}.png"
        fig.savefig(path, dpi=100)
        paths.append(path)
    return paths
