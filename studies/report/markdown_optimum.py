"""The report's optimum sections, read from the analysis Dataset.

A full factorial computed every combination: its section is the **best computed point** (run
and value, its neighbours, no model interval). An orthogonal array did not: its section is
Taguchi's **predicted optimum** (additive model, the runs it rests on, confidence intervals).
Operating factors are never chosen: values are given per operating condition, with the worst
and the mean over them (:mod:`studies.analysis.optimum`).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
import xarray as xr

from studies.analysis.sums_of_squares import round_off_of
from studies.common.text_safety import Markup, md_escape
from studies.report.markdown_format import levels_of, num, table, units_of, value_text
from studies.report.markdown_ran import ran_note, ran_text, replaced
from studies.report.markdown_terms import (
    at_run,
    bound_mark,
    computed,
    control_terms,
    model_terms,
    none_text,
    not_chosen,
    optimum_levels,
    run_text,
    units_suffix,
)

MAX_CONDITION_ROWS = 12  # operating conditions listed one per row; more: see analysis.nc
MAX_LISTED_RUNS = 12  # runs named per level in "rests on runs …"

LACK_OF_FIT = (
    "The responses are computed, not measured: V_e is the additive model's lack of fit (the "
    "interactions it leaves out), and the intervals hold at their level only where that lack "
    "of fit behaves like random error; a confirmation run outside them shows such an "
    "interaction, not bad luck."
)
EXACT_FIT = (
    "the error mean square is 0 (an exact fit: the model's terms reproduce every run), so "
    "nothing estimates the model's error. With computed responses that is no proof of "
    "accuracy: an interaction the array does not separate (one on the columns of assigned "
    "factors) is read as their main effects. The confirmation run is the check."
)


def _nothing_to_choose(an: xr.Dataset) -> str:
    what = "an operating condition or a model rung" if model_terms(an) else "an operating condition"
    return f"Every factor is {what}: there are no levels to choose."


def _worst_condition(an: xr.Dataset, at: np.ndarray, sense: str) -> str:
    """The label of the worst condition; "" when there is none to name (no value, or every
    condition gives the same value)."""
    finite = at[np.isfinite(at)]
    if not finite.size or np.ptp(finite) <= round_off_of(finite):
        return ""
    i = int(np.nanargmax(at) if sense == "smaller" else np.nanargmin(at))
    return str(an["condition"].values[i])


def _levels_table(
    view: xr.Dataset,
    an: xr.Dataset,
    levels: dict[str, int],
    runs: Sequence[int] = (),
    tied: Sequence[str] = (),
) -> list[str]:
    """The chosen levels; a level that some of ``runs`` did not run with is marked as a
    request (:mod:`studies.report.markdown_ran`), a factor in ``tied`` (R = 0: every level
    gives the same) as any level."""
    if not levels:
        return [_nothing_to_choose(an), ""]
    instead: set[str] = set()
    for run in runs:
        instead |= set(replaced(view, an, int(run))) if run >= 0 else set()
    rows = [
        [
            f,
            f"{level + 1} (any: R = 0)" if f in tied else level + 1,
            Markup(
                value_text(levels_of(an, f)[level], units_of(view, f))
                + (" (requested; what ran: below)" if f in instead else "")
            ),
        ]
        for f, level in levels.items()
    ]
    lines = [table(["factor", "level", "value"], rows), ""]
    return lines + [line for sentence in not_chosen(an) for line in (sentence, "")]


def _levels_ofrun_text(view: xr.Dataset, an: xr.Dataset, run: int) -> Markup:
    """``factor = value (level n)`` of each control factor at ``run``."""
    parts = []
    for f in control_terms(an):
        level = int(at_run(view, f"{f}_level", run))
        units = units_of(view, f)
        shown = value_text(levels_of(an, f)[level], units if units != "1" else "")
        parts.append(f"{md_escape(f)} = {shown} (level {level + 1})")
    return Markup(", ".join(parts))


def _conditions(view: xr.Dataset, an: xr.Dataset, r: xr.Dataset, units: str) -> list[str]:
    """Per operating condition: the value at the chosen levels and (grid) the best run there."""
    labels = an["condition"].values
    if len(labels) > MAX_CONDITION_ROWS:
        return [
            (
                f"{len(labels)} "
                + (
                    "conditions (model rungs × operating conditions)"
                    if model_terms(an)
                    else "operating conditions"
                )
                + ": per condition in `analysis.nc` "
                "(`optimum_at`, `optimum_run`, `best_value`, `best_run`)."
            ),
            "",
        ]
    grid = computed(an) and bool(control_terms(an))
    header = ["condition", "at these levels" if control_terms(an) else "value"]
    header += ["best in this condition"] if grid else []
    rows = []
    name = str(r.response.values)
    for i, condition in enumerate(labels):
        run = int(r.optimum_run.values[i])
        value = num(float(r.optimum_at.values[i])) + units
        at = value + (f" ({run_text(run)})" if run >= 0 else "")
        if run >= 0 and bound_mark(view, name, run):
            at = f"{md_escape(none_text(view, name))} ({run_text(run)}: counted at {value})"
        row: list[Any] = [str(condition), Markup(at)]
        if grid:
            best = int(r.best_run.values[i])
            value = f"{num(float(r.best_value.values[i]))}{units}"
            if best >= 0 and bound_mark(view, name, best):
                value = md_escape(none_text(view, name))
            row.append(
                Markup(
                    f"{value} ({run_text(best)}: {_levels_ofrun_text(view, an, best)}"
                    f"{ran_text(view, an, best)})"
                )
                if best >= 0
                else "—"
            )
        rows.append(row)
    return [table(header, rows), ""]


def _over_conditions(an: xr.Dataset, r: xr.Dataset, units: str, what: str) -> str:
    sense = str(r.sense.values)
    worst = _worst_condition(an, r.optimum_at.values, sense)
    n = an.sizes["condition"]
    if not worst:
        return f"{what} over the {n} operating conditions: **{num(float(r.optimum_value))}{units}** in every one."
    return (
        f"{what} over the {n} operating conditions: mean "
        f"**{num(float(r.optimum_value))}{units}**, worst **{num(float(r.optimum_worst))}{units}**"
        f" ({md_escape(worst)})."
    )


def _ties(r: xr.Dataset) -> list[str]:
    """One sentence when several control combinations share the best value."""
    ties = int(r.optimum_ties)
    if ties < 2:
        return []
    rule = str(r.optimum_tie_rule.values)
    how = (
        "the one whose levels have the best main effects (range analysis) is shown"
        if rule == "main effects"
        else "the first in grid order is shown"
    )
    return [f"{ties} level combinations share this best value: {how}.", ""]


def optimum_section(view: xr.Dataset, an: xr.Dataset, name: str, shown: str) -> list[str]:
    """The best computed point (full factorial) or the predicted optimum (array) of ``name``."""
    r = an.sel(response=name)
    if not np.isfinite(float(r.optimum_value)):
        return []
    return _computed(view, an, r, shown) if computed(an) else _predicted(view, an, r, shown)


def _computed(view: xr.Dataset, an: xr.Dataset, r: xr.Dataset, shown: str) -> list[str]:
    units = units_suffix(r)
    name = str(r.response.values)
    if not control_terms(an):
        lines = ["### Over the operating conditions", ""]
        lines += [_nothing_to_choose(an), ""]
        lines += [line for sentence in not_chosen(an) for line in (sentence, "")]
        if not model_terms(an):  # a mean over models would mix them: per model instead
            lines += [_over_conditions(an, r, units, "Computed"), ""]
        return lines + _per_model(an, r, units) + _conditions(view, an, r, units)
    lines = [
        "### Best computed point",
        "",
        (
            "Every combination of the levels was computed: this is the best run, not a "
            "prediction (no model, no interval)."
            if an.sizes["condition"] == 1
            else "Every combination of the levels was computed: the values below are computed "
            "runs, not a prediction (no model, no interval). The levels are the control "
            "combination whose runs have the best mean over the operating conditions."
        ),
        "",
        *_levels_table(view, an, optimum_levels(an, name), r.optimum_run.values),
    ]
    if an.sizes["condition"] == 1:
        run = int(r.optimum_run.values[0])
        lines += [_best_line(view, r, run, shown, units), ""]
    else:
        lines += [_over_conditions(an, r, units, "Chosen for the best mean"), ""]
        lines += _conditions(view, an, r, units)
    lines += ran_note(view, an, r.optimum_run.values)
    return lines + _per_model(an, r, units) + _ties(r) + _neighbours(view, an, r, units)


def _per_model(an: xr.Dataset, r: xr.Dataset, units: str) -> list[str]:
    """Per model rung: the mean and the worst over the other operating conditions."""
    if "model" not in an.coords:
        return []
    labels = an["condition"].values
    rows = []
    for m, model in enumerate(an["model"].values):
        worst = int(r.model_worst_at.values[m])
        where = an["condition_model"].values == m
        at = r.optimum_at.values[where]
        same = bool(np.isfinite(at).all() and (at == at[0]).all())
        rows.append(
            [
                str(model),
                Markup(f"{num(float(r.model_mean.values[m]))}{units}"),
                Markup(
                    "the same in every condition"
                    if same or worst < 0
                    else f"{num(float(r.model_worst.values[m]))}{units} ({md_escape(labels[worst])})"
                ),
            ]
        )
    return ["Per model:", "", table(["model", "mean", "worst condition"], rows), ""]


def _best_line(view: xr.Dataset, r: xr.Dataset, run: int, shown: str, units: str) -> str:
    """The best run's value, or, when that run has no value of its own, what it is
    (``none_label``) and what it was counted as (``none_means``): never a computed value."""
    name = str(r.response.values)
    best = num(float(r.optimum_value))
    grand = f"grand mean {num(float(r.grand_mean))}{units}"
    if not bound_mark(view, name, run):
        return f"Best {md_escape(shown)}: **{best}{units}** in {run_text(run)} ({grand})."
    meaning = str(view[name].attrs.get("none_means", "unknown"))
    counted = (
        f"better than every computed value (the best is {best}{units})"
        if meaning == "best"
        else f"counted at the bound {best}{units}"
    )
    return (
        f"Best {md_escape(shown)}: **{md_escape(none_text(view, name))}** in {run_text(run)} "
        f"(none_means = {md_escape(meaning)}: {counted}; {grand})."
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
                # Named levels (a material) have no order: nothing lies beyond the first or last.
                numeric = np.isfinite(an["level_value"].sel(term=f).values[level])
                cells.append("— (edge of the grid)" if numeric else "—")
                if numeric and len(levels_of(an, f)) > 1 and _edge_matters(r, f, 1 - s):
                    edges.append(f)
                continue
            if not np.isfinite(value):
                cells.append("— (no value there)")
                continue
            at = value_text(levels_of(an, f)[level + step], units_of(view, f))
            if run >= 0 and bound_mark(view, name, run):
                shown = md_escape(none_text(view, name))
                cells.append(
                    Markup(f"{shown} at {at} ({run_text(run)}: counted at {num(value)}{units})")
                )
                continue
            ran = f" ({run_text(run)})" if run >= 0 else ""
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


def _edge_matters(r: xr.Dataset, factor: str, inwards: int) -> bool:
    """Whether the optimum at an edge level of ``factor`` differs beyond round-off from its
    neighbour one level inwards (``neighbour_value`` side ``inwards``): where they are equal,
    the response does not change with ``factor`` there and nothing says a better value lies
    beyond; without a value there, it may."""
    both = np.array(
        [float(r.neighbour_value.sel(term=factor).values[inwards]), float(r.optimum_value)]
    )
    return not np.isfinite(both).all() or abs(both[0] - both[1]) > round_off_of(both)


def _rests_on(view: xr.Dataset, name: str, terms: list[str], levels: dict[str, int]) -> str:
    """The runs each model term's effect is the mean of: those at its level with a value of
    ``name`` (a run without one is left out of the analysis)."""
    parts = []
    valued = ~np.isnan(view[name].values)
    for t in terms:
        if t not in levels:
            parts.append(f"the interaction column {md_escape(t)}")
            continue
        runs = np.flatnonzero((view[f"{t}_level"].values == levels[t]) & valued) + 1
        listed = ", ".join(str(i) for i in runs[:MAX_LISTED_RUNS])
        more = f", … ({runs.size} runs)" if runs.size > MAX_LISTED_RUNS else ""
        parts.append(f"{md_escape(t)} at level {levels[t] + 1} (runs {listed}{more})")
    return "; ".join(parts)


def _predicted(view: xr.Dataset, an: xr.Dataset, r: xr.Dataset, shown: str) -> list[str]:
    units = units_suffix(r)
    name = str(r.response.values)
    levels = optimum_levels(an, name)
    terms = [t for t in str(r.model_terms.values).split(",") if t]
    alpha = float(an.attrs["alpha"])
    tied = [t for t in levels if float(r["R"].sel(term=t)) == 0.0]
    lines = ["### Predicted optimum", "", *_levels_table(view, an, levels, tied=tied)]
    lines.append(
        f"Predicted {md_escape(shown)} at these levels: **{num(float(r.predicted))}{units}**"
        + (" (mean over the operating conditions)" if an.sizes["condition"] > 1 else "")
        + f" — Taguchi's additive model: the grand mean {num(float(r.grand_mean))}{units} plus "
        "the effect of each model term at its level, each effect the mean of the runs at that "
        f"level: {_rests_on(view, name, terms, levels) or 'no term'}."
    )
    half = float(r.half_width)
    if np.isfinite(half):
        mean = float(r.predicted)
        confirm = float(r.confirmation_half_width)
        runs = int(an.attrs["confirmation_runs"])
        lines.append(
            f"{100 * (1 - alpha):g} % confidence interval of the mean: {num(mean - half)} … "
            f"{num(mean + half)}{units} (± {num(half)}; n_eff = {num(float(r.n_eff))}, V_e = "
            f"{num(float(r.error_ms))} with {int(r.error_dof)} dof); a confirmation run: "
            f"{num(mean - confirm)} … {num(mean + confirm)}{units} (± {num(confirm)}, "
            f"{runs} run). {LACK_OF_FIT}"
        )
    elif int(r.error_dof) > 0:
        lines.append(f"No interval: {EXACT_FIT}")
    else:
        lines.append("No interval: the error term has no degrees of freedom.")
    if int(r.pass_fail) and not 0.0 <= float(r.predicted) <= 1.0:
        lines.append(
            f"{num(float(r.predicted))} lies outside the flag's range 0 (fail) … 1 (pass): a "
            "pass/fail flag is not additive, so the model cannot say how often these levels "
            "pass; the confirmation run can."
        )
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
        lines.append(f"This combination was run: {run_text(run)} gave {num(y)}{units}.")
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
        where = f" in {run_text(run)}" if an.sizes["condition"] == 1 and run >= 0 else ""
        return f"Best computed S/N: {num(value)} dB{where}."
    half = float(r.half_width)
    interval = (
        f" ± {num(half)} dB ({100 * (1 - float(an.attrs['alpha'])):g} % confidence where the "
        "lack of fit behaves like noise)"
        if np.isfinite(half)
        else ""
    )
    return f"Predicted S/N at its best levels: {num(float(r.predicted))} dB{interval}."
