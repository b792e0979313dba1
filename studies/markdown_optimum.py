"""The report's optimum and trade-off sections, read from the analysis Dataset.

A full factorial computed every combination: its section is the **best computed point** (run
and value, its neighbours, no model interval). An orthogonal array did not: its section is
Taguchi's **predicted optimum** (additive model, the runs it rests on, confidence intervals).
Operating factors are never chosen: values are given per operating condition, with the worst
and the mean over them (:mod:`studies.analysis_optimum`).
"""

from __future__ import annotations

import json
import math
from typing import Any

import numpy as np
import xarray as xr

from studies import taguchi
from studies.analysis_optimum import COMPUTED
from studies.markdown_format import level_text, levels_of, num, pct, table, units_of, value_text
from studies.text_safety import Markup, md_escape

MAX_CONDITION_ROWS = 12  # operating conditions listed one per row; more: see analysis.nc
MAX_LISTED_RUNS = 12  # runs named per level in "rests on runs …"


def computed(an: xr.Dataset) -> bool:
    return an.attrs.get("optimum_basis") == COMPUTED


def optimum_levels(an: xr.Dataset, name: str) -> dict[str, int]:
    """Control factor → its chosen level (0-based) for ``name``."""
    r = an.sel(response=name)
    return {
        str(t): int(level)
        for t, level, role in zip(
            an["term"].values, r.optimum_level.values, an["term_role"].values, strict=True
        )
        if role == "control" and level >= 0
    }


def _control(an: xr.Dataset) -> list[str]:
    return [str(t) for t, role in zip(an["term"].values, an["term_role"].values, strict=True)
            if role == "control"]  # fmt: skip


def _operating(an: xr.Dataset) -> list[str]:
    return list(json.loads(an.attrs.get("operating_factors", "[]")))


def _units(r: xr.Dataset) -> Markup:
    """`` <units>`` (Markdown, escaped); nothing for a dimensionless "1"."""
    units = str(r.units.values)
    return Markup(f" {md_escape(units)}" if units and units != "1" else "")


def _run(index: int) -> str:
    return f"run {index + 1}"


def _worst_condition(an: xr.Dataset, at: np.ndarray, sense: str) -> str:
    if not np.isfinite(at).any():
        return ""
    i = int(np.nanargmax(at) if sense == "smaller" else np.nanargmin(at))
    return str(an["condition"].values[i])


def _levels_table(view: xr.Dataset, an: xr.Dataset, levels: dict[str, int]) -> list[str]:
    if not levels:
        return ["Every factor is an operating condition: there are no levels to choose.", ""]
    rows = [
        [f, level + 1, value_text(levels_of(an, f)[level], units_of(view, f))]
        for f, level in levels.items()
    ]
    lines = [table(["factor", "level", "value"], rows), ""]
    operating = _operating(an)
    if operating:
        lines += [
            (
                f"Operating conditions, not chosen: {md_escape(', '.join(operating))} (every level "
                "is a case "
                "the design must meet)."
            ),
            "",
        ]
    return lines


def _levels_of_run(view: xr.Dataset, an: xr.Dataset, run: int) -> Markup:
    return Markup(
        ", ".join(
            f"{md_escape(f)} = {level_text(an, f, int(view[f'{f}_level'].values[run]))}"
            for f in _control(an)
        )
    )


def _conditions(view: xr.Dataset, an: xr.Dataset, r: xr.Dataset, units: str) -> list[str]:
    """Per operating condition: the value at the chosen levels and (grid) the best run there."""
    labels = an["condition"].values
    if len(labels) > MAX_CONDITION_ROWS:
        return [
            (
                f"{len(labels)} operating conditions: per condition in `analysis.nc` "
                "(`optimum_at`, `optimum_run`, `best_value`, `best_run`)."
            ),
            "",
        ]
    grid = computed(an) and bool(_control(an))
    header = ["condition", "at these levels" if _control(an) else "value"]
    header += ["best in this condition"] if grid else []
    rows = []
    for i, condition in enumerate(labels):
        run = int(r.optimum_run.values[i])
        at = num(float(r.optimum_at.values[i])) + units + (f" ({_run(run)})" if run >= 0 else "")
        row: list[Any] = [str(condition), Markup(at)]
        if grid:
            best = int(r.best_run.values[i])
            row.append(
                Markup(
                    f"{num(float(r.best_value.values[i]))}{units} ({_run(best)}: "
                    f"{_levels_of_run(view, an, best)})"
                )
                if best >= 0
                else "—"
            )
        rows.append(row)
    return [table(header, rows), ""]


def _over_conditions(an: xr.Dataset, r: xr.Dataset, units: str, what: str) -> str:
    sense = str(r.sense.values)
    worst = _worst_condition(an, r.optimum_at.values, sense)
    return (
        f"{what} over the {an.sizes['condition']} operating conditions: mean "
        f"**{num(float(r.optimum_value))}{units}**, worst **{num(float(r.optimum_worst))}{units}**"
        f" ({md_escape(worst)})."
    )


def optimum_section(view: xr.Dataset, an: xr.Dataset, name: str, shown: str) -> list[str]:
    """The best computed point (full factorial) or the predicted optimum (array) of ``name``."""
    r = an.sel(response=name)
    if not np.isfinite(float(r.optimum_value)):
        return []
    return _computed(view, an, r, shown) if computed(an) else _predicted(view, an, r, shown)


def _computed(view: xr.Dataset, an: xr.Dataset, r: xr.Dataset, shown: str) -> list[str]:
    units = _units(r)
    name = str(r.response.values)
    if not _control(an):
        lines = ["### Over the operating conditions", ""]
        lines += ["Every factor is an operating condition: there are no levels to choose.", ""]
        lines += [_over_conditions(an, r, units, "Computed"), ""]
        return lines + _conditions(view, an, r, units)
    lines = [
        "### Best computed point",
        "",
        (
            "Every combination of the levels was computed: this is the best run, not a "
            "prediction (no model, no interval)."
        ),
        "",
        *_levels_table(view, an, optimum_levels(an, name)),
    ]
    if an.sizes["condition"] == 1:
        run = int(r.optimum_run.values[0])
        lines += [_best_line(view, r, run, shown, units), ""]
    else:
        lines += [_over_conditions(an, r, units, "Chosen for the best mean"), ""]
        lines += _conditions(view, an, r, units)
    return lines + _neighbours(view, an, r, units)


def _bound_mark(view: xr.Dataset, name: str, run: int) -> str:
    """``: no value, counted at the bound`` when ``run`` has no value of ``name`` of its own
    (its response's ``none_means`` counted it at the best or worst value seen)."""
    own = float(view[name].values[run]) if name in view else math.nan
    return "" if np.isfinite(own) else ": no value, counted at the bound"


def _best_line(view: xr.Dataset, r: xr.Dataset, run: int, shown: str, units: str) -> str:
    """The best run's value, or, when that run has no value of its own, what it was counted
    as (``none_means``): a bound, never a computed value."""
    name = str(r.response.values)
    best = num(float(r.optimum_value))
    grand = f"grand mean {num(float(r.grand_mean))}{units}"
    if not _bound_mark(view, name, run):
        return f"Best {md_escape(shown)}: **{best}{units}** in {_run(run)} ({grand})."
    meaning = str(view[name].attrs.get("none_means", "unknown"))
    counted = (
        f"counted as at least as good as the best value computed, {best}{units}"
        if meaning == "best"
        else f"counted at the bound {best}{units}"
    )
    return (
        f"Best {md_escape(shown)}: {_run(run)}, which has **no value** of it (none_means = "
        f"{md_escape(meaning)}: {counted}; {grand}). Runs without a value tie with each "
        "other: the first in grid order is shown."
    )


def _neighbours(view: xr.Dataset, an: xr.Dataset, r: xr.Dataset, units: str) -> list[str]:
    levels = optimum_levels(an, str(r.response.values))
    if not levels:
        return []
    name = str(r.response.values)
    rows, edges = [], []
    for f, level in levels.items():
        cells = []
        for s, step in enumerate((-1, 1)):
            value = float(r.neighbour_value.sel(term=f).values[s])
            run = int(r.neighbour_run.sel(term=f).values[s])
            if not 0 <= level + step < len(levels_of(an, f)):
                cells.append("— (edge of the grid)")
                if len(levels_of(an, f)) > 1:
                    edges.append(f)
                continue
            if not np.isfinite(value):
                cells.append("— (no value there)")
                continue
            at = value_text(levels_of(an, f)[level + step], units_of(view, f))
            ran = f" ({_run(run)}{_bound_mark(view, name, run)})" if run >= 0 else ""
            cells.append(Markup(f"{num(value)}{units} at {at}{ran}"))
        rows.append([f, *cells])
    what = "" if an.sizes["condition"] == 1 else " (mean over the operating conditions)"
    lines = [
        f"Neighbours: one level away in one factor, the others at the optimum{what}:",
        "",
        table(["factor", "one level below", "one level above"], rows),
        "",
    ]
    if edges:
        lines += [
            (
                "The optimum lies at the edge of the grid in "
                f"{md_escape(', '.join(sorted(set(edges))))}: a "
                "better value may lie beyond the levels studied."
            ),
            "",
        ]
    return lines


def _rests_on(view: xr.Dataset, terms: list[str], levels: dict[str, int]) -> str:
    parts = []
    for t in terms:
        if t not in levels:
            parts.append(f"the interaction column {md_escape(t)}")
            continue
        runs = np.flatnonzero(view[f"{t}_level"].values == levels[t]) + 1
        listed = ", ".join(str(i) for i in runs[:MAX_LISTED_RUNS])
        more = f", … ({runs.size} runs)" if runs.size > MAX_LISTED_RUNS else ""
        parts.append(f"{md_escape(t)} at level {levels[t] + 1} (runs {listed}{more})")
    return "; ".join(parts)


def _predicted(view: xr.Dataset, an: xr.Dataset, r: xr.Dataset, shown: str) -> list[str]:
    units = _units(r)
    name = str(r.response.values)
    levels = optimum_levels(an, name)
    terms = [t for t in str(r.model_terms.values).split(",") if t]
    alpha = float(an.attrs["alpha"])
    lines = ["### Predicted optimum", "", *_levels_table(view, an, levels)]
    lines.append(
        f"Predicted {md_escape(shown)} at these levels: **{num(float(r.predicted))}{units}**"
        + (" (mean over the operating conditions)" if an.sizes["condition"] > 1 else "")
        + f" — Taguchi's additive model: the grand mean {num(float(r.grand_mean))}{units} plus "
        "the effect of each model term at its level, each effect the mean of the runs at that "
        f"level: {_rests_on(view, terms, levels) or 'no term'}."
    )
    half = float(r.half_width)
    if np.isfinite(half):
        mean = float(r.predicted)
        confirm = float(r.confirmation_half_width)
        runs = int(an.attrs["confirmation_runs"])
        lines.append(
            f"{100 * (1 - alpha):g} % confidence interval of the mean: {num(mean - half)} … "
            f"{num(mean + half)}{units} (± {num(half)}; n_eff = {num(float(r.n_eff))}, V_e = "
            f"{num(float(r.error_ms))} with {int(r.error_dof)} dof). A confirmation run should "
            f"fall in {num(mean - confirm)} … {num(mean + confirm)}{units} (± {num(confirm)}, "
            f"{runs} run)."
        )
    else:
        lines.append("No interval: the error term has no degrees of freedom.")
    if shown != name:  # a replicated response, analysed as its run means
        lines.append(
            "Replicated responses are analysed as run means: the interval of a confirmation run "
            "is for the mean of as many replicates."
        )
    if an.sizes["condition"] > 1:
        lines += ["", _over_conditions(an, r, units, "Predicted"), ""]
        lines += _conditions(view, an, r, units)
    run = int(r.optimum_run.values[0])
    if an.sizes["condition"] == 1 and run >= 0:
        y = float(view[name].values[run])
        lines.append(f"This combination was run: {_run(run)} gave {num(y)}{units}.")
    elif an.sizes["condition"] == 1:
        lines.append(
            "This combination is not among the runs of the array: the confirmation run tests "
            "the prediction."
        )
    return [*lines, ""]


def sn_optimum_line(an: xr.Dataset, sn: str) -> str:
    """One sentence on the best S/N (computed or predicted)."""
    r = an.sel(response=sn)
    value = float(r.optimum_value)
    if not np.isfinite(value):
        return ""
    if computed(an):
        run = int(r.optimum_run.values[0])
        where = f" in {_run(run)}" if an.sizes["condition"] == 1 and run >= 0 else ""
        return f"Best computed S/N: {num(value)} dB{where}."
    half = float(r.half_width)
    interval = (
        f" ± {num(half)} dB ({100 * (1 - float(an.attrs['alpha'])):g} % confidence)"
        if np.isfinite(half)
        else ""
    )
    return f"Predicted S/N at its best levels: {num(float(r.predicted))} dB{interval}."


def tradeoff_section(
    an: xr.Dataset, view: xr.Dataset, names: list[str]
) -> tuple[list[str], dict[str, int]]:
    """The trade-off of several responses (control factors only) and the chosen levels."""
    shown = {taguchi.mean_name(view, r): r for r in json.loads(an.attrs["responses"])}
    factors = _control(an)
    if not factors:  # every factor an operating condition: nothing to trade
        return [], {}
    operating = _operating(an)
    lines = [
        "## Trade-off summary",
        "",
        "Best level of each control factor for each response, with the factor's contribution to "
        "that response's variation. Where the responses disagree, the chosen level is the best "
        "one for the response the factor contributes most to."
        + (
            f" Operating conditions ({md_escape(', '.join(operating))}) are not chosen: the "
            "values below "
            "are over all of them."
            if operating
            else ""
        ),
        "",
    ]
    header = ["response", "better", *factors]
    rows: list[list[Any]] = []
    for m in names:
        r = an.sel(response=m)
        cells = [
            f"{int(r.optimum_level.sel(term=f)) + 1} ({pct(float(r.contribution.sel(source=f)))} %)"
            for f in factors
        ]
        rows.append([shown.get(m, m), str(r.sense.values), *cells])
    chosen = {f: int(an["chosen_level"].sel(term=f)) for f in factors}
    chosen_row = [Markup("**chosen level**"), "", *[level_text(an, f, chosen[f]) for f in factors]]
    rows.append(chosen_row)
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
    lines += [table(header, rows), ""]
    grid = computed(an)
    several = an.sizes["condition"] > 1
    rows = []
    for m in names:
        r = an.sel(response=m)
        units = str(r.units.values)
        row = [shown.get(m, m), str(r.sense.values), num(float(r.optimum_value)),
               num(float(r.compromise))]  # fmt: skip
        row += [num(float(r.compromise_worst))] if several else []
        row += [] if grid else [num(float(r.compromise_half_width))]
        rows.append([*row, units if units != "1" else ""])
    header = ["response", "better", "own optimum", "chosen levels"]
    header += ["worst condition"] if several else []
    header += [] if grid else ["± (CI)"]
    what = "Computed" if grid else "Predicted"
    over = " (means over the operating conditions, and the worst of them)" if several else ""
    lines += [
        f"{what} value of each response at its own optimum and at the chosen levels{over}:",
        "",
        table([*header, "units"], rows),
        "",
    ]
    return lines, chosen
