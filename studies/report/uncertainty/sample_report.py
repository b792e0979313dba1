"""Renderers of a Sobol' or Latin-hypercube sample's statistics
(:mod:`studies.analysis.uncertainty.sample_statistics`): per response its mean, sd, quantiles and
probability of violating a limit with their intervals, a table of the factors' Pearson and
Spearman correlations with it (text and Markdown), and a figure of the correlations with their
intervals. Every number comes from the analysis Dataset."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import xarray as xr
from matplotlib.figure import Figure

from studies.common.text_safety import md_escape
from studies.report.markdown_format import aligned, figure, num, table

HEADER = ["factor", "Spearman ρ", "95 % interval", "Pearson r", "95 % interval"]


def _interval(low: float, high: float) -> str:
    return f"[{num(low, 3)}, {num(high, 3)}]"


def _rows(an: xr.Dataset, response: str) -> list[list[str]]:
    r = an.sel(response=response)
    order = np.argsort(-np.nan_to_num(np.abs(r["spearman"].values), nan=-1.0), kind="stable")
    rows = []
    for i in order:
        rows.append(
            [
                str(r["factor"].values[i]),
                num(float(r["spearman"][i]), 3),
                _interval(float(r["spearman_low"][i]), float(r["spearman_high"][i])),
                num(float(r["pearson"][i]), 3),
                _interval(float(r["pearson_low"][i]), float(r["pearson_high"][i])),
            ]
        )
    return rows


def summary(an: xr.Dataset, response: str) -> list[str]:
    """Sentences on the response's distribution over the sample (95 % intervals in brackets)."""
    r = an.sel(response=response)
    units = str(r["units"].values)
    units = f" {units}" if units not in ("", "1") else ""
    q = r["sample_quantile"].values
    low, high = r["sample_quantile_low"].values, r["sample_quantile_high"].values
    quantiles = ", ".join(
        f"{100 * p:g} % {num(float(q[j]))} {_interval(float(low[j]), float(high[j]))}"
        for j, p in enumerate(an["quantile"].values)
    )
    mean = _interval(float(r["sample_mean_low"]), float(r["sample_mean_high"]))
    sd = _interval(float(r["sample_sd_low"]), float(r["sample_sd_high"]))
    first = (
        f"{response}{units} over {int(r['sample_n'])} sampled points: mean "
        f"{num(float(r['sample_mean']))} {mean}, sd {num(float(r['sample_sd']))} {sd}; "
        f"quantiles {quantiles}"
    )
    lines = [first]
    p = float(r["sample_violation_probability"])
    if np.isfinite(p):
        limits = [
            f"{response} {sign} {num(float(r[key]))}{units}"
            for key, sign in (("limit_min", "<"), ("limit_max", ">"))
            if np.isfinite(float(r[key]))
        ]
        lines.append(
            f"P({' or '.join(limits)}) = {num(p, 3)} ({int(r['sample_violations'])}/"
            f"{int(r['sample_violation_n'])}) "
            f"{_interval(float(r['sample_violation_low']), float(r['sample_violation_high']))} "
            "(Wilson)"
        )
    lines.append(
        "Correlation of each factor with it: Spearman's rank ρ (monotone effects) and "
        "Pearson's r (linear; r² is the share of the variance a factor explains when the "
        "response is additive and linear); 95 % intervals on Fisher's z scale with the variance "
        "estimated from the data (no normality assumed)"
    )
    return lines


def sample_text(an: xr.Dataset) -> list[str]:
    """One block of text per response (``analysis.txt``)."""
    out = []
    for response in an["response"].values:
        rows = _rows(an, str(response))
        lines = [*summary(an, str(response)), *aligned(HEADER, rows)]
        out.append("\n".join(lines))
    return out


def sample_markdown(an: xr.Dataset, figures: set[str]) -> list[str]:
    """The ``report.md`` sections of a Sobol' or Latin-hypercube sample."""
    lines = []
    for response in an["response"].values:
        name = str(response)
        lines += [f"## {md_escape(name)}: distribution and correlations", ""]
        for sentence in summary(an, name):
            lines += [md_escape(sentence) + ".", ""]
        lines += [table(HEADER, _rows(an, name)), ""]
        lines += figure(figure_name(name), f"correlations with {name}", figures)
    return lines


def figure_name(response: str) -> str:
    return f"correlation_{response}.png"


def save_correlations(an: xr.Dataset, folder: Path) -> list[Path]:
    """``correlation_<response>.png``: Spearman ρ and Pearson r per factor with their
    intervals, the strongest on top."""
    paths = []
    for response in an["response"].values:
        r = an.sel(response=response)
        order = np.argsort(np.nan_to_num(np.abs(r["spearman"].values), nan=-1.0), kind="stable")
        y = np.arange(order.size)
        fig = Figure(figsize=(6.0, 1.5 + 0.45 * order.size))  # Agg on save, no pyplot state
        ax = fig.add_subplot()
        for key, shift in (("spearman", 0.2), ("pearson", -0.2)):
            value = r[key].values[order]
            err = [value - r[f"{key}_low"].values[order], r[f"{key}_high"].values[order] - value]
            ax.barh(y + shift, value, 0.4, xerr=np.nan_to_num(err), label=key.capitalize())
        ax.axvline(0.0, color="0.3", linewidth=0.8)
        ax.set_yticks(y, [str(f) for f in r["factor"].values[order]])
        ax.set_xlim(-1.0, 1.0)
        ax.set_xlabel("correlation with the response (bars: 95 % interval)")
        ax.set_title(f"What drives {response}")
        ax.legend(loc="lower right")
        fig.tight_layout()
        path = folder / figure_name(str(response))
        fig.savefig(path, dpi=100)
        paths.append(path)
    return paths
