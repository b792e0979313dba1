"""The report's trade-off section, read from the analysis Dataset: per control factor the level
each response prefers and the chosen one, then every response at its own optimum and at the
chosen levels (:mod:`studies.analysis.tradeoff`). Operating conditions are never chosen."""

from __future__ import annotations

import json
from collections.abc import Sequence
from typing import Any

import numpy as np
import xarray as xr

from studies.analysis import taguchi
from studies.common.blocks import runs_matching
from studies.common.text_safety import Markup, md_escape
from studies.report.markdown_format import level_text, num, pct, table
from studies.report.markdown_ran import replaced
from studies.report.markdown_terms import (
    bound_mark,
    computed,
    control_terms,
    none_text,
    operating_terms,
)


def tradeoff_section(
    an: xr.Dataset, view: xr.Dataset, names: list[str]
) -> tuple[list[str], dict[str, int]]:
    """The trade-off of several responses (control factors only) and the chosen levels."""
    shown = {taguchi.mean_name(view, r): r for r in json.loads(an.attrs["responses"])}
    factors = control_terms(an)
    if not factors:  # every factor an operating condition: nothing to trade
        return [], {}
    operating = operating_terms(an)
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
    requested = differs = False
    for m in names:
        r = an.sel(response=m)
        instead: set[str] = set()
        for run in r.optimum_run.values:
            instead |= set(replaced(view, an, int(run))) if run >= 0 else set()
        cells = [
            f"{int(r.optimum_level.sel(term=f)) + 1} ({pct(float(r.contribution.sel(source=f)))} %)"
            + (" ‡" if f in instead else "")
            + (" ≠" if _differs(r, f) else "")
            for f in factors
        ]
        differs = differs or any(_differs(r, f) for f in factors)
        requested = requested or bool(instead)
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
    if differs:
        lines += [
            (
                "≠ Not the range analysis' best level: the level at that response's best "
                "computed point, where the other factors' levels make it best (an interaction); "
                "the range analysis averages over them."
            ),
            "",
        ]
    if requested:
        lines += [
            (
                "‡ A requested level: at that response's best point the scene ran another "
                "value in some runs (its best computed point says which)."
            ),
            "",
        ]
    grid = computed(an)
    several = an.sizes["condition"] > 1
    at_chosen = _runs_at(view, chosen) if grid else np.array([], dtype=np.int64)
    rows = []
    for m in names:
        r = an.sel(response=m)
        units = str(r.units.values)
        own = _value(view, m, float(r.optimum_value), r.optimum_run.values if grid else ())
        row = [shown.get(m, m), str(r.sense.values), own,
               _value(view, m, float(r.compromise), at_chosen)]  # fmt: skip
        row += [num(float(r.compromise_worst))] if several else []
        row += [] if grid else [num(float(r.compromise_confirmation_half_width))]
        rows.append([*row, units if units != "1" else ""])
    header = ["response", "better", "own optimum", "chosen levels"]
    header += ["worst condition at the chosen levels"] if several else []
    header += [] if grid else ["± (a confirmation run)"]
    what = "Computed" if grid else "Predicted"
    over = (
        " (means over the operating conditions; the last value column is the worst condition "
        "at the chosen levels)"
        if several
        else ""
    )
    lines += [
        f"{what} value of each response at its own optimum and at the chosen levels{over}:",
        "",
        table([*header, "units"], rows),
        "",
    ]
    missing = [
        shown.get(m, m) for m in names if not np.isfinite(float(an.compromise.sel(response=m)))
    ]
    if missing:
        lines += [
            (
                f"— at the chosen levels ({md_escape(', '.join(missing))}): some of those runs "
                "have no value (none_means = unknown), so there is no value to give."
            ),
            "",
        ]
    return lines, chosen


def _runs_at(view: xr.Dataset, levels: dict[str, int]) -> np.ndarray:
    """The runs at these control levels (one per operating condition on a grid)."""
    conditions = [(view[f"{f}_level"].variable, level) for f, level in levels.items()]
    return runs_matching(conditions, view.sizes["run"])


def _value(view: xr.Dataset, name: str, value: float, runs: Sequence[int] | np.ndarray) -> Markup:
    """``value``, or what the runs behind it are when none has a value of its own (the reed's
    "no crossing up to order 3"), or the value marked as resting on such runs: a bound is
    never shown as a computed value."""
    runs = [int(i) for i in runs if int(i) >= 0]
    without = [i for i in runs if bound_mark(view, name, i)]
    if not without or not np.isfinite(value):  # "—": no value (none_means = unknown)
        return Markup(num(value))
    if len(without) == len(runs):
        return md_escape(none_text(view, name))
    return Markup(
        f"{num(value)} (counts {len(without)} of {len(runs)} runs at the bound: "
        f"{md_escape(none_text(view, name))})"
    )


def _differs(r: xr.Dataset, factor: str) -> bool:
    """Whether the optimum's level of ``factor`` is not the range analysis' best level."""
    best = int(r.best_level.sel(term=factor))
    return best >= 0 and best != int(r.optimum_level.sel(term=factor))
