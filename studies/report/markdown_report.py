"""``report.md``: a run's analysis as Markdown that can be pasted into a design review.

Sections: the study and run; the design (array, column assignment with dummy levels,
interaction and error columns, each factor's role: control or operating condition); the runs;
per response the range analysis, the ANOVA (pooling always stated), interaction effects, the
variance decomposition of a full factorial, S/N ratios and the optimum (a full factorial's best
computed point with its neighbours, an array's predicted optimum with its confidence interval;
per operating condition); a trade-off summary when there are several responses; for an array
the confirmation run as a study file (``confirmation.toml``), for a full factorial a finer grid
around the best point (``refinement.toml``), both written when the study text is known.
Figures are linked by file name, only those that were written. Sweeps get their tables and
figures.

A renderer: every number comes from the results or from the analysis Dataset
(:func:`studies.analysis.analyze.analyze`); nothing here computes a statistic.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from studies.analysis import confirmation, taguchi
from studies.analysis.missing import nothing_to_analyse
from studies.analysis.statistics import sense_words, sweep_runs
from studies.common.text_safety import Markup, code_span, fence, md_escape
from studies.define.designs import orthogonal_array
from studies.define.sampling import SAMPLING_DESIGNS
from studies.report.markdown_format import (
    figure,
    label,
    levels_of,
    num,
    other_figures,
    table,
    units_of,
    value_text,
)
from studies.report.markdown_response import constant_section, response_section
from studies.report.markdown_terms import computed, optimum_levels
from studies.report.markdown_tradeoff import tradeoff_section
from studies.report.text import status_line
from studies.report.uncertainty.noise_report import robust_markdown
from studies.report.uncertainty.sample_report import sample_markdown
from studies.report.uncertainty.sobol_report import sobol_markdown

REPORT_NAME = "report.md"
CONFIRMATION_NAME = "confirmation.toml"
REFINEMENT_NAME = "refinement.toml"
MAX_RUN_ROWS = 100  # runs listed in full; larger designs point to results.nc


def write_report(
    ds: xr.Dataset,
    an: xr.Dataset,
    folder: Path,
    responses: Sequence[str],
    figures: Sequence[Path] = (),
) -> list[Path]:
    """Write ``report.md`` (and, with the study text, ``confirmation.toml`` for an array or
    ``refinement.toml`` for a full factorial) into ``folder``; return the paths, report first.
    ``an`` is the analysis of ``ds`` (:func:`studies.analysis.analyze.analyze`)."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    text, study = _report(ds, an, list(responses), {Path(f).name for f in figures})
    path = folder / REPORT_NAME
    path.write_text(text, encoding="utf-8")
    paths = [path]
    if study and ds.attrs.get("study_toml"):
        paths.append(folder / (REFINEMENT_NAME if computed(an) else CONFIRMATION_NAME))
        paths[-1].write_text(study, encoding="utf-8")
    return paths


def report_text(
    ds: xr.Dataset, an: xr.Dataset, responses: Sequence[str], figures: Sequence[str] = ()
) -> str:
    """The Markdown text of :func:`write_report` (``figures``: file names that exist)."""
    return _report(ds, an, list(responses), {Path(f).name for f in figures})[0]


# --- sections -----------------------------------------------------------------------------------
def _report(
    ds: xr.Dataset, an: xr.Dataset, responses: list[str], figures: set[str]
) -> tuple[str, str]:
    analysed = json.loads(an.attrs.get("analysed", "[]"))
    status = json.loads(an.attrs.get("status_responses", "[]"))
    lines = _header(ds, responses, analysed, status)
    without = int(an.attrs.get("points_without_value", 0))
    if without:
        note = (
            f"**{without} of {an.attrs['points']} design points gave no value for any "
            "response**: they did not run (the reasons are in `analysis.txt`). The tables "
            "below use the others."
        )
        lines += [note, ""]
    if status:
        lines += [f"- {md_escape(status_line(an, r))}" for r in status] + [""]
    listed = [  # an analysed response has finite values: nothing to read
        r
        for r in responses
        if r not in status and (taguchi.mean_name(ds, r) in analysed or _has_value(ds, r))
    ]
    responses = [r for r in responses if taguchi.mean_name(ds, r) in analysed]
    if ds.attrs.get("design") == "sweep":
        lines += _sweep(ds, responses, figures)
        lines += other_figures(lines, figures)
        return "\n".join(lines).rstrip() + "\n", ""
    if ds.attrs.get("design") in SAMPLING_DESIGNS:
        saltelli = ds.attrs.get("design") == "saltelli"
        lines += sobol_markdown(an, figures) if saltelli else sample_markdown(an, figures)
        lines += other_figures(lines, figures)
        return "\n".join(lines).rstrip() + "\n", ""
    view = ds.assign({n: an[n] for n in an.data_vars if "run" in an[n].dims})
    lines += _design(view, an)
    lines += _runs(view, an, listed)
    lines += robust_markdown(ds, an, figures)
    optimised = []
    for r in responses:
        name = taguchi.mean_name(view, r)
        if int(an["varies"].sel(response=name)):
            lines += response_section(view, an, r, figures)
            optimised.append(name)
        else:
            lines += constant_section(view, r, figures)
    optimised = [n for n in optimised if np.isfinite(float(an["optimum_value"].sel(response=n)))]
    levels = optimum_levels(an, optimised[0]) if optimised else {}
    if len(optimised) > 1:
        section, levels = tradeoff_section(an, view, optimised)
        lines += section
    several = len(optimised) > 1
    toml, section = _next_study(ds, view, an, levels, several) if optimised else ("", [])
    lines += section
    lines += other_figures(lines, figures)
    return "\n".join(lines).rstrip() + "\n", toml


VALUE_BLOCK = 1 << 16  # runs read at a time while looking for a response's first value


def _has_value(ds: xr.Dataset, response: str) -> bool:
    """Whether ``response`` has a value (finite or ±inf) in some run: a column of the runs
    table even when the analysis has nothing to analyse (inf in every run). Read a block of
    runs at a time, up to the first value (not the whole response)."""
    y = ds[response]
    if y.dtype.kind != "f":
        return True
    runs = ds.sizes["run"]
    return any(
        bool((~np.isnan(y.isel(run=slice(start, start + VALUE_BLOCK)).values)).any())
        for start in range(0, runs, VALUE_BLOCK)
    )


def _next_study(
    ds: xr.Dataset, view: xr.Dataset, an: xr.Dataset, levels: dict[str, int], several: bool
) -> tuple[str, list[str]]:
    """The confirmation run of an array, or the refinement grid of a full factorial: the study
    text and the report's section on it (``several``: the levels are a trade-off's)."""
    written = bool(ds.attrs.get("study_toml"))
    if computed(an):
        flat = [f for f in levels if not (an["R"].sel(term=f).values > 0).any()]
        toml = confirmation.refinement_toml(view, levels, flat)
        if not toml:
            return "", []
        intro = (
            "Every combination was computed, so there is nothing to confirm. The study below "
            "is a finer grid around the chosen levels (5 levels between the neighbours of each "
            "numeric control factor that has an effect, reaching one step past the edge of the "
            "grid where the chosen level is at an edge, as its comment lines say; operating "
            "conditions at all their levels)"
            + (f", also written to `{REFINEMENT_NAME}`." if written else ".")
        )
        title = "## Refinement around the best point"
    else:
        toml = confirmation.confirmation_toml(view, levels)
        intro = (
            "The study below runs the chosen levels once"
            + (" in every operating condition. " if confirmation.operating_factors(view) else ". ")
            + (
                f"It is also written to `{CONFIRMATION_NAME}` in the run folder: run it with "
                f"`python -m studies run <run folder>/{CONFIRMATION_NAME}` and compare the "
                + (
                    "results with the trade-off's confirmation intervals above (at these levels)."
                    if several
                    else "result with the confirmation interval above."
                )
                if written
                else "Add it to the study's other tables to run it."
            )
        )
        title = "## Confirmation run"
    return toml, [title, "", intro, "", f"{fence(toml)}toml", toml.rstrip(), fence(toml), ""]


def _header(
    ds: xr.Dataset, responses: list[str], analysed: list[str], status: list[str]
) -> list[str]:
    a = ds.attrs
    title = a.get("title") or a.get("study_name") or "Study results"
    commit = str(a.get("git_commit", ""))[:10]
    rows = [
        ("study", code_span(a["study_name"]) if a.get("study_name") else "—"),
        ("run", code_span(a["run_id"]) if a.get("run_id") else "—"),
        (
            "design",
            Markup(
                f"{md_escape(str(a.get('design', '?')))}, {ds.sizes['run']} runs, numbered from "
                f"1 here (run k is index k − 1 of {code_span('run')} in results.nc)"
            ),
        ),
        ("scene", a.get("scene", "—")),
        ("commit", (commit + (" (dirty)" if a.get("git_dirty") else "")) or "—"),
        ("created", a.get("created", "—")),
    ]
    shown = []
    for r in responses:
        y = ds[r]
        sense = y.attrs.get("better")
        shown.append(
            f"{md_escape(r)} ({label(str(y.attrs.get('long_name', r)), units_of(ds, r))}"
            + (f", {md_escape(sense_words(sense))}" if sense else "")
            + (
                ""
                if taguchi.mean_name(ds, r) in analysed
                else ", a status code: counted below, never averaged"
                if r in status
                else f", {nothing_to_analyse(y)}: not analysed"
            )
            + ")"
        )
    rows.append(("responses", Markup("; ".join(shown))))
    return [f"# {md_escape(title)}", "", table(["", ""], rows), ""]


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
        lines += [f"Orthogonal array {md_escape(name)}, {ds.sizes['run']} runs.", ""]
    rows = []
    pairs = taguchi.interaction_columns(ds)
    errors = json.loads(ds.attrs.get("error_columns", "[]"))
    array_levels = _array_levels(name)
    for entry in columns or factors:
        col = columns.get(entry)
        col_levels = array_levels[col - 1] if col and array_levels else None
        if entry in factors:
            values = levels_of(an, entry)
            units = units_of(ds, entry)
            role = {"operating": "operating condition", "model": "model rung"}.get(
                str(an["term_role"].sel(term=entry).values), "factor"
            )
            if col_levels and len(values) < col_levels:
                dummy = ", ".join(
                    f"{j + 1} → {j % len(values) + 1}" for j in range(len(values), col_levels)
                )
                role = f"{role}, dummy level (column level → factor level: {dummy})"
            shown = Markup(
                ", ".join(value_text(v, "") for v in values.values())
                + (f" {md_escape(units)}" if units and units != "1" else "")
            )
        elif entry in pairs:
            role, shown = f"interaction {pairs[entry][0]} x {pairs[entry][1]}", Markup()
        elif entry in errors:
            role, shown = "error (empty column)", Markup()
        else:
            continue
        rows.append([col if col else "—", col_levels or "—", entry, role, shown])
    lines += [table(["column", "levels", "assigned", "role", "values"], rows), ""]
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
    header = ["run"] + [label(f, units_of(view, f)) for f in factors]
    header += [label(r, units_of(view, m)) for r, m in zip(responses, means, strict=True)]
    rows = []
    for i in range(n):
        row: list[Any] = [i + 1]
        row += [
            value_text(levels_of(an, f)[int(view[f"{f}_level"].values[i])], "") for f in factors
        ]
        row += [num(float(view[m].values[i])) for m in means]
        rows.append(row)
    note = (
        ["Responses with replicates or noise are shown as the mean over them.", ""]
        if any(m != r for r, m in zip(responses, means, strict=True))
        else []
    )
    return [*lines, table(header, rows), "", *note]


def _sweep(ds: xr.Dataset, responses: list[str], figures: set[str]) -> list[str]:
    lines = ["## Sweep", "", "One factor at a time; the others stay at their base levels.", ""]
    for f in taguchi.factor_names(ds):
        part = sweep_runs(ds, f)
        header = [label(f, units_of(ds, f))] + [label(r, units_of(ds, r)) for r in responses]
        rows = [
            [value_text(part[f].values[i], ""), *[num(float(part[r].values[i])) for r in responses]]
            for i in range(part.sizes["run"])
        ]
        lines += [f"### {md_escape(f)}", "", table(header, rows), ""]
    for r in responses:
        lines += figure(f"sweep_{r}.png", f"Sweep: {r}", figures)
    return lines
