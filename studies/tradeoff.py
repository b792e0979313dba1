"""The trade-off of several responses of one Taguchi study: per term the level each response
prefers, the level chosen (the response with the largest contribution decides), conflicts,
and every response predicted at the compromise."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd
import xarray as xr

from studies.prediction import Prediction, predict, predict_optimum
from studies.taguchi import ALPHA, anova_table, factor_names


@dataclass(frozen=True)
class TradeOff:
    """Best levels per response and the compromise for conflicting objectives.

    ``table`` (index factor): per response ``best <r>`` (1-based level) and ``% <r>``
    (contribution to that response's variation), then ``conflict`` (the responses disagree),
    ``choice`` (1-based compromise level) and ``decided by`` (the response the factor
    contributes most to, whose best level is taken). ``predictions`` (index response): the
    predicted mean at the response's own optimum and at the compromise, with the confidence
    half-width at the compromise, ``units`` and ``sense``. ``levels``: compromise, 0-based.
    """

    table: pd.DataFrame
    predictions: pd.DataFrame
    levels: dict[str, int]


def tradeoff(
    ds: xr.Dataset,
    responses: Sequence[str],
    alpha: float = ALPHA,
    tables: Mapping[str, pd.DataFrame] | None = None,
    optima: Mapping[str, Prediction] | None = None,
) -> TradeOff:
    """Trade-off summary of several responses on the same runs (each with its own ANOVA;
    ``tables`` and ``optima``: those ANOVAs and optima when the caller has them already)."""
    factors = factor_names(ds)
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
    preds = {}
    for r in responses:
        at = predict(ds, r, levels, alpha=alpha, table=tables[r])
        preds[r] = {
            "own optimum": optima[r].mean,
            "compromise": at.mean,
            "half width": at.half_width,
            "units": optima[r].units,
            "sense": optima[r].sense,
        }
    predictions = pd.DataFrame.from_dict(preds, orient="index")
    predictions.index.name = "response"
    return TradeOff(table, predictions, levels)
