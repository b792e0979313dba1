"""``analysis.txt``: tables of the analysis Dataset (:func:`studies.analysis.analyze.analyze`) as text.

A renderer: it formats what the analysis holds and computes no statistics.
"""

from __future__ import annotations

import json
import textwrap
from collections.abc import Sequence

import numpy as np
import pandas as pd
import xarray as xr

from studies.analysis.statistics import sense_words, sweep_runs

NO_NOISE = (
    "A deterministic full factorial has no noise term: its ANOVA 'error' is the interactions, "
    "so F and P test the main effects against the interactions, not against noise."
)


MAX_LEVEL_COLUMNS = 12  # level means as table columns up to this many levels
WIDTH = 100  # characters per line of wrapped text


def wrap(text: str) -> str:
    """Prose of analysis.txt wrapped to ``WIDTH`` characters (tables are not wrapped)."""
    return textwrap.fill(text, WIDTH, subsequent_indent="  ")


def _number(value: float) -> str:
    """4 significant figures; ``inf``/``-inf`` as such, NaN as —."""
    if np.isnan(value):
        return "—"
    return f"{value:.4g}" if np.isfinite(value) else ("inf" if value > 0 else "-inf")


def _units_suffix(units: str) -> str:
    return f" [{units}]" if units and units != "1" else ""


def _with_units(text: str, units: str) -> str:
    return f"{text} {units}" if units not in ("", "1") else text


def _level_means(row: xr.Dataset) -> list[str]:
    """A term's level means, * when runs at the level have no value (left out), † when some
    count at the best or worst value seen (see :func:`missing_notes`); the arrays read once."""
    k, left_out, bounded = row.k.values, row.left_out.values, row.bounded.values
    return [
        _number(k[i]) + ("*" if int(left_out[i]) else "") + ("†" if int(bounded[i]) else "")
        for i in range(k.size)
    ]


def _level_names(row: xr.Dataset) -> list[str]:
    """The term's levels as text (numbers with 4 significant figures, or their names)."""
    return [
        _number(v) if np.isfinite(v) else str(label)
        for v, label in zip(row.level_value.values, row.level_label.values, strict=True)
        if str(label)
    ]


def _best_text(an: xr.Dataset, row: xr.Dataset, t: str) -> str:
    role = str(an["term_role"].sel(term=t).values)
    best = int(row.best_level)
    if role in ("operating", "model"):
        return f"— ({role})"
    if role == "column":
        return "—"
    if best < 0:
        return "— (not ranked)" if str(row.sense.values) == "none" else "— (R = 0)"
    names = _level_names(row)
    fu = str(row.term_units.values)
    return f"{best + 1} ({_with_units(names[best], fu)})" if best < len(names) else str(best + 1)


def range_text(an: xr.Dataset, response: str) -> str:
    """The range-analysis table (k_i, R, rank, best level per term) of one response; factors
    with more than ``MAX_LEVEL_COLUMNS`` levels get their level means as wrapped lines below."""
    r = an.sel(response=response)
    nlevels = int(np.isfinite(r.k.values).any(axis=0).sum())
    wide = nlevels > MAX_LEVEL_COLUMNS
    rows, long = [], []
    for t in an["term"].values:
        row = r.sel(term=t)
        names, means = _level_names(row), _level_means(row)
        fu = str(row.term_units.values)
        levels = f"{len(names)} levels" if wide else _with_units(", ".join(names), fu)
        rows.append(
            {
                "factor": t,
                "levels": levels,
                **({} if wide else {f"k{i + 1}": means[i] for i in range(nlevels)}),
                "R": _number(float(row.R)),
                "rank": int(row["rank"]),
                "best": _best_text(an, row, str(t)),
            }
        )
        if wide:
            present = np.flatnonzero(np.isfinite(row.k.values))
            pairs = ", ".join(f"{names[i]}: {means[i]}" for i in present)
            long.append(
                textwrap.fill(
                    f"k of {t} by level{_units_suffix(fu)}: {pairs}",
                    WIDTH,
                    subsequent_indent="  ",
                )
            )
    return "\n".join([pd.DataFrame(rows).to_string(index=False), *long])


def missing_notes(an: xr.Dataset, response: str) -> list[str]:
    """Sentences on the runs without a finite value behind the level means (marks * and †),
    with how many runs each marked level has without one."""
    r = an.sel(response=response)
    meaning = str(r.none_means.values)
    notes = []
    left = r.left_out.values
    if left.any():
        notes.append(
            f"* Level mean without some of its runs: runs with no value are left out "
            f"(none_means = {meaning}). Runs left out per level: {_per_level(an, r, left)}."
        )
    bounded = r.bounded.values
    if bounded.any():
        bounds = " or ".join(
            f"the {which} value seen ({_number(float(v))})"
            for which, v in (("best", r.best_bound.values), ("worst", r.worst_bound.values))
            if np.isfinite(v)
        )
        notes.append(
            f"† Level mean counting runs without a finite value at {bounds} (none_means = "
            f"{meaning}; ±inf counts as the best or worst value by the sense): a bound, their "
            f"true values lie beyond it. Such runs per level: {_per_level(an, r, bounded)}."
        )
    return notes


def _per_level(an: xr.Dataset, r: xr.Dataset, counts: np.ndarray) -> str:
    """``length = 25 mm: 3 of 15 runs`` for each factor level with a count."""
    parts = []
    for j, t in enumerate(an["term"].values):
        if str(an["term_role"].sel(term=t).values) == "column":
            continue
        names = _level_names(r.sel(term=t))
        fu = str(r.term_units.sel(term=t).values)
        runs = an["level_runs"].sel(term=t).values
        parts += [
            f"{t} = {_with_units(names[i], fu)}: {int(counts[j, i])} of {int(runs[i])}"
            for i in np.flatnonzero(counts[j])
        ]
    return "; ".join(parts)


def pooled_note() -> str:
    """What the parenthesised contributions of pooled rows mean."""
    return (
        "A pooled term's share (in parentheses) is counted inside the error row, so the other "
        "rows add up to 100 %."
    )


def anova_frame(an: xr.Dataset, response: str) -> pd.DataFrame:
    """The ANOVA rows of one response as a table indexed by source (pooled rows marked)."""
    r = an.sel(response=response)
    frame = pd.DataFrame(
        {c: r[c].values for c in ("SS", "dof", "MS", "F", "P", "contribution")},
        index=[
            f"{s} (pooled)" if p else str(s)
            for s, p in zip(an["source"].values, r["pooled"].values, strict=True)
        ],
    )
    frame["dof"] = frame["dof"].astype(int)
    return frame.rename(columns={"contribution": "contribution %"})


def format_tables(an: xr.Dataset, response: str) -> str:
    """Range-analysis and ANOVA tables of ``response`` as text, with units."""
    r = an.sel(response=response)
    units = str(r.units.values)
    frame = anova_frame(an, response)
    pooled = r["pooled"].values.astype(bool)
    shares = [_number(v) for v in frame["contribution %"]]
    frame["contribution %"] = [f"({v})" if p else v for v, p in zip(shares, pooled, strict=True)]
    anova_text = frame.to_string(
        formatters=dict.fromkeys(["SS", "MS", "F", "P"], _number), na_rep=""
    )
    ss_unit = f" (SS in ({units})^2)" if units not in ("", "1") else ""
    lines = [
        wrap(
            f"Range analysis of {response} ({r.long_name.values}){_units_suffix(units)}; "
            f"{sense_words(str(r.sense.values))}; k_i = mean at level i (levels numbered from 1 here, "
            "from 0 in results.nc)"
        ),
        range_text(an, response),
        *(wrap(n) for n in missing_notes(an, response)),
        "",
        f"ANOVA of {response}{ss_unit}",
        anova_text,
    ]
    note = str(r.anova_note.values)
    if pooled.any():
        note = f"{pooled_note()} {note}".strip()
    if note:
        lines.append(wrap(f"Note: {note}"))
    if "first_order" in an and np.isfinite(r.first_order.values).any():
        lines += ["", decomposition_text(an, response)]
    return "\n".join(lines)


def decomposition_frame(an: xr.Dataset, response: str) -> pd.DataFrame:
    """Main effects, two-factor interactions and the remainder of a full factorial, with the
    share of the total and the Sobol indices."""
    r = an.sel(response=response)
    total = float(r.total_SS)
    rows = {
        str(f): (float(r.main_SS.sel(factor=f)), float(r.first_order.sel(factor=f)),
                 float(r.total_effect.sel(factor=f)))
        for f in an["factor"].values
    }  # fmt: skip
    rows |= {str(p): (float(r.pair_SS.sel(pair=p)), np.nan, np.nan) for p in an["pair"].values}
    if an.sizes["factor"] > 2:
        rows["3+ factor interactions"] = (float(r.remainder_SS), np.nan, np.nan)
    rows["total"] = (total, np.nan, np.nan)
    frame = pd.DataFrame.from_dict(rows, orient="index", columns=["SS", "S1", "ST"])
    frame.insert(1, "share %", 100.0 * frame["SS"] / total if total > 0 else np.nan)
    return frame


def decomposition_text(an: xr.Dataset, response: str) -> str:
    frame = decomposition_frame(an, response)
    table = frame.to_string(formatters=dict.fromkeys(frame.columns, _number), na_rep="")
    return "\n".join(
        [
            wrap(
                f"Variance decomposition of {response} over the full factorial (exact; S1 and "
                "ST are the first-order and total Sobol indices over the grid)"
            ),
            table,
            wrap(NO_NOISE),
        ]
    )


def status_line(an: xr.Dataset, response: str) -> str:
    """How many design points carry each value of a status code (counted, never averaged)."""
    counts = an[f"{response}_count"]
    labels = counts[f"{response}_flag"].values
    shown = ", ".join(
        f"{int(n)} {label}" for label, n in zip(labels, counts.values, strict=True) if n
    )
    meaning = counts.attrs.get("comment", "")
    return (
        f"{response}{f' ({meaning})' if meaning else ''}: {shown or 'no design points'} "
        f"— a status code, counted per design point (not averaged)"
    )


def format_sweep(ds: xr.Dataset, responses: Sequence[str]) -> str:
    """One table per swept factor: factor value against every response (with units)."""
    blocks = []
    for f in json.loads(ds.attrs["factors"]):
        part = sweep_runs(ds, f)
        columns = {f"{f} [{ds[f].attrs.get('units', '')}]": part[f].values}
        for r in responses:
            columns[f"{r} [{ds[r].attrs.get('units', '')}]"] = part[r].values
        table = pd.DataFrame(columns).to_string(index=False, float_format=_number)
        blocks.append(f"Sweep of {f} (other factors at their base levels)\n{table}")
    return "\n\n".join(blocks)
