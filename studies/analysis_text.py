"""``analysis.txt``: tables of the analysis Dataset (:func:`studies.analysis.analyze`) as text.

A renderer: it formats what the analysis holds and computes no statistics.
"""

from __future__ import annotations

import json
from collections.abc import Sequence

import numpy as np
import pandas as pd
import xarray as xr

from studies.statistics import sweep_runs

NO_NOISE = (
    "A deterministic full factorial has no noise term: its ANOVA 'error' is the interactions, "
    "so F and P test the main effects against the interactions, not against noise."
)


def _number(value: float) -> str:
    return "—" if not np.isfinite(value) else f"{value:.4g}"


def _units_suffix(units: str) -> str:
    return f" [{units}]" if units else ""


def range_text(an: xr.Dataset, response: str) -> str:
    """The range-analysis table (k_i, R, rank, best level per term) of one response."""
    r = an.sel(response=response)
    nlevels = int(np.isfinite(r.k.values).any(axis=0).sum())
    rows = []
    for t in an["term"].values:
        row = r.sel(term=t)
        values = [v for v in row.level_value.values if np.isfinite(v)]
        fu = str(row.term_units.values)
        best = int(row.best_level)
        best_value = row.level_value.values[best]
        levels = ", ".join(_number(v) for v in values) + (f" {fu}" if fu else "")
        shown = f" ({_number(best_value)} {fu})".rstrip() if np.isfinite(best_value) else ""
        if not values and int(an["is_factor"].sel(term=t)):  # categorical: the level names
            labels = [str(label) for label in row.level_label.values]
            levels = ", ".join(label for label in labels if label)
            shown = f" ({labels[best]})"
        rows.append(
            {
                "factor": t,
                "levels": levels,
                **{f"k{i + 1}": _number(row.k.values[i]) for i in range(nlevels)},
                "R": _number(float(row.R)),
                "rank": int(row["rank"]),
                "best": f"{best + 1}{shown}",
            }
        )
    return pd.DataFrame(rows).to_string(index=False)


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
    anova_text = anova_frame(an, response).to_string(
        formatters=dict.fromkeys(["SS", "MS", "F", "P", "contribution %"], _number), na_rep=""
    )
    ss_unit = f" (SS in ({units})^2)" if units not in ("", "1") else ""
    lines = [
        (
            f"Range analysis of {response} ({r.long_name.values}){_units_suffix(units)}; "
            f"{r.sense.values} is better; k_i = mean at level i (levels numbered from 1 here, "
            "from 0 in results.nc)"
        ),
        range_text(an, response),
        "",
        f"ANOVA of {response}{ss_unit}",
        anova_text,
    ]
    note = str(r.anova_note.values)
    if note:
        lines.append(f"Note: {note}")
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
            (
                f"Variance decomposition of {response} over the full factorial (exact; S1 and "
                "ST are the first-order and total Sobol indices over the grid)"
            ),
            table,
            NO_NOISE,
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
