"""The report's section for one response: range analysis, ANOVA, variance decomposition,
interactions, S/N and the predicted optimum, all read from the analysis Dataset."""

from __future__ import annotations

import json
from typing import Any

import numpy as np
import xarray as xr

from studies import plots, taguchi
from studies.analysis_text import NO_NOISE, decomposition_frame
from studies.markdown_format import (
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
from studies.prediction import Prediction
from studies.text_safety import md_escape


def _shown(view: xr.Dataset, response: str) -> str:
    """The response's name, noting when its values are means over replicates."""
    replicated = taguchi.mean_name(view, response) != response
    return f"{response} (mean over replicates)" if replicated else response


def _range_rows(view: xr.Dataset, an: xr.Dataset, name: str) -> tuple[list[str], list[list[Any]]]:
    r = an.sel(response=name)
    factors = taguchi.factor_names(view)
    nlevels = int(np.isfinite(r.k.sel(term=factors).values).any(axis=0).sum())
    header = ["factor", *[f"k{i + 1}" for i in range(nlevels)], "R", "rank", "best level"]
    rows = []
    for f in factors:
        row = r.sel(term=f)
        rows.append(
            [
                f,
                *[num(float(k)) for k in row.k.values[:nlevels]],
                num(float(row.R)),
                int(row["rank"]),
                level_text(an, f, int(row.best_level)),
            ]
        )
    return header, rows


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
    pooled = [str(t) for t, p in zip(an["source"].values, r.pooled.values, strict=True) if p]
    pooling = f"Pooled into error: {', '.join(pooled)}." if pooled else "No term pooled into error."
    errors = json.loads(view.attrs.get("error_columns", "[]"))
    source = (
        f"Error from the empty column(s) {', '.join(errors)}"
        if errors
        else "Error from the dof the terms leave"
    )
    note = str(r.anova_note.values)
    return [table(header, rows), "", md_escape(f"{source}. {pooling} {note}".rstrip()), ""]


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
        f"{md_escape(sense.capitalize())} is better. k\\_i = mean at level i.",
        "",
        "### Range analysis",
        "",
    ]
    header, rows = _range_rows(view, an, mean)
    lines += [table(header, rows), ""]
    lines += figure(f"main_effects_{response}.png", f"Main effects on {response}", figures)
    lines += ["### ANOVA", "", *_anova_lines(view, an, mean, units)]
    lines += _decomposition_lines(an, mean)
    lines += figure(plots.map_png(response), f"Map of {response}", figures)
    if an.sizes["interaction"]:
        lines += _interaction_lines(view, an, response, figures)
    sn = taguchi.sn_name(response)
    if sn in an["response"].values:
        lines += _sn_lines(view, an, response, figures)
    lines += _optimum_lines(view, an, mean, response)
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
    finite = y.values[np.isfinite(y.values)]
    value = value_text(float(finite[0]), units if units != "1" else "") if finite.size else "—"
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
    p = stored_prediction(an, sn)
    lines += [
        f"Predicted S/N at its best levels: {num(p.mean)} dB"
        + (
            f" ± {num(p.half_width)} dB ({100 * (1 - p.alpha):g} % confidence)."
            if np.isfinite(p.half_width)
            else "."
        ),
        "",
    ]
    lines += figure(plots.sn_png(response), f"S/N ratio of {response}", figures)
    return lines


def optimum_levels(an: xr.Dataset, name: str) -> dict[str, int]:
    r = an.sel(response=name)
    return {
        str(t): int(level)
        for t, level, factor in zip(
            an["term"].values, r.optimum_level.values, an["is_factor"].values, strict=True
        )
        if factor
    }


def stored_prediction(an: xr.Dataset, name: str) -> Prediction:
    """The predicted optimum of ``name`` as the analysis Dataset holds it."""
    r = an.sel(response=name)
    terms = str(r.model_terms.values)
    return Prediction(
        response=name,
        units=str(r.units.values),
        sense=str(r.sense.values),
        levels=optimum_levels(an, name),
        terms=tuple(terms.split(",")) if terms else (),
        mean=float(r.predicted),
        grand_mean=float(r.grand_mean),
        n_eff=float(r.n_eff),
        error_ms=float(r.error_ms),
        error_dof=int(r.error_dof),
        alpha=float(an.attrs["alpha"]),
        half_width=float(r.half_width),
        confirmation_runs=int(an.attrs["confirmation_runs"]),
        confirmation_half_width=float(r.confirmation_half_width),
    )


def _optimum_lines(view: xr.Dataset, an: xr.Dataset, name: str, response: str) -> list[str]:
    p = stored_prediction(an, name)
    rows = [
        [f, p.levels[f] + 1, value_text(levels_of(an, f)[p.levels[f]], units_of(view, f))]
        for f in taguchi.factor_names(view)
    ]
    units = f" {md_escape(p.units)}" if p.units and p.units != "1" else ""
    level = f"{100 * (1 - p.alpha):g} %"
    lines = ["### Predicted optimum", "", table(["factor", "level", "value"], rows), ""]
    lines.append(
        f"Predicted {md_escape(_shown(view, response))} at these levels: **{num(p.mean)}{units}** "
        f"(grand mean {num(p.grand_mean)}{units}; model terms "
        f"{md_escape(', '.join(p.terms) or 'none')})."
    )
    if np.isfinite(p.half_width):
        lo, hi = p.interval
        clo, chi = p.confirmation_interval
        lines.append(
            f"{level} confidence interval of the mean: {num(lo)} … {num(hi)}{units} "
            f"(± {num(p.half_width)}; n_eff = {num(p.n_eff)}, V_e = {num(p.error_ms)} with "
            f"{p.error_dof} dof). A confirmation run should fall in {num(clo)} … "
            f"{num(chi)}{units} (± {num(p.confirmation_half_width)}, "
            f"{p.confirmation_runs} run)."
        )
    else:
        lines.append("No interval: the error term has no degrees of freedom.")
    if _shown(view, response) != response:
        lines.append(
            "Replicated responses are analysed as run means: the interval of a confirmation run "
            "is for the mean of as many replicates."
        )
    lines += _observed(view, p, units)
    return [*lines, ""]


def _observed(view: xr.Dataset, p: Prediction, units: str) -> list[str]:
    """The run that already holds the predicted combination (every one does in a full
    factorial), as a check on the additive model."""
    hit = np.ones(view.sizes["run"], dtype=bool)
    for f, level in p.levels.items():
        hit &= view[f"{f}_level"].values == level
    runs = np.flatnonzero(hit)
    if runs.size == 0:
        return []
    y = view[p.response].values[runs]
    shown = ", ".join(f"{num(float(v))}{units} (run {i + 1})" for i, v in zip(runs, y, strict=True))
    return [f"Observed at these levels: {shown}. The prediction is the additive model's."]
