"""``report.md``: a run's analysis as Markdown that can be pasted into a design review.

Sections: the study and run; the design (array, column assignment with dummy levels,
interaction and error columns); the runs; per response the range analysis, the ANOVA (pooling
always stated), interaction effects, S/N ratios and the predicted optimum with its confidence
interval; a trade-off summary when there are several responses; the confirmation run as a
study file (also written to ``confirmation.toml`` when the study text is known). Figures are
linked by file name, only those that were written. Sweeps get their tables and figures.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import xarray as xr

from studies import plots, taguchi
from studies.analysis import has_values, range_analysis, sweep_runs
from studies.designs import orthogonal_array

REPORT_NAME = "report.md"
CONFIRMATION_NAME = "confirmation.toml"
MAX_RUN_ROWS = 100  # runs listed in full; larger designs point to results.nc


def write_report(
    ds: xr.Dataset, folder: Path, responses: Sequence[str], figures: Sequence[Path] = ()
) -> list[Path]:
    """Write ``report.md`` (and ``confirmation.toml`` for array and factorial runs with the
    study text) into ``folder``; return the paths, report first."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    text, confirmation = _report(ds, list(responses), {Path(f).name for f in figures})
    path = folder / REPORT_NAME
    path.write_text(text, encoding="utf-8")
    paths = [path]
    if confirmation and ds.attrs.get("study_toml"):
        paths.append(folder / CONFIRMATION_NAME)
        paths[-1].write_text(confirmation, encoding="utf-8")
    return paths


def report_text(ds: xr.Dataset, responses: Sequence[str], figures: Sequence[str] = ()) -> str:
    """The Markdown text of :func:`write_report` (``figures``: file names that exist)."""
    return _report(ds, list(responses), {Path(f).name for f in figures})[0]


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


def _level_text(ds: xr.Dataset, factor: str, level: int) -> str:
    """1-based level number and the factor's value: ``2 (9 deg)``."""
    value = taguchi.level_values(ds, factor)[level]
    return f"{level + 1} ({_value(value, _units(ds, factor))})"


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
def _report(ds: xr.Dataset, responses: list[str], figures: set[str]) -> tuple[str, str]:
    lines = _header(ds, responses)
    responses = [r for r in responses if has_values(ds, r)]
    if ds.attrs.get("design") == "sweep":
        lines += _sweep(ds, responses, figures)
        lines += _other_figures(lines, figures)
        return "\n".join(lines).rstrip() + "\n", ""
    view = taguchi.with_sn(taguchi.with_means(ds, responses), taguchi.sn_responses(ds, responses))
    lines += _design(ds)
    lines += _runs(view, responses)
    optima = {}
    for r in responses:
        if taguchi.varies(view, taguchi.mean_name(view, r)):
            section, optima[r] = _response(view, r, figures)
        else:
            section = _constant(view, r, figures)
        lines += section
    levels = next(iter(optima.values())).levels if optima else {}
    if len(optima) > 1:
        section, levels = _tradeoff(view, list(optima))
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


def _header(ds: xr.Dataset, responses: list[str]) -> list[str]:
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
            + ("" if has_values(ds, r) else ", NaN in every run: not analysed")
            + ")"
        )
    rows.append(("responses", "; ".join(shown)))
    return [f"# {title}", "", _table(["", ""], rows), ""]


def _design(ds: xr.Dataset) -> list[str]:
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
            values = taguchi.level_values(ds, label)
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


def _runs(view: xr.Dataset, responses: list[str]) -> list[str]:
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
        row += [
            _value(taguchi.level_values(view, f)[int(view[f"{f}_level"].values[i])], "")
            for f in factors
        ]
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


def _range_rows(ds: xr.Dataset, response: str) -> tuple[list[str], list[list[Any]]]:
    ra = range_analysis(ds, response)
    nlevels = ra.sizes["level"]
    header = ["factor", *[f"k{i + 1}" for i in range(nlevels)], "R", "rank", "best level"]
    rows = []
    for f in ra.factor.values:
        r = ra.sel(factor=f)
        rows.append(
            [
                f,
                *[_num(float(k)) for k in r.k.values],
                _num(float(r.R)),
                int(r["rank"]),
                _level_text(ds, str(f), int(r.best_level)),
            ]
        )
    return header, rows


def _anova_lines(table: pd.DataFrame, units: str) -> list[str]:
    rows = []
    for source, row in table.iterrows():
        name = f"{source} (pooled)" if row["pooled"] else str(source)
        rows.append(
            [
                name,
                _num(row["SS"]),
                int(row["dof"]),
                _num(row["MS"]),
                _num(row["F"]),
                _num(row["P"], 3),
                _pct(row["contribution"]),
            ]
        )
    squared = f"{units}²" if units.isalpha() else f"({units})²"
    header = ["source", _label("SS", squared if units != "1" else ""), "dof", "MS", "F", "P", "%"]
    pooled = table.attrs.get("pooled", [])
    pooling = f"Pooled into error: {', '.join(pooled)}." if pooled else "No term pooled into error."
    errors = table.attrs.get("error_columns", [])
    source = (
        f"Error from the empty column(s) {', '.join(errors)}"
        if errors
        else "Error from the dof the terms leave"
    )
    note = table.attrs.get("note", "")
    return [_table(header, rows), "", f"{source}. {pooling} {note}".rstrip(), ""]


def _response(view: xr.Dataset, response: str, figures: set[str]) -> tuple[list[str], Any]:
    mean = taguchi.mean_name(view, response)
    y = view[mean]
    units = str(y.attrs.get("units", ""))
    sense = str(y.attrs.get("better", "smaller"))
    lines = [
        f"## {response}: {_label(str(y.attrs.get('long_name', response)), units)}",
        "",
        f"{sense.capitalize()} is better. k_i = mean at level i.",
        "",
        "### Range analysis",
        "",
    ]
    header, rows = _range_rows(view, mean)
    lines += [_table(header, rows), ""]
    lines += _figure(f"main_effects_{response}.png", f"Main effects on {response}", figures)
    table = taguchi.anova_table(view, mean)
    lines += ["### ANOVA", "", *_anova_lines(table, units)]
    pairs = taguchi.interaction_pairs(view)
    if pairs:
        lines += ["### Interactions", ""]
        inter = taguchi.interaction_anova(table, view)
        rows = [
            [f"{name} (pooled)" if r["pooled"] else name, _num(r["SS"]), int(r["dof"]),
             _num(r["F"]), _num(r["P"], 3), _pct(r["contribution"])]
            for name, r in inter.iterrows()
        ]  # fmt: skip
        lines += [_table(["interaction", "SS", "dof", "F", "P", "%"], rows), ""]
        for a, b in pairs:
            means = taguchi.interaction_means(view, mean, a, b)
            ua, ub = _units(view, a), _units(view, b)
            head = [f"{a} \\ {b}", *[_value(v, ub) for v in means[b].values]]
            body = [
                [_value(va, ua), *[_num(float(v)) for v in means.values[i]]]
                for i, va in enumerate(means[a].values)
            ]
            lines += [f"{_label(f'Mean {response}', units)} by level of {a} and {b}:", ""]
            lines += [_table(head, body), ""]
            lines += _figure(plots.interaction_png(response, a, b), f"{a} x {b}", figures)
    if taguchi.sn_name(response) in view:
        lines += _sn_lines(view, response, figures)
    optimum = taguchi.predict_optimum(view, mean)
    lines += _optimum_lines(view, optimum, response)
    return lines, optimum


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


def _sn_lines(view: xr.Dataset, response: str, figures: set[str]) -> list[str]:
    sn = taguchi.sn_name(response)
    attrs = view[sn].attrs
    n = int(attrs["observations"])
    lines = [
        "### Signal-to-noise ratio",
        "",
        (
            f"S/N ({attrs['sn_kind']} is better) in dB over {n} observation(s) per run; "
            "larger S/N is better."
        ),
        "",
    ]
    if n == 1:
        lines[-2] += " With one observation per run the S/N is a log transform of the response."
    header, rows = _range_rows(view, sn)
    lines += [_table(header, rows), ""]
    optimum = taguchi.predict_optimum(view, sn)
    lines += [
        f"Predicted S/N at its best levels: {_num(optimum.mean)} dB"
        + (
            f" ± {_num(optimum.half_width)} dB ({100 * (1 - optimum.alpha):g} % confidence)."
            if np.isfinite(optimum.half_width)
            else "."
        ),
        "",
    ]
    lines += _figure(plots.sn_png(response), f"S/N ratio of {response}", figures)
    return lines


def _optimum_lines(view: xr.Dataset, p: taguchi.Prediction, response: str) -> list[str]:
    rows = [
        [f, p.levels[f] + 1, _value(taguchi.level_values(view, f)[p.levels[f]], _units(view, f))]
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


def _tradeoff(view: xr.Dataset, responses: list[str]) -> tuple[list[str], dict[str, int]]:
    means = {taguchi.mean_name(view, r): r for r in responses}
    result = taguchi.tradeoff(view, list(means))
    t = result.table
    factors = [str(f) for f in t.index]
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
    rows = [
        [r, view[m].attrs.get("better", "smaller"),
         *[f"{int(taguchi.number(t, f, f'best {m}'))} "
           f"({_pct(taguchi.number(t, f, f'% {m}'))} %)" for f in factors]]
        for m, r in means.items()
    ]  # fmt: skip
    chosen = [_level_text(view, f, result.levels[f]) for f in factors]
    rows.append(["**chosen level**", "", *chosen])
    rows.append(["decided by", "", *[means[str(t.loc[f, "decided by"])] for f in factors]])
    rows.append(["conflict", "", *["yes" if t.loc[f, "conflict"] else "no" for f in factors]])
    lines += [_table(header, rows), ""]
    rows = [
        [means[str(m)], p["sense"], _num(p["own optimum"]), _num(p["compromise"]),
         _num(p["half width"]), p["units"] if p["units"] != "1" else ""]
        for m, p in result.predictions.iterrows()
    ]  # fmt: skip
    lines += [
        "Predicted mean of each response at its own optimum and at the chosen levels:",
        "",
        _table(["response", "better", "own optimum", "chosen levels", "± (CI)", "units"], rows),
        "",
    ]
    return lines, result.levels


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
