"""The report's section for one response: range analysis (levels resting on runs without a
value marked), ANOVA, variance decomposition, interactions, S/N and the optimum
(:mod:`studies.report.markdown_optimum`), all read from the analysis Dataset."""

from __future__ import annotations

import json
from typing import Any

import numpy as np
import xarray as xr

from studies.analysis import taguchi
from studies.common.blocks import blocks, level_count
from studies.common.text_safety import md_escape
from studies.report import plots
from studies.report.markdown_format import (
    figure,
    label,
    level_text,
    levels_of,
    num,
    pct,
    table,
    units_of,
    value_text,
)
from studies.report.markdown_optimum import optimum_section, sn_optimum_line
from studies.report.text import NO_NOISE, decomposition_frame, missing_notes, pooled_note


def _shown(view: xr.Dataset, response: str) -> str:
    """The response's name, noting when its values are means over replicates."""
    replicated = taguchi.mean_name(view, response) != response
    return f"{response} (mean over replicates)" if replicated else response


MAX_LEVEL_COLUMNS = 12  # level means as columns up to this many levels; more: one row each


def _best(an: xr.Dataset, row: xr.Dataset, f: str) -> str:
    role = str(an["term_role"].sel(term=f).values)
    if role in ("operating", "model"):
        return "— (operating condition)" if role == "operating" else "— (model rung)"
    best = int(row.best_level)
    if best >= 0:
        return level_text(an, f, best)
    return "— (not ranked)" if str(row.sense.values) == "none" else "— (R = 0: all levels equal)"


def _level_means(row: xr.Dataset) -> list[str]:
    """The level means of a term, each marked * when runs at that level have no value (left
    out) and † when some count at a bound (see the notes under the table); the arrays are
    read once (a factor may have hundreds of levels)."""
    k, left_out, bounded = row.k.values, row.left_out.values, row.bounded.values
    return [
        num(float(k[i])) + ("*" if int(left_out[i]) else "") + ("†" if int(bounded[i]) else "")
        for i in range(k.size)
    ]


def _range_rows(view: xr.Dataset, an: xr.Dataset, name: str) -> tuple[list[str], list[list[Any]]]:
    r = an.sel(response=name)
    factors = taguchi.factor_names(view)
    nlevels = int(np.isfinite(r.k.sel(term=factors).values).any(axis=0).sum())
    if nlevels > MAX_LEVEL_COLUMNS:
        header = ["factor", "levels", "R", "rank", "best level"]
        rows = [[f, len(levels_of(an, f)), num(float(r.sel(term=f).R)), int(r.sel(term=f)["rank"]),
                 _best(an, r.sel(term=f), f)] for f in factors]  # fmt: skip
        return header, rows
    header = ["factor", *[f"k{i + 1}" for i in range(nlevels)], "R", "rank", "best level"]
    rows = []
    for f in factors:
        row = r.sel(term=f)
        rows.append(
            [
                f,
                *_level_means(row)[:nlevels],
                num(float(row.R)),
                int(row["rank"]),
                _best(an, row, f),
            ]
        )
    return header, rows


def _long_levels(view: xr.Dataset, an: xr.Dataset, name: str) -> list[str]:
    """The level means of factors with more levels than fit as columns, one row per level."""
    r = an.sel(response=name)
    lines = []
    for f in taguchi.factor_names(view):
        row = r.sel(term=f)
        present = np.flatnonzero(np.isfinite(row.k.values))
        if present.size <= MAX_LEVEL_COLUMNS:
            continue
        values, means, units = levels_of(an, f), _level_means(row), units_of(view, f)
        rows = [[value_text(values[int(i)], units), means[int(i)]] for i in present]
        lines += [f"Level means of {md_escape(f)}:", "", table([f, "k"], rows), ""]
    return lines


def _anova_lines(view: xr.Dataset, an: xr.Dataset, name: str, units: str) -> list[str]:
    r = an.sel(response=name)
    rows = [
        [f"{source} (pooled)" if pooled else str(source), num(float(ss)), int(dof),
         num(float(ms)), num(float(f)), num(float(p), 3), pct(float(c))]
        for source, ss, dof, ms, f, p, c, pooled in zip(
            an["source"].values, r.SS.values, r.dof.values, r.MS.values, r.F.values,
            r.P.values, r.contribution.values, r.pooled.values, strict=True,
        )
    ]  # fmt: skip
    squared = f"{units}²" if units.isalpha() else f"({units})²"
    header = ["source", label("SS", squared if units != "1" else ""), "dof", "MS", "F", "P", "%"]
    for row, pooled in zip(rows, r.pooled.values, strict=True):
        if pooled:  # its share is inside the error row: shown in parentheses, not counted twice
            row[-1] = f"({row[-1]})"
    pooled = [str(t) for t, p in zip(an["source"].values, r.pooled.values, strict=True) if p]
    pooling = f"Pooled into error: {', '.join(pooled)}." if pooled else "No term pooled into error."
    source = _error_source(view, r, pooled)
    note = str(r.anova_note.values)
    share = f" {pooled_note()}" if pooled else ""
    return [table(header, rows), "", md_escape(f"{source}. {pooling}{share} {note}".rstrip()), ""]


def _error_source(view: xr.Dataset, r: xr.Dataset, pooled: list[str]) -> str:
    """Where the error row's degrees of freedom come from: the empty columns, and the dof the
    array's columns leave beyond them (an L18's 2: the interaction of its first two columns);
    with runs left out (no value), the dof the terms leave over the runs that have one."""
    errors = json.loads(view.attrs.get("error_columns", "[]"))
    dof = dict(zip(map(str, r["source"].values), r.dof.values.astype(int), strict=True))
    runs = dof.get("total", -1) + 1
    if 0 < runs < view.sizes["run"]:  # runs without a value left out: no column is whole
        own = dof.get("error", 0) - sum(dof[p] for p in pooled)
        if own == 0:
            return f"Over the {runs} runs with a value the terms leave the error no dof"
        return f"Error from the {own} dof the terms leave over the {runs} runs with a value"
    empty = sum(level_count(view[f"{e}_level"].variable) - 1 for e in errors)
    left = dof.get("error", 0) - sum(dof[p] for p in pooled) - empty
    if not errors:
        return "Error from the dof the terms leave"
    text = f"Error from the empty column(s) {', '.join(errors)} ({empty} dof)"
    if left > 0:
        text += f" and the {left} dof the array's columns leave"
    return text


def _decomposition_lines(an: xr.Dataset, name: str) -> list[str]:
    if "first_order" not in an or not np.isfinite(an.first_order.sel(response=name)).any():
        return []
    frame = decomposition_frame(an, name)
    rows = [
        [source, num(row["SS"]), pct(row["share %"]), num(row["S1"], 3), num(row["ST"], 3)]
        for source, row in frame.iterrows()
    ]
    return [
        "### Variance decomposition (computer experiment)",
        "",
        table(["source", "SS", "%", "S1", "ST"], rows),
        "",
        f"{NO_NOISE} S1 and ST are the first-order and total Sobol indices over the grid.",
        "",
    ]


def response_section(
    view: xr.Dataset, an: xr.Dataset, response: str, figures: set[str]
) -> list[str]:
    mean = taguchi.mean_name(view, response)
    r = an.sel(response=mean)
    units, sense = str(r.units.values), str(r.sense.values)
    lines = [
        f"## {md_escape(response)}: {label(str(r.long_name.values), units)}",
        "",
        (
            f"{md_escape(sense.capitalize())} is better."
            if sense != "none"
            else 'Not ranked ([sense] = "none": no direction is better, no best level).'
        )
        + " k\\_i = mean at level i.",
        "",
        "### Range analysis",
        "",
    ]
    header, rows = _range_rows(view, an, mean)
    lines += [table(header, rows), ""]
    notes = missing_notes(an, mean)
    lines += [*map(md_escape, notes), ""] if notes else []
    lines += _long_levels(view, an, mean)
    lines += figure(f"main_effects_{response}.png", f"Main effects on {response}", figures)
    lines += ["### ANOVA", "", *_anova_lines(view, an, mean, units)]
    lines += _decomposition_lines(an, mean)
    lines += figure(plots.map_png(response), f"Map of {response}", figures)
    if an.sizes["interaction"]:
        lines += _interaction_lines(view, an, response, figures)
    sn = taguchi.sn_name(response)
    if sn in an["response"].values:
        lines += _sn_lines(view, an, response, figures)
    elif why := taguchi.sn_left_out(view, response):
        lines += ["### Signal-to-noise ratio", "", md_escape(why), ""]
    lines += optimum_section(view, an, mean, _shown(view, response))
    return lines


def _interaction_lines(
    view: xr.Dataset, an: xr.Dataset, response: str, figures: set[str]
) -> list[str]:
    mean = taguchi.mean_name(view, response)
    r = an.sel(response=mean)
    rows = [
        [f"{name} (pooled)" if r.interaction_pooled.values[i] else str(name),
         num(float(r.interaction_SS.values[i])), int(r.interaction_dof.values[i]),
         num(float(r.interaction_F.values[i])), num(float(r.interaction_P.values[i]), 3),
         pct(float(r.interaction_contribution.values[i]))]
        for i, name in enumerate(an["interaction"].values)
    ]  # fmt: skip
    lines = ["### Interactions", "", table(["interaction", "SS", "dof", "F", "P", "%"], rows), ""]
    units = str(r.units.values)
    pairs = zip(an["interaction_a"].values, an["interaction_b"].values, strict=True)
    for i, (a, b) in enumerate(pairs):
        means = r.interaction_mean.values[i]
        la = np.flatnonzero(np.isfinite(means).any(axis=1)).tolist()
        lb = np.flatnonzero(np.isfinite(means).any(axis=0)).tolist()
        va, vb = levels_of(an, a), levels_of(an, b)
        ua, ub = units_of(view, a), units_of(view, b)
        head = [f"{a} \\ {b}", *[value_text(vb[j], ub) for j in lb]]
        body = [[value_text(va[i_a], ua), *[num(float(means[i_a, j])) for j in lb]] for i_a in la]
        by = f"{label(f'Mean {response}', units)} by level of {md_escape(a)} and {md_escape(b)}:"
        lines += [by, ""]
        lines += [table(head, body), ""]
        lines += figure(plots.interaction_png(response, a, b), f"{a} x {b}", figures)
    return lines


def constant_section(view: xr.Dataset, response: str, figures: set[str]) -> list[str]:
    y = view[taguchi.mean_name(view, response)]
    units = str(y.attrs.get("units", ""))
    first = next((v[np.isfinite(v)][0] for v in blocks(y.variable) if np.isfinite(v).any()), None)
    value = value_text(float(first), units if units != "1" else "") if first is not None else "—"
    long_name = str(y.attrs.get("long_name", response))
    return [
        f"## {md_escape(response)}: {label(long_name, units)}",
        "",
        f"Does not vary over the runs ({md_escape(value)} in every run with a value): "
        + "nothing to analyse.",
        "",
        *figure(f"main_effects_{response}.png", f"Main effects on {response}", figures),
    ]


def _sn_lines(view: xr.Dataset, an: xr.Dataset, response: str, figures: set[str]) -> list[str]:
    sn = taguchi.sn_name(response)
    n = int(an["observations"].sel(response=sn))
    kind = str(an["sn_kind"].sel(response=sn).values)
    lines = [
        "### Signal-to-noise ratio",
        "",
        (
            f"S/N ({md_escape(kind)} is better) in dB over {n} observation(s) per run; larger "
            "S/N is better."
        ),
        "",
    ]
    if n == 1:
        lines[-2] += " With one observation per run the S/N is a log transform of the response."
    header, rows = _range_rows(view, an, sn)
    lines += [table(header, rows), ""]
    best = sn_optimum_line(an, sn)
    lines += [best, ""] if best else []
    lines += figure(plots.sn_png(response), f"S/N ratio of {response}", figures)
    return lines
