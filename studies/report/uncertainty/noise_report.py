"""Renderers of the statistics under noise (:mod:`studies.analysis.uncertainty.noise_statistics`): per response a
table of every design point's mean, sd, quantiles and probability of violating its limit, and
the robust choice — the most robust computed design point and the control levels that the S/N
ratio over the noise prefers, and the map of the probability of violation over the two
strongest control factors (:mod:`studies.report.uncertainty.violation_map`). Text for ``analysis.txt``, Markdown for ``report.md`` (and so
``report.html``). Every number comes from the results or the analysis Dataset."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import xarray as xr
from matplotlib.figure import Figure

from studies.analysis.uncertainty.noise_statistics import DIM
from studies.common.figure_style import axis_label
from studies.common.text_safety import Markup, md_escape
from studies.report.markdown_format import aligned, figure, label, levels_of, num, table
from studies.report.uncertainty import violation_map
from studies.run.results import NOISE

MAX_ROWS = 100  # design points listed; larger designs point to analysis.nc
MAX_CURVES = 30  # design points drawn in the figure; larger designs: the most robust only


def has_noise(an: xr.Dataset) -> bool:
    return DIM in an.dims


def _limit_words(an: xr.Dataset, name: str) -> str:
    row = an.sel({DIM: name})
    units = str(row["noise_units"].values)
    parts = []
    if np.isfinite(float(row["limit_min"])):
        parts.append(f"{name} < {num(float(row['limit_min']))} {units}".rstrip())
    if np.isfinite(float(row["limit_max"])):
        parts.append(f"{name} > {num(float(row['limit_max']))} {units}".rstrip())
    return " or ".join(parts)


def _rows(ds: xr.Dataset, an: xr.Dataset, name: str) -> tuple[list[str], list[list[str]]]:
    row = an.sel({DIM: name})
    factors = json.loads(ds.attrs.get("factors", "[]"))
    q = [f"{100 * p:g} %" for p in an["quantile"].values]
    header = ["run", *factors, "n", "mean [95 % CI]", "sd", *(f"q {p}" for p in q)]
    limited = bool(_limit_words(an, name))
    if limited:
        header.append(f"P({_limit_words(an, name)}) [95 % Wilson]")
    shown = slice(0, min(ds.sizes["run"], MAX_ROWS))  # read once, as arrays: never per cell
    at = [ds[f][shown].values for f in factors]
    first = row.isel(run=shown).load()
    stats = {k: first[k].values for k in ("noise_mean", "noise_mean_low", "noise_mean_high")}
    n, sd, quantiles = first["noise_n"].values, first["noise_sd"].values, first["noise_quantile"]
    rows = []
    for i in range(shown.stop):
        mean = (
            f"{num(float(stats['noise_mean'][i]))} [{num(float(stats['noise_mean_low'][i]))}, "
            f"{num(float(stats['noise_mean_high'][i]))}]"
        )
        values = [str(i + 1), *(_value(v[i]) for v in at)]
        values += [str(int(n[i])), mean, num(float(sd[i]))]
        values += [num(float(v)) for v in quantiles.values[i]]
        if limited:
            values.append(_probability(first, i))
        rows.append(values)
    return header, rows


def _value(v: object) -> str:
    return num(float(v)) if isinstance(v, int | float | np.number) else str(v)


def _units(an: xr.Dataset, term: str) -> str:
    units = str(an["term_units"].sel(term=term).values)
    return f" {units}" if units not in ("", "1") else ""


def _probability(row: xr.Dataset, i: int) -> str:
    p = float(row["violation_probability"][i])
    if not np.isfinite(p):
        return "—"
    k, n = int(row["violations"][i]), int(row["violation_n"][i])
    low, high = float(row["violation_low"][i]), float(row["violation_high"][i])
    return f"{num(p, 3)} ({k}/{n}) [{num(low, 3)}, {num(high, 3)}]"


def _choice(ds: xr.Dataset, an: xr.Dataset, name: str) -> list[str]:
    """The most robust computed design point and the S/N-preferred control levels."""
    row = an.sel({DIM: name})
    best = int(row["robust_run"])
    lines = []
    if best >= 0:
        factors = json.loads(ds.attrs.get("factors", "[]"))
        at = ", ".join(f"{f} = {_value(ds[f].values[best])}" for f in factors)
        units = str(row["noise_units"].values)
        q = row["noise_quantile"].values[best]
        text = (
            f"Most robust computed design point for {name}: run {best + 1} ({at}): mean "
            f"{num(float(row['noise_mean'][best]))} {units}, 5 % quantile {num(float(q[0]))}, "
            f"95 % quantile {num(float(q[-1]))}"
        )
        if np.isfinite(float(row["violation_probability"][best])):
            text += f", P({_limit_words(an, name)}) = {_probability(row, best)}"
        lines.append(text + ".")
    sn = f"{name}_sn"
    if "response" in an.dims and sn in an["response"].values and "optimum_level" in an:
        levels = an["optimum_level"].sel(response=sn)
        chosen = [
            (str(t), int(v))
            for t, v in zip(levels["term"].values, levels.values, strict=True)
            if v >= 0
        ]
        if chosen:
            shown = ", ".join(
                f"{t} = {_value(levels_of(an, t)[v])}{_units(an, t)} (level {v + 1})"
                for t, v in chosen
            )
            lines.append(
                f"Robust optimum by the S/N ratio of {name} over the noise "
                f"({an.attrs.get('optimum_basis', '')}): {shown}."
            )
    return lines


def robust_text(ds: xr.Dataset, an: xr.Dataset) -> str:
    """The statistics under noise as plain text (``analysis.txt``)."""
    out = [f"Under noise: {ds.sizes[NOISE]} cases per design point ({ds.attrs['noise_design']})"]
    for name in an[DIM].values:
        header, rows = _rows(ds, an, str(name))
        out += ["", f"{name} [{an.sel({DIM: name})['noise_units'].values}] over the noise cases"]
        out += aligned(header, rows)
        out += _choice(ds, an, str(name))
        if str(name) in violation_map.mapped(an):
            out += [violation_map.sentence(an, str(name), _limit_words(an, str(name)))]
            out += violation_map.map_lines(an, str(name))
    return "\n".join(out)


def figure_name(response: str) -> str:
    return f"noise_{response}.png"


def save_noise_figures(ds: xr.Dataset, an: xr.Dataset, folder: Path) -> list[Path]:
    """``noise_<response>.png``: the empirical distribution (ECDF) of the response over the
    noise cases of each design point (grey; up to ``MAX_CURVES``), the most robust one
    highlighted, and the limits as vertical lines."""
    paths = []
    for name in an[DIM].values:
        row = an.sel({DIM: name})
        best = int(row["robust_run"])
        count = ds.sizes["run"]
        runs = list(range(count)) if count <= MAX_CURVES else [best] if best >= 0 else []
        drawn = ds[str(name)].transpose("run", NOISE).isel(run=runs).values  # only those read
        y = dict(zip(runs, drawn, strict=True))
        fig = Figure(figsize=(6.4, 4.0))  # Agg on save, no pyplot state
        ax = fig.add_subplot()
        for i in runs:
            values = y[i][np.isfinite(y[i])]
            if values.size and i != best:
                ax.ecdf(values, color="0.7", linewidth=0.8)
        if best in y and np.isfinite(y[best]).any():
            values = y[best][np.isfinite(y[best])]
            ax.ecdf(values, color="C0", linewidth=2.0, label=f"run {best + 1} (most robust)")
        for key, style in (("limit_min", "--"), ("limit_max", ":")):
            limit = float(row[key])
            if np.isfinite(limit):
                ax.axvline(limit, color="C3", linestyle=style, label=f"{key[6:]} {num(limit)}")
        units = str(row["noise_units"].values)
        ax.set_xlabel(axis_label(str(name), units))
        ax.set_ylabel("share of noise cases ≤ value")
        ax.set_title(
            f"{name} under noise, every design point (grey)"
            if count <= MAX_CURVES
            else f"{name} under noise, the most robust of {count} design points"
        )
        if ax.get_legend_handles_labels()[0]:
            ax.legend(loc="lower right")
        fig.tight_layout()
        path = folder / figure_name(str(name))
        fig.savefig(path, dpi=100)
        paths.append(path)
    words = {n: _limit_words(an, n) for n in violation_map.mapped(an)}
    return paths + violation_map.save_violation_maps(an, folder, words)


def robust_markdown(ds: xr.Dataset, an: xr.Dataset, figures: set[str]) -> list[str]:
    """The statistics under noise as a ``report.md`` section."""
    if not has_noise(an):
        return []
    lines = [
        "## Under noise",
        "",
        md_escape(
            f"Every design point ran at {ds.sizes[NOISE]} noise cases "
            f"({ds.attrs['noise_design']}). Intervals are 95 %: t for the mean, "
            "order statistics for the quantiles, Wilson for the probability of violating a "
            "limit (sampling error; indicative for an outer orthogonal array)."
        ),
        "",
    ]
    for name in an[DIM].values:
        units = str(an.sel({DIM: name})["noise_units"].values)
        header, rows = _rows(ds, an, str(name))
        lines += [f"### {label(str(name), units)}", "", table(header, rows), ""]
        for sentence in _choice(ds, an, str(name)):
            lines += [Markup(md_escape(sentence)), ""]
        lines += figure(figure_name(str(name)), f"{name} under noise", figures)
        if str(name) in violation_map.mapped(an):
            words = _limit_words(an, str(name))
            lines += [md_escape(violation_map.sentence(an, str(name), words) + "."), ""]
            caption = f"P({words}) over the two strongest control factors"
            lines += figure(violation_map.figure_name(str(name)), caption, figures)
    return lines
