"""The predicted optimum of a Taguchi study and its confidence intervals.

Predicted response (additive model): ŷ = T̄ + Σ_t (m_t - T̄) over the model terms t (factors
and interaction columns not pooled into error), m_t the mean response at the term's level,
T̄ the grand mean. Confidence interval of that mean and of the mean of r confirmation runs
(Ross 1996, ch. 8; Roy 1990):

    ± sqrt(F(1 - α; 1, ν_e) · V_e / n_eff)   and   ± sqrt(F(1 - α; 1, ν_e) · V_e · (1/n_eff + 1/r))

with Taguchi's effective number of replications n_eff = N / (1 + Σ_t dof_t), V_e and ν_e the
error mean square and dof of the ANOVA. F(1 - α; 1, ν) = t(1 - α/2; ν)², so these are t
intervals; for a balanced array they equal the OLS confidence interval of the fitted mean.

Only **control** factors are chosen. **Operating** factors (attribute ``operating_factors``:
speed, load) are conditions: the prediction is made in every condition (each combination of
their levels) and ``mean`` is the mean over the conditions, ``worst`` the worst of them. The
additive model is Taguchi's tool for an orthogonal array, where the optimum was usually not run;
a full factorial computed every combination (:mod:`studies.analysis.grid_optimum`).
"""

from __future__ import annotations

import itertools
import json
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import pandas as pd
import xarray as xr

from studies.analysis.statistics import SENSES, f_quantile
from studies.analysis.sums_of_squares import level_sums, round_off_of
from studies.analysis.taguchi import (
    ALPHA,
    anova_table,
    factor_names,
    interaction_columns,
    model_terms,
    number,
)
from studies.common.blocks import level_count
from studies.common.errors import StudyError


@dataclass(frozen=True)
class Prediction:
    """Additive-model prediction of ``response`` at ``levels`` (0-based level per factor)."""

    response: str
    units: str
    sense: str
    levels: dict[str, int]
    terms: tuple[str, ...]
    mean: float
    grand_mean: float
    n_eff: float
    error_ms: float
    error_dof: int
    alpha: float
    half_width: float
    confirmation_runs: int
    confirmation_half_width: float
    conditions: tuple[dict[str, int], ...] = ({},)
    at: tuple[float, ...] = ()

    @property
    def worst(self) -> float:
        """The worst predicted value over the operating conditions."""
        if not self.at:
            return self.mean
        return max(self.at) if self.sense == "smaller" else min(self.at)

    @property
    def interval(self) -> tuple[float, float]:
        return self.mean - self.half_width, self.mean + self.half_width

    @property
    def confirmation_interval(self) -> tuple[float, float]:
        return self.mean - self.confirmation_half_width, self.mean + self.confirmation_half_width


class _Model:
    """Level means of the model terms and the ANOVA error of one response."""

    def __init__(
        self,
        ds: xr.Dataset,
        response: str,
        pool: Sequence[str] | None,
        terms: Sequence[str] | None,
        table: pd.DataFrame | None = None,
    ) -> None:
        self.ds, self.response = ds, response
        self.table = anova_table(ds, response, pool) if table is None else table
        available = model_terms(ds)
        if terms is None:
            terms = [t for t in available if not self.table.loc[t, "pooled"]]
        unknown = [t for t in terms if t not in available]
        if unknown:
            msg = f"unknown model term(s) {unknown}; terms are {available}"
            raise StudyError(msg)
        self.terms = tuple(terms)
        self.pairs = interaction_columns(ds)
        y = ds[response].values.astype(float)
        self.finite = np.isfinite(y)
        self.y_all = y
        self.y = y if self.finite.all() else y[self.finite]
        self.grand = float(self.y.mean())
        self.means = {t: self.level_means(t) for t in self.terms}
        dof = sum(int(number(self.table, t, "dof")) for t in self.terms)
        self.n_eff = self.finite.sum() / (1 + dof)

    def level_means(self, name: str) -> np.ndarray:
        """Mean response at each level index of a factor or column (NaN where no value)."""
        codes = self.ds[f"{name}_level"].values
        counts, sums = level_sums(codes, self.y_all, int(codes.max()) + 1, self.finite)
        with np.errstate(invalid="ignore", divide="ignore"):
            return sums / counts

    def level_of(self, term: str, levels: Mapping[str, int]) -> int:
        if term not in self.pairs:
            return int(levels[term])
        a, b = self.pairs[term]
        hit = (self.ds[f"{a}_level"].values == levels[a]) & (
            self.ds[f"{b}_level"].values == levels[b]
        )
        found = np.unique(self.ds[f"{term}_level"].values[hit])
        if found.size != 1:
            msg = f"column {term} does not carry the interaction {a} x {b}: levels {found}"
            raise StudyError(msg)
        return int(found[0])

    def value(self, levels: Mapping[str, int]) -> float:
        effects = [self.means[t][self.level_of(t, levels)] - self.grand for t in self.terms]
        return self.grand + float(np.sum(effects))

    def over(self, levels: Mapping[str, int], conditions: Sequence[dict[str, int]]) -> list[float]:
        """The predicted value in each condition at the control ``levels``."""
        return [self.value({**levels, **c}) for c in conditions]

    def prediction(
        self,
        levels: Mapping[str, int],
        sense: str,
        alpha: float,
        runs: int,
        conditions: Sequence[dict[str, int]] = ({},),
    ) -> Prediction:
        ms_e, dof_e = number(self.table, "error", "MS"), int(number(self.table, "error", "dof"))
        at = self.over(levels, conditions)
        half = confirm = np.nan
        if dof_e > 0 and np.isfinite(ms_e) and ms_e > 0.0:  # an exact fit estimates no error
            f = f_quantile(1.0 - alpha, 1, dof_e)
            half = math.sqrt(f * ms_e / self.n_eff)
            confirm = math.sqrt(f * ms_e * (1.0 / self.n_eff + 1.0 / runs))
        return Prediction(
            response=self.response,
            units=str(self.ds[self.response].attrs.get("units", "")),
            sense=sense,
            levels={f: int(v) for f, v in levels.items()},
            terms=self.terms,
            mean=float(np.mean(at)),
            grand_mean=self.grand,
            n_eff=float(self.n_eff),
            error_ms=ms_e,
            error_dof=dof_e,
            alpha=alpha,
            half_width=half,
            confirmation_runs=runs,
            confirmation_half_width=confirm,
            conditions=tuple(dict(c) for c in conditions),
            at=tuple(at),
        )


def operating_factors(ds: xr.Dataset) -> list[str]:
    """The factors that are operating conditions (attribute ``operating_factors``)."""
    return list(json.loads(ds.attrs.get("operating_factors", "[]")))


def control_factors(ds: xr.Dataset) -> list[str]:
    """The factors whose levels are chosen (every factor that is not an operating one)."""
    operating = set(operating_factors(ds))
    return [f for f in factor_names(ds) if f not in operating]


def conditions(ds: xr.Dataset) -> list[dict[str, int]]:
    """Every combination of the operating factors' levels (last factor fastest); one empty
    condition when there is no operating factor."""
    names = operating_factors(ds)
    counts = [range(level_count(ds[f"{f}_level"].variable)) for f in names]
    return [dict(zip(names, combo, strict=True)) for combo in itertools.product(*counts)]


def predict(
    ds: xr.Dataset,
    response: str,
    levels: Mapping[str, int],
    pool: Sequence[str] | None = None,
    terms: Sequence[str] | None = None,
    alpha: float = ALPHA,
    confirmation_runs: int = 1,
    table: pd.DataFrame | None = None,
) -> Prediction:
    """Predicted mean of ``response`` at ``levels`` (control factor → 0-based level) with
    intervals, in every operating condition (operating factors given in ``levels`` are held).

    ``terms`` are the model terms (factors, interaction columns); by default those the ANOVA
    keeps (not pooled, see :func:`anova_table`). ``pool`` is passed to the ANOVA; ``table`` is
    that ANOVA when the caller has it already.
    """
    model = _Model(ds, response, pool, terms, table)
    missing = sorted({f for f in control_factors(ds) if f not in levels})
    if missing:
        msg = f"levels missing for factor(s) {missing}"
        raise StudyError(msg)
    held = [c for c in conditions(ds) if all(levels.get(f, v) == v for f, v in c.items())]
    sense = str(ds[response].attrs.get("better", "smaller"))
    return model.prediction(levels, sense, alpha, confirmation_runs, held)


def _best_level(scores: np.ndarray) -> int:
    """The lowest level whose score is the least up to round-off (``ROUND_OFF`` of the largest
    |score|, the tolerance of R = 0 in the range analysis): levels equal in exact arithmetic
    are a tie, not a choice made by the last bits of their means."""
    finite = np.where(np.isnan(scores), np.inf, scores)
    return int(np.argmax(finite <= finite.min() + round_off_of(finite)))


def predict_optimum(
    ds: xr.Dataset,
    response: str,
    sense: str | None = None,
    pool: Sequence[str] | None = None,
    terms: Sequence[str] | None = None,
    alpha: float = ALPHA,
    confirmation_runs: int = 1,
    table: pd.DataFrame | None = None,
) -> Prediction:
    """The best control-level combination of ``response`` and its predicted mean with
    intervals (the mean over the operating conditions; each condition in ``at``).

    Each control factor takes the level with the best mean, as in range analysis (``sense``:
    "smaller" or "larger", default the response's ``better`` attribute; ties go to the lower
    level); control factors linked by an interaction term take the combination of the additive
    model that is best on average over the operating conditions, searched over all their level
    combinations. Operating factors are never chosen.
    """
    chosen = sense or str(ds[response].attrs.get("better", "smaller"))
    if chosen not in SENSES:
        msg = f"sense must be one of {SENSES}, got {chosen!r}"
        raise StudyError(msg)
    sign = 1.0 if chosen == "smaller" else -1.0
    model = _Model(ds, response, pool, terms, table)
    factors = control_factors(ds)
    each = conditions(ds)
    levels = {}
    for f in factors:
        levels[f] = _best_level(sign * model.level_means(f))
    linked = [f for f in factors if any(f in model.pairs.get(t, ()) for t in model.terms)]
    if linked:
        best, best_levels = math.inf, levels
        counts = [range(int(ds[f"{f}_level"].max()) + 1) for f in linked]
        for combo in itertools.product(*counts):
            trial = levels | dict(zip(linked, combo, strict=True))
            score = sign * float(np.mean(model.over(trial, each)))
            if score < best:
                best, best_levels = score, trial
        levels = best_levels
    return model.prediction(levels, chosen, alpha, confirmation_runs, each)
