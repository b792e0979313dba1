"""The trade-off of several responses of one study: per control factor the level each response
prefers, the level chosen (the response the factor contributes most to decides), conflicts,
and every response at the compromise, in each operating condition, worst and mean.

Operating factors (:mod:`studies.analysis.prediction`) are never chosen. In an orthogonal array the
compromise is predicted by each response's additive model, with its interval; in a complete
full factorial it was computed, and its value is read from the runs (:mod:`studies.analysis.grid_optimum`).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, Protocol

import numpy as np
import pandas as pd
import xarray as xr

from studies.analysis.grid_optimum import Grid
from studies.analysis.prediction import Prediction, control_factors, predict, predict_optimum
from studies.analysis.taguchi import ALPHA, anova_table


class Optimum(Protocol):
    """What the trade-off reads of a response's own optimum (a prediction or a grid point)."""

    @property
    def levels(self) -> dict[str, int]: ...

    @property
    def mean(self) -> float: ...


@dataclass(frozen=True)
class TradeOff:
    """Best levels per response and the compromise for conflicting objectives.

    ``table`` (index control factor): per response ``best <r>`` (1-based level) and ``% <r>``
    (contribution to that response's variation), then ``conflict`` (the responses disagree),
    ``choice`` (1-based compromise level) and ``decided by`` (the response the factor
    contributes most to, whose best level is taken). ``predictions`` (index response): the mean
    over the operating conditions at the response's own optimum and at the compromise, the
    worst condition at the compromise, the confidence half-width (arrays; NaN for a computed
    grid), ``units`` and ``sense``. ``at``: response → its value in each condition at the
    compromise. ``levels``: compromise, 0-based.
    """

    table: pd.DataFrame
    predictions: pd.DataFrame
    levels: dict[str, int]
    at: dict[str, np.ndarray] = field(default_factory=dict)


def tradeoff(
    ds: xr.Dataset,
    responses: Sequence[str],
    alpha: float = ALPHA,
    tables: Mapping[str, pd.DataFrame] | None = None,
    optima: Mapping[str, Optimum] | None = None,
    grid: Grid | None = None,
) -> TradeOff:
    """Trade-off summary of several responses on the same runs (each with its own ANOVA;
    ``tables`` and ``optima``: those ANOVAs and optima when the caller has them already;
    ``grid``: a complete full factorial's grid, whose compromise values are computed)."""
    factors = control_factors(ds)
    tables = {r: anova_table(ds, r) for r in responses} if tables is None else tables
    if optima is None:
        optima = {r: predict_optimum(ds, r, alpha=alpha, table=tables[r]) for r in responses}
    share = {r: tables[r]["contribution"] for r in responses}
    rows = {}
    levels = {}
    for f in factors:
        row: dict[str, Any] = {}
        for r in responses:
            row[f"best {r}"] = optima[r].levels[f] + 1
            row[f"% {r}"] = float(share[r][f])
        lead = max(responses, key=lambda r: np.nan_to_num(share[r][f], nan=-1.0))
        levels[f] = optima[lead].levels[f]
        row["conflict"] = len({optima[r].levels[f] for r in responses}) > 1
        row["choice"] = levels[f] + 1
        row["decided by"] = lead
        rows[f] = row
    table = pd.DataFrame.from_dict(rows, orient="index")
    table.index.name = "factor"
    preds, at = {}, {}
    for r in responses:
        sense = str(ds[r].attrs.get("better", "smaller"))
        if grid is not None:
            runs = grid.row(grid.combination(levels))  # read at these runs only
            values = ds[r].isel(run=runs).values.astype(float)
            half = confirm = np.nan
        else:
            p: Prediction = predict(ds, r, levels, alpha=alpha, table=tables[r])
            values, half = np.asarray(p.at), p.half_width
            confirm = p.confirmation_half_width
        at[r] = values
        preds[r] = {
            "own optimum": optima[r].mean,
            "compromise": float(np.mean(values)),
            "worst": float(values.max() if sense == "smaller" else values.min()),
            "half width": half,
            "confirmation half width": confirm,
            "units": str(ds[r].attrs.get("units", "")),
            "sense": sense,
        }
    predictions = pd.DataFrame.from_dict(preds, orient="index")
    predictions.index.name = "response"
    return TradeOff(table, predictions, levels, at)
