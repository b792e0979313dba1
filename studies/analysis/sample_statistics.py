"""Statistics of a sampling design (``[design] type = "sobol"`` or ``"lhs"``,
:mod:`studies.define.sampling`): the distribution of each response over the sample and how
strongly each factor drives it, with 95 % intervals.

Per response (dimension ``response``), over the runs with a finite value (``sample_n``), with
the interval machinery of the statistics under noise (:mod:`studies.analysis.robust`):

* ``sample_mean`` with its t interval ``sample_mean_low`` … ``_high``; ``sample_sd`` (divisor
  n − 1) with its χ² interval; ``sample_quantile`` at ``QUANTILES`` with the distribution-free
  order-statistic interval ``sample_quantile_low`` … ``_high``;
* where the study gives a ``[limits]`` entry: ``sample_violations``, ``sample_violation_n`` and
  ``sample_violation_probability`` with its Wilson interval ``sample_violation_low`` … ``_high``.

Per (response, factor):

* ``pearson``: the linear correlation r of the factor with the response (scipy.stats.pearsonr)
  and its Fisher-z interval ``pearson_low`` … ``_high`` (tanh(atanh r ± z/√(n − 3)));
* ``spearman``: the rank correlation ρ (scipy.stats.spearmanr), for monotone but non-linear
  effects, and its Fisher-z interval with the variance 1.06/(n − 3) of Fieller, Hartley &
  Pearson (1957, Biometrika 44, 470).

For a linear response Y = Σ a_i X_i of independent X_i, r_i = a_i σ_i / σ_Y and Σ r_i² = 1:
r² is then the share of the variance the factor explains (= S1). The intervals assume
independent random points; for a scrambled Sobol' or a Latin-hypercube sample they are
conservative (those samples cover the space more evenly than random points). O(N log N) per
response and factor (the ranks).
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from typing import Any

import numpy as np
import xarray as xr
from scipy import stats

from studies.analysis.robust import (
    CONFIDENCE,
    QUANTILES,
    moments,
    quantile_interval,
    violation_counts,
    wilson,
)

SPEARMAN_VARIANCE = 1.06  # × 1/(n − 3): Fieller, Hartley & Pearson 1957
MOMENTS = ("mean", "mean_low", "mean_high", "sd", "sd_low", "sd_high")
VIOLATION = ("violation_probability", "violation_low", "violation_high")
CORRELATIONS = ("pearson", "pearson_low", "pearson_high", "spearman", "spearman_low")


def fisher_interval(r: float, n: int, variance: float = 1.0) -> tuple[float, float]:
    """tanh(atanh r ∓ z √(variance/(n − 3))) at ``CONFIDENCE`` (NaN when n ≤ 3)."""
    if n <= 3 or not np.isfinite(r):
        return np.nan, np.nan
    half = stats.norm.ppf(0.5 + CONFIDENCE / 2) * np.sqrt(variance / (n - 3))
    with np.errstate(divide="ignore"):  # |r| = 1 (an exact monotone relation): [r, r]
        centre = np.arctanh(np.clip(r, -1.0, 1.0))
    return float(np.tanh(centre - half)), float(np.tanh(centre + half))


def correlations(x: np.ndarray, y: np.ndarray) -> dict[str, float]:
    """Pearson r and Spearman ρ of ``x`` with ``y`` and their intervals (NaN when either is
    constant or fewer than 4 points)."""
    out = dict.fromkeys((*CORRELATIONS, "spearman_high"), np.nan)
    if x.size < 4 or np.ptp(x) == 0 or np.ptp(y) == 0:
        return out
    found = stats.pearsonr(x, y)
    ci = found.confidence_interval(CONFIDENCE)
    out["pearson"], out["pearson_low"], out["pearson_high"] = (
        float(found.statistic),
        ci.low,
        ci.high,
    )
    rho = float(stats.spearmanr(x, y).statistic)
    out["spearman"] = rho
    out["spearman_low"], out["spearman_high"] = fisher_interval(rho, x.size, SPEARMAN_VARIANCE)
    return out


def sample_analysis(ds: xr.Dataset, responses: Sequence[str]) -> xr.Dataset:
    """The variables above for ``responses`` (those with a finite value somewhere)."""
    factors = json.loads(ds.attrs["factors"])
    limits = json.loads(ds.attrs.get("limits", "{}"))
    k, d = len(responses), len(factors)
    one = {f"noise_{m}": np.full((k, 1), np.nan) for m in MOMENTS}
    q = {s: np.full((k, len(QUANTILES)), np.nan) for s in ("", "_low", "_high")}
    p = {v: np.full(k, np.nan) for v in VIOLATION}
    n_ok, violations, counted = (np.zeros(k, dtype=np.int64) for _ in range(3))
    corr = {v: np.full((k, d), np.nan) for v in (*CORRELATIONS, "spearman_high")}
    x = {f: np.asarray(ds[f].values, dtype=float) for f in factors}
    for i, name in enumerate(responses):
        y = np.asarray(ds[name].values, dtype=float)
        finite = np.isfinite(y)
        n_ok[i] = finite.sum()
        moments(one, i, y[None, :], finite[None, :], n_ok[i : i + 1])
        for j, level in enumerate(QUANTILES):
            found = quantile_interval(y[None, :], level)
            q[""][i, j], q["_low"][i, j], q["_high"][i, j] = (float(v[0]) for v in found)
        if name in limits:
            none_means = str(ds[name].attrs.get("none_means", ""))
            hits, m = violation_counts(y[None, :], limits[name], none_means)
            violations[i], counted[i] = int(hits[0]), int(m[0])
            found = wilson(hits, m)
            p["violation_probability"][i], p["violation_low"][i], p["violation_high"][i] = (
                float(v[0]) for v in found
            )
        for j, f in enumerate(factors):
            for key, value in correlations(x[f][finite], y[finite]).items():
                corr[key][i, j] = value
    data: dict[str, Any] = {
        f"sample_{m}": (("response",), one[f"noise_{m}"][:, 0]) for m in MOMENTS
    }
    data |= {f"sample_quantile{s}": (("response", "quantile"), v) for s, v in q.items()}
    data |= {f"sample_{v}": (("response",), values) for v, values in p.items()}
    data |= {
        "sample_n": (("response",), n_ok),
        "sample_violations": (("response",), np.where(counted > 0, violations, -1)),
        "sample_violation_n": (("response",), counted),
    }
    data |= {v: (("response", "factor"), values, {"units": "1"}) for v, values in corr.items()}
    coords = {
        "response": list(responses),
        "factor": factors,
        "quantile": list(QUANTILES),
        "units": ("response", [str(ds[r].attrs.get("units", "")) for r in responses]),
        "long_name": ("response", [str(ds[r].attrs.get("long_name", r)) for r in responses]),
        "limit_min": ("response", [limits.get(r, {}).get("min", np.nan) for r in responses]),
        "limit_max": ("response", [limits.get(r, {}).get("max", np.nan) for r in responses]),
    }
    return xr.Dataset(data, coords=coords, attrs={"confidence": CONFIDENCE})
