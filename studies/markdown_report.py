"""``report.md``: a run's analysis as Markdown that can be pasted into a design review.

Sections: the study and run; the design (array, column assignment with dummy levels,
interaction and error columns); the runs; per response the range analysis, the ANOVA (pooling
always stated), interaction effects, the variance decomposition of a full factorial, S/N
ratios and the predicted optimum with its confidence interval; a trade-off summary when there
are several responses; the confirmation run as a study file (also written to
``confirmation.toml`` when the study text is known). Figures are linked by file name, only
those that were written. Sweeps get their tables and figures.

A renderer: every number comes from the results or from the analysis Dataset
(:func:`studies.analysis.analyze`); nothing here computes a statistic.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from studies import plots, taguchi
from studies.analysis_text import NO_NOISE, decomposition_frame
from studies.designs import orthogonal_array
from studies.statistics import sweep_runs

REPORT_NAME = "report.md"
CONFIRMATION_NAME = "confirmation.toml"
MAX_RUN_ROWS = 100  # runs listed in full; larger designs point to results.nc


def write_report(
    ds: xr.Dataset,
    an: xr.Dataset,
    folder: Path,
    responses: Sequence[str],
    figures: Sequence[Path] = (),
) -> list[Path]:
    """Write ``report.md`` (and ``confirmation.toml`` for array and factorial runs with the
    study text) into ``folder``; return the paths, report first. ``an`` is the analysis of
    ``ds`` (:func:`studies.analysis.analyze`)."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    text, confirmation = _report(ds, an, list(responses), {Path(f).name for f in figures})
    path = folder / REPORT_NAME
    path.write_text(text, encoding="utf-8")
    paths = [path]
    if confirmation and ds.attrs.get("study_toml"):
        paths.append(folder / CONFIRMATION_NAME)
        paths[-1].write_text(confirmation, encoding="utf-8")
    return paths


def report_text(
    ds: xr.Dataset, an: xr.Dataset, responses: Sequence[str], figures: Sequence[str] = ()
) -> str:
    """The Markdown text of :func:`write_report` (``figures``: file names that exist)."""
    return _report(ds, an, list(responses), {Path(f).name for f in figures})[0]


# --- formatting ---------------------------------------------------------------------------------
def _pct(value: float) -> str:
    return f"{value:.1f}" if np.isfinite(value) else "—"


def _num(value: Any, digits: int = 4) -> str:
    if isinstance(value, str):
        return value
    if value is None or not np.isfinite(value):
        return "—"
    return f"{value:.{digits}g}"


def _cell(value: Any) -> str:
    text = _num(value) if isinstance(value, float | np.floating) else str(value)
    return text.replace("|", "\\|").replace("\n", " ")


def _table(header: Sequence[str], rows: Sequence[Sequence[Any]]) -> str:
    lines = ["| " + " | ".join(_cell(h) for h in header) + " |"]
    lines.append("|" + "|".join("---" for _ in header) + "|")
    lines += ["| " + " | ".join(_cell(v) for v in row) + " |" for row in rows]
    return "\n".join(lines)


def _label(name: str, units: str) -> str:
    """``name [units]``; dimensionless ("1") and unknown units are left out."""
    return f"{name} [{units}]" if units and units != "1" else name


def _units(ds: xr.Dataset, name: str) -> str:
    return str(ds[name].attrs.get("units", "")) if name in ds.variables else ""


def _value(value: Any, units: str) -> str:
    shown = _num(value) if isinstance(value, int | float | np.number) else str(value)
    return f"{shown} {units}".rstrip()


def _levels(an: xr.Dataset, term: str) -> dict[int, Any]:
    """Level index → the term's value (a number, else its label), for the levels it has."""
    values = an["level_value"].sel(term=term).values
    labels = an["level_label"].sel(term=term).values
    return {
        i: float(v) if np.isfinite(v) else str(label)
        for i, (v, label) in enumerate(zip(values, labels, strict=True))
        if label != ""
    }


def _level_text(an: xr.Dataset, factor: str, level: int) -> str:
    """1-based level number and the factor's value: ``2 (9 deg)``."""
    units = str(an["term_units"].sel(term=factor).values)
    return f"{level + 1} ({_value(_levels(an, factor)[level], units)})"


def _figure(name: str, caption: str, figures: set[str]) -> list[str]:
    return [f"![{caption}]({name})", ""] if name in figures else []


def _other_figures(lines: list[str], figures: set[str]) -> list[str]:
    """Links to the figures no section has shown (e.g. the scene's own figures)."""
    text = "\n".join(lines)
    rest = sorted(f for f in figures if f"]({f})" not in text)
    if not rest:
        return []
    out = ["## Other figures", ""]
    for f in rest:
        out += _figure(f, Path(f).stem.replace("_", " "), figures)
    return out


# --- sections -----------------------------------------------------------------------------------
def _report(
    ds: xr.Dataset, an: xr.Dataset, responses: list[str], figures: set[str]
) -> tuple[str, str]:
    analysed = json.loads(an.attrs.get("analysed", "[]"))
    lines = _header(ds, responses, analysed)
    without = int(an.attrs.get("points_without_value", 0))
    if without:
        note = (
            f"**{without} of {an.attrs['points']} design points gave no value for any "
            "response**: they did not run (the reasons are in `analysis.txt`). The tables "
            "below use the others."
        )
        lines += [note, ""]
    responses = [r for r in responses if taguchi.mean_name(ds, r) in analysed]
    if ds.attrs.get("design") == "sweep":
        lines += _sweep(ds, responses, figures)
        lines += _other_figures(lines, figures)
        return "\n".join(lines).rstrip() + "\n", ""
    view = ds.assign({n: an[n] for n in an.data_vars if "run" in an[n].dims})
    lines += _design(view, an)
    lines += _runs(view, an, responses)
    optimised = []
    for r in responses:
        name = taguchi.mean_name(view, r)
        if int(an["varies"].sel(response=name)):
            lines += _response(view, an, r, figures)
            optimised.append(name)
        else:
            lines += _constant(view, r, figures)
    levels = _optimum_levels(an, optimised[0]) if optimised else {}
    if len(optimised) > 1:
        section, levels = _tradeoff(an, view, optimised)
        lines += section
    confirmation = taguchi.confirmation_toml(view, levels) if levels else ""
    if confirmation:
        lines += [
            "## Confirmation run",
            "",
            "The study below runs the chosen levels once (a full factorial of one point). "
            + (
                f"It is also written to `{CONFIRMATION_NAME}` in the run folder: run it with "
                f"`python -m studies run <run folder>/{CONFIRMATION_NAME}` and compare the "
                "result with the confirmation intervals above."
                if ds.attrs.get("study_toml")
                else "Add it to the study's other tables to run it."
            ),
            "",
            "```toml",
            confirmation.rstrip(),
            "```",
            "",
        ]
    lines += _other_figures(lines, figures)
    return "\n".join(lines).rstrip() + "\n", confirmation


def _header(ds: xr.Dataset, responses: list[str], analysed: list[str]) -> list[str]:
    a = ds.attrs
    title = a.get("title") or a.get("study_name") or "Study results"
    commit = str(a.get("git_commit", ""))[:10]
    rows = [
        ("study", f"`{a['study_name']}`" if a.get("study_name") else "—"),
        ("run", f"`{a['run_id']}`" if a.get("run_id") else "—"),
        ("design", f"{a.get('design', '?')}, {ds.sizes['run']} runs"),
        ("scene", a.get("scene", "—")),
        ("commit", (commit + (" (dirty)" if a.get("git_dirty") else "")) or "—"),
        ("created", a.get("created", "—")),
    ]
    shown = []
    for r in responses:
        y = ds[r]
        sense = y.attrs.get("better")
        shown.append(
            f"{r} ({_label(str(y.attrs.get('long_name', r)), _units(ds, r))}"
            + (f", {sense} is better" if sense else "")
            + ("" if taguchi.mean_name(ds, r) in analysed else ", NaN in every run: not analysed")
            + ")"
        )
    rows.append(("responses", "; ".join(shown)))
    return [f"# {title}", "", _table(["", ""], rows), ""]


def _design(ds: xr.Dataset, an: xr.Dataset) -> list[str]:
    factors = taguchi.factor_names(ds)
    name = str(ds.attrs.get("design", ""))
    columns = json.loads(ds.attrs.get("array_columns", "{}"))
    lines = ["## Design", ""]
    if name == "full_factorial":
        text = (
            f"Full factorial: every combination of the factor levels, {ds.sizes['run']} runs. "
            "The ANOVA error holds the interactions."
        )
        lines += [text, ""]
    else:
        lines += [f"Orthogonal array {name}, {ds.sizes['run']} runs.", ""]
    rows = []
    pairs = taguchi.interaction_columns(ds)
    errors = json.loads(ds.attrs.get("error_columns", "[]"))
    array_levels = _array_levels(name)
    for label in columns or factors:
        col = columns.get(label)
        col_levels = array_levels[col - 1] if col and array_levels else None
        if label in factors:
            values = _levels(an, label)
            units = _units(ds, label)
            role = "factor"
            if col_levels and len(values) < col_levels:
                dummy = ", ".join(
                    f"{j + 1} → {j % len(values) + 1}" for j in range(len(values), col_levels)
                )
                role = f"factor, dummy level (column level → factor level: {dummy})"
            shown = ", ".join(_value(v, "") for v in values.values()) + (
                f" {units}" if units else ""
            )
        elif label in pairs:
            role, shown = f"interaction {pairs[label][0]} x {pairs[label][1]}", ""
        elif label in errors:
            role, shown = "error (empty column)", ""
        else:
            continue
        rows.append([col if col else "—", col_levels or "—", label, role, shown])
    lines += [_table(["column", "levels", "assigned", "role", "values"], rows), ""]
    return lines


def _array_levels(name: str) -> list[int] | None:
    try:
        return [int(v) for v in orthogonal_array(name).max(axis=0) + 1]
    except ValueError:
        return None


def _runs(view: xr.Dataset, an: xr.Dataset, responses: list[str]) -> list[str]:
    n = view.sizes["run"]
    lines = ["## Runs", ""]
    if n > MAX_RUN_ROWS:
        return [*lines, f"{n} runs: see `results.nc`.", ""]
    factors = taguchi.factor_names(view)
    means = [taguchi.mean_name(view, r) for r in responses]
    header = ["run"] + [_label(f, _units(view, f)) for f in factors]
    header += [_label(r, _units(view, m)) for r, m in zip(responses, means, strict=True)]
    rows = []
    for i in range(n):
        row: list[Any] = [i + 1]
        row += [_value(_levels(an, f)[int(view[f"{f}_level"].values[i])], "") for f in factors]
        row += [_num(float(view[m].values[i])) for m in means]
        rows.append(row)
    note = (
        ["Responses with replicates are shown as the mean over the replicates.", ""]
        if any(m != r for r, m in zip(responses, means, strict=True))
        else []
    )
    return [*lines, _table(header, rows), "", *note]


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
                *[_num(float(k)) for k in row.k.values[:nlevels]],
                _num(float(row.R)),
                int(row["rank"]),
                _level_text(an, f, int(row.best_level)),
            ]
        )
    return header, rows


def _anova_lines(view: xr.Dataset, an: xr.Dataset, name: str, units: str) -> list[str]:
    r = an.sel(response=name)
    rows = [
        [f"{source} (pooled)" if pooled else str(source), _num(float(ss)), int(dof),
         _num(float(ms)), _num(float(f)), _num(float(p), 3), _pct(float(c))]
        for source, ss, dof, ms, f, p, c, pooled in zip(
            an["source"].values, r.SS.values, r.dof.values, r.MS.values, r.F.values,
            r.P.values, r.contribution.values, r.pooled.values, strict=True,
        )
    ]  # fmt: skip
    squared = f"{units}²" if units.isalpha() else f"({units})²"
    header = ["source", _label("SS", squared if units != "1" else ""), "dof", "MS", "F", "P", "%"]
    pooled = [str(t) for t, p in zip(an["source"].values, r.pooled.values, strict=True) if p]
    pooling = f"Pooled into error: {', '.join(pooled)}." if pooled else "No term pooled into error."
    errors = json.loads(view.attrs.get("error_columns", "[]"))
    source = (
        f"Error from the empty column(s) {', '.join(errors)}"
        if errors
        else "Error from the dof the terms leave"
    )
    note = str(r.anova_note.values)
    return [_table(header, rows), "", f"{source}. {pooling} {note}".rstrip(), ""]


def _decomposition_lines(an: xr.Dataset, name: str) -> list[str]:
    if "first_order" not in an or not np.isfinite(an.first_order.sel(response=name)).any():
        return []
    frame = decomposition_frame(an, name)
    rows = [
        [source, _num(row["SS"]), _pct(row["share %"]), _num(row["S1"], 3), _num(row["ST"], 3)]
        for source, row in frame.iterrows()
    ]
    return [
        "### Variance decomposition (computer experiment)",
        "",
        _table(["source", "SS", "%", "S1", "ST"], rows),
        "",
        f"{NO_NOISE} S1 and ST are the first-order and total Sobol indices over the grid.",
        "",
    ]


def _response(view: xr.Dataset, an: xr.Dataset, response: str, figures: set[str]) -> list[str]:
    mean = taguchi.mean_name(view, response)
    r = an.sel(response=mean)
    units, sense = str(r.units.values), str(r.sense.values)
    lines = [
        f"## {response}: {_label(str(r.long_name.values), units)}",
        "",
        f"{sense.capitalize()} is better. k_i = mean at level i.",
        "",
        "### Range analysis",
        "",
    ]
    header, rows = _range_rows(view, an, mean)
    lines += [_table(header, rows), ""]
    lines += _figure(f"main_effects_{response}.png", f"Main effects on {response}", figures)
    lines += ["### ANOVA", "", *_anova_lines(view, an, mean, units)]
    lines += _decomposition_lines(an, mean)
    lines += _figure(plots.map_png(response), f"Map of {response}", figures)
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
         _num(float(r.interaction_SS.values[i])), int(r.interaction_dof.values[i]),
         _num(float(r.interaction_F.values[i])), _num(float(r.interaction_P.values[i]), 3),
         _pct(float(r.interaction_contribution.values[i]))]
        for i, name in enumerate(an["interaction"].values)
    ]  # fmt: skip
    lines = ["### Interactions", "", _table(["interaction", "SS", "dof", "F", "P", "%"], rows), ""]
    units = str(r.units.values)
    pairs = zip(an["interaction_a"].values, an["interaction_b"].values, strict=True)
    for i, (a, b) in enumerate(pairs):
        means = r.interaction_mean.values[i]
        la = np.flatnonzero(np.isfinite(means).any(axis=1)).tolist()
        lb = np.flatnonzero(np.isfinite(means).any(axis=0)).tolist()
        va, vb = _levels(an, a), _levels(an, b)
        ua, ub = _units(view, a), _units(view, b)
        head = [f"{a} \\ {b}", *[_value(vb[j], ub) for j in lb]]
        body = [[_value(va[i_a], ua), *[_num(float(means[i_a, j])) for j in lb]] for i_a in la]
        lines += [f"{_label(f'Mean {response}', units)} by level of {a} and {b}:", ""]
        lines += [_table(head, body), ""]
        lines += _figure(plots.interaction_png(response, a, b), f"{a} x {b}", figures)
    return lines


def _constant(view: xr.Dataset, response: str, figures: set[str]) -> list[str]:
    y = view[taguchi.mean_name(view, response)]
    units = str(y.attrs.get("units", ""))
    finite = y.values[np.isfinite(y.values)]
    value = _value(float(finite[0]), units if units != "1" else "") if finite.size else "—"
    return [
        f"## {response}: {_label(str(y.attrs.get('long_name', response)), units)}",
        "",
        f"Does not vary over the runs ({value} in every run with a value): nothing to analyse.",
        "",
        *_figure(f"main_effects_{response}.png", f"Main effects on {response}", figures),
    ]


def _sn_lines(view: xr.Dataset, an: xr.Dataset, response: str, figures: set[str]) -> list[str]:
    sn = taguchi.sn_name(response)
    n = int(an["observations"].sel(response=sn))
    kind = str(an["sn_kind"].sel(response=sn).values)
    lines = [
        "### Signal-to-noise ratio",
        "",
        (f"S/N ({kind} is better) in dB over {n} observation(s) per run; larger S/N is better."),
        "",
    ]
    if n == 1:
        lines[-2] += " With one observation per run the S/N is a log transform of the response."
    header, rows = _range_rows(view, an, sn)
    lines += [_table(header, rows), ""]
    p = prediction(an, sn)
    lines += [
        f"Predicted S/N at its best levels: {_num(p.mean)} dB"
        + (
            f" ± {_num(p.half_width)} dB ({100 * (1 - p.alpha):g} % confidence)."
            if np.isfinite(p.half_width)
            else "."
        ),
        "",
    ]
    lines += _figure(plots.sn_png(response), f"S/N ratio of {response}", figures)
    return lines


def _optimum_levels(an: xr.Dataset, name: str) -> dict[str, int]:
    r = an.sel(response=name)
    return {
        str(t): int(level)
        for t, level, factor in zip(
            an["term"].values, r.optimum_level.values, an["is_factor"].values, strict=True
        )
        if factor
    }


def prediction(an: xr.Dataset, name: str) -> taguchi.Prediction:
    """The predicted optimum of ``name`` as the analysis Dataset holds it."""
    r = an.sel(response=name)
    terms = str(r.model_terms.values)
    return taguchi.Prediction(
        response=name,
        units=str(r.units.values),
        sense=str(r.sense.values),
        levels=_optimum_levels(an, name),
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
    p = prediction(an, name)
    rows = [
        [f, p.levels[f] + 1, _value(_levels(an, f)[p.levels[f]], _units(view, f))]
        for f in taguchi.factor_names(view)
    ]
    units = f" {p.units}" if p.units and p.units != "1" else ""
    level = f"{100 * (1 - p.alpha):g} %"
    lines = ["### Predicted optimum", "", _table(["factor", "level", "value"], rows), ""]
    lines.append(
        f"Predicted {_shown(view, response)} at these levels: **{_num(p.mean)}{units}** "
        f"(grand mean {_num(p.grand_mean)}{units}; model terms {', '.join(p.terms) or 'none'})."
    )
    if np.isfinite(p.half_width):
        lo, hi = p.interval
        clo, chi = p.confirmation_interval
        lines.append(
            f"{level} confidence interval of the mean: {_num(lo)} … {_num(hi)}{units} "
            f"(± {_num(p.half_width)}; n_eff = {_num(p.n_eff)}, V_e = {_num(p.error_ms)} with "
            f"{p.error_dof} dof). A confirmation run should fall in {_num(clo)} … "
            f"{_num(chi)}{units} (± {_num(p.confirmation_half_width)}, "
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


def _observed(view: xr.Dataset, p: taguchi.Prediction, units: str) -> list[str]:
    """The run that already holds the predicted combination (every one does in a full
    factorial), as a check on the additive model."""
    hit = np.ones(view.sizes["run"], dtype=bool)
    for f, level in p.levels.items():
        hit &= view[f"{f}_level"].values == level
    runs = np.flatnonzero(hit)
    if runs.size == 0:
        return []
    y = view[p.response].values[runs]
    shown = ", ".join(
        f"{_num(float(v))}{units} (run {i + 1})" for i, v in zip(runs, y, strict=True)
    )
    return [f"Observed at these levels: {shown}. The prediction is the additive model's."]


def _tradeoff(
    an: xr.Dataset, view: xr.Dataset, names: list[str]
) -> tuple[list[str], dict[str, int]]:
    shown = {taguchi.mean_name(view, r): r for r in json.loads(an.attrs["responses"])}
    factors = taguchi.factor_names(view)
    lines = [
        "## Trade-off summary",
        "",
        (
            "Best level of each factor for each response, with the factor's contribution to that "
            "response's variation. Where the responses disagree, the chosen level is the best one "
            "for the response the factor contributes most to."
        ),
        "",
    ]
    header = ["response", "better", *factors]
    rows = []
    for m in names:
        r = an.sel(response=m)
        cells = [
            f"{int(r.optimum_level.sel(term=f)) + 1} "
            f"({_pct(float(r.contribution.sel(source=f)))} %)"
            for f in factors
        ]
        rows.append([shown.get(m, m), str(r.sense.values), *cells])
    chosen = {f: int(an["chosen_level"].sel(term=f)) for f in factors}
    rows.append(["**chosen level**", "", *[_level_text(an, f, chosen[f]) for f in factors]])
    rows.append(
        [
            "decided by",
            "",
            *[shown.get(str(v), str(v)) for v in an["decided_by"].sel(term=factors).values],
        ]
    )
    rows.append(
        ["conflict", "", *["yes" if c else "no" for c in an["conflict"].sel(term=factors).values]]
    )
    lines += [_table(header, rows), ""]
    rows = []
    for m in names:
        r = an.sel(response=m)
        units = str(r.units.values)
        rows.append(
            [shown.get(m, m), str(r.sense.values), _num(float(r.predicted)),
             _num(float(r.compromise)), _num(float(r.compromise_half_width)),
             units if units != "1" else ""]
        )  # fmt: skip
    lines += [
        "Predicted mean of each response at its own optimum and at the chosen levels:",
        "",
        _table(["response", "better", "own optimum", "chosen levels", "± (CI)", "units"], rows),
        "",
    ]
    return lines, chosen


def _sweep(ds: xr.Dataset, responses: list[str], figures: set[str]) -> list[str]:
    lines = ["## Sweep", "", "One factor at a time; the others stay at their base levels.", ""]
    for f in taguchi.factor_names(ds):
        part = sweep_runs(ds, f)
        header = [_label(f, _units(ds, f))] + [_label(r, _units(ds, r)) for r in responses]
        rows = [
            [_value(part[f].values[i], ""), *[_num(float(part[r].values[i])) for r in responses]]
            for i in range(part.sizes["run"])
        ]
        lines += [f"### {f}", "", _table(header, rows), ""]
    for r in responses:
        lines += _figure(f"sweep_{r}.png", f"Sweep: {r}", figures)
    return lines
