"""Statistics under noise: each design point's distribution of a response over its noise cases.

For a results Dataset with a ``noise`` dimension (a study's ``[noise]``, :mod:`studies.define.noise`)
and per response with values on ``run × noise``, per design point (dimension ``run``):

* ``noise_n``: the noise cases with a finite value (the others are left out of the moments);
* ``noise_mean`` with its 95 % t interval ``noise_mean_low`` … ``noise_mean_high``
  (x̄ ± t_{0.975, n-1} s/√n);
* ``noise_sd`` (divisor n − 1) with Bonett's (2006, Comput. Stat. Data Anal. 50, 775)
  kurtosis-adjusted interval ``noise_sd_low`` … ``noise_sd_high`` (:func:`sd_interval`; NaN
  below 5 cases). The χ² interval assumes a normal response: on a log-normal one (σ = 1) it
  covered the true sd in 49–64 % of 400 scrambled Sobol' samples of 32 and 256 cases, Bonett's
  in 99.5–99.8 %; on random samples Bonett's covered 74–96 % over five responses (the 74 % for
  that log-normal at 32 cases), the χ² interval 32–98 % over three of them;
* ``noise_quantile`` at ``QUANTILES`` (linear interpolation, numpy's default) with the
  distribution-free order-statistic interval ``noise_quantile_low`` … ``_high``: the ranks
  l = F⁻¹(α/2), u = F⁻¹(1 − α/2) + 1 of the binomial(n, p) (Hahn & Meeker 1991, §5.2);
* where the study gives the response a ``[limits]`` entry: ``violations`` (cases beyond the
  limit; a case without a value counts as a violation when the response's ``none_means`` is
  "worst", as none when "best", and is left out when "unknown"), ``violation_n`` (cases
  counted), ``violation_probability`` = violations / n and its Wilson score interval
  ``violation_low`` … ``violation_high`` (scipy.stats.binomtest(...).proportion_ci);
* ``robust_run``: the design point with the lowest probability of violation, ties and
  responses without a limit decided by the quantile on the worse side (5 % when larger is
  better, 95 % when smaller is); -1 for an unranked response.

The intervals describe sampling error of random, Latin-hypercube or scrambled Sobol' noise
samples (the last two spread more evenly than random points and were covered more often: the
t interval of the mean covered 100 % of 400 Sobol' and Latin-hypercube samples of 32 and 256
cases of a uniform-sum, a two-valued and a log-normal response, and 84–95 % of random
ones, short of 95 % for the skewed and two-valued responses at 32 cases); for an outer
orthogonal array the cases are not a sample and the intervals are indicative.
Everything is O(runs × cases): sorts and sums along the noise axis.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from typing import Any

import numpy as np
import xarray as xr

from studies.run.results import NOISE

QUANTILES = (0.05, 0.5, 0.95)
CONFIDENCE = 0.95
DIM = "noise_response"  # the responses with values under noise (beside the analysis' response)


def robust_statistics(ds: xr.Dataset, responses: Sequence[str]) -> xr.Dataset:
    """The statistics above for each of ``responses`` that has a ``noise`` dimension (an
    empty Dataset when none has)."""
    names = [r for r in responses if NOISE in ds[r].dims and ds[r].dtype.kind == "f"]
    if not names:
        return xr.Dataset()
    limits = json.loads(ds.attrs.get("limits", "{}"))
    runs = ds.sizes["run"]
    shape = (len(names), runs)
    out = {
        v: np.full(shape, np.nan)
        for v in (
            "noise_mean", "noise_mean_low", "noise_mean_high", "noise_sd", "noise_sd_low",
            "noise_sd_high", "violation_probability", "violation_low", "violation_high",
        )
    }  # fmt: skip
    n_ok = np.zeros(shape, dtype=np.int64)
    violations = np.full(shape, -1, dtype=np.int64)
    counted = np.zeros(shape, dtype=np.int64)
    q_shape = (*shape, len(QUANTILES))
    quantile = {v: np.full(q_shape, np.nan) for v in ("", "_low", "_high")}
    for i, name in enumerate(names):
        y = np.asarray(ds[name].transpose("run", NOISE).values, dtype=float)
        finite = np.isfinite(y)
        n = finite.sum(axis=1)
        n_ok[i] = n
        moments(out, i, y, finite, n)
        for j, p in enumerate(QUANTILES):
            q, low, high = quantile_interval(y, p)
            quantile[""][i, :, j], quantile["_low"][i, :, j], quantile["_high"][i, :, j] = (
                q,
                low,
                high,
            )
        if name in limits:
            k, m = violation_counts(y, limits[name], str(ds[name].attrs.get("none_means", "")))
            violations[i], counted[i] = k, m
            p_hat, low, high = wilson(k, m)
            out["violation_probability"][i], out["violation_low"][i], out["violation_high"][i] = (
                p_hat,
                low,
                high,
            )
    dims = (DIM, "run")
    data: dict[str, Any] = {v: (dims, values) for v, values in out.items()}
    data |= {f"noise_quantile{s}": ((*dims, "quantile"), q) for s, q in quantile.items()}
    data |= {"noise_n": (dims, n_ok), "violations": (dims, violations)}
    data["violation_n"] = (dims, counted)
    lows = [limits.get(r, {}).get("min", np.nan) for r in names]
    highs = [limits.get(r, {}).get("max", np.nan) for r in names]
    coords = {
        DIM: names,
        "quantile": list(QUANTILES),
        "limit_min": (DIM, np.asarray(lows, dtype=float)),
        "limit_max": (DIM, np.asarray(highs, dtype=float)),
        "noise_units": (DIM, [str(ds[r].attrs.get("units", "")) for r in names]),
    }
    data["robust_run"] = (
        DIM,
        [_robust_run(ds[r], i, out, quantile[""]) for i, r in enumerate(names)],
    )
    result = xr.Dataset(data, coords=coords)
    result.attrs = {"noise_cases": ds.sizes[NOISE], "confidence": CONFIDENCE}
    return result


def _robust_run(y: xr.DataArray, i: int, out: dict[str, np.ndarray], quantile: np.ndarray) -> int:
    """The design point that meets the response's limit most often, ties (and responses
    without a limit) broken by the quantile on the worse side: the 5 % quantile when larger
    is better, the 95 % one when smaller is (-1 for an unranked response)."""
    better = str(y.attrs.get("better", "smaller"))
    if better not in ("smaller", "larger"):
        return -1
    worse_side = quantile[i, :, 0] if better == "larger" else -quantile[i, :, -1]
    p = out["violation_probability"][i]
    limited = bool(np.isfinite(p).any())
    key_p = np.where(np.isfinite(p), p, np.inf) if limited else np.zeros(p.size)
    key_q = np.where(np.isfinite(worse_side), -worse_side, np.inf)
    first = int(np.lexsort((key_q, key_p))[0])
    ranked = np.isfinite(key_q[first]) or (limited and np.isfinite(key_p[first]))
    return first if ranked else -1  # no limit and no quantile anywhere: nothing to rank


def moments(
    out: dict[str, np.ndarray], i: int, y: np.ndarray, finite: np.ndarray, n: np.ndarray
) -> None:
    """Mean and sd with their intervals into row ``i`` of ``out`` (NaN where n < 2)."""
    from scipy import stats  # noqa: PLC0415  (on use: a study without noise or samples needs none)

    with np.errstate(invalid="ignore", divide="ignore"):
        mean = np.where(finite, y, 0.0).sum(axis=1) / n
        var = np.where(finite, (y - mean[:, None]) ** 2, 0.0).sum(axis=1) / (n - 1)
        sd = np.sqrt(var)
        dof = np.maximum(n - 1, 1)
        t = stats.t.ppf(0.5 + CONFIDENCE / 2, dof)
        half = t * sd / np.sqrt(n)
        two = n >= 2
        out["noise_mean"][i] = np.where(n >= 1, mean, np.nan)
        out["noise_mean_low"][i] = np.where(two, mean - half, np.nan)
        out["noise_mean_high"][i] = np.where(two, mean + half, np.nan)
        out["noise_sd"][i] = np.where(two, sd, np.nan)
        out["noise_sd_low"][i], out["noise_sd_high"][i] = sd_interval(y, finite, n, var)


def sd_interval(
    y: np.ndarray, finite: np.ndarray, n: np.ndarray, var: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Bonett's (2006) 95 % interval of the sd of each row of ``y`` (its ``finite`` values,
    ``n`` of them, sample variance ``var``): ln(c s²) ∓ z c √((γ₄ − (n − 3)/n)/(n − 1)) with
    c = n/(n − z) and the kurtosis γ₄ = n Σ(y − m)⁴ / (Σ(y − ȳ)²)² about the mean m trimmed by
    1/(2√(n − 4)) at each end (as ``scipy.stats.trim_mean`` cuts). [0, 0] for a row whose
    values are all equal; NaN where n < 5."""
    from scipy import stats  # noqa: PLC0415  (on use: a study without noise or samples needs none)

    z = stats.norm.ppf(0.5 + CONFIDENCE / 2)
    count = n.astype(np.int64)
    ordered = np.sort(np.where(finite, y, np.inf), axis=1)  # the values first, then the rest
    sums = np.zeros((y.shape[0], y.shape[1] + 1))
    np.cumsum(np.where(np.isfinite(ordered), ordered, 0.0), axis=1, out=sums[:, 1:])
    rows = np.arange(y.shape[0])
    with np.errstate(invalid="ignore", divide="ignore"):
        cut = np.floor(np.where(count > 4, 0.5 / np.sqrt(count - 4.0), 0.0) * count)
        cut = cut.astype(np.int64)
        m = (sums[rows, count - cut] - sums[rows, cut]) / (count - 2 * cut)
        fourth = np.where(finite, (y - m[:, None]) ** 4, 0.0).sum(axis=1)
        kurtosis = n * fourth / ((n - 1) * var) ** 2
        c = n / (n - z)
        se = c * np.sqrt(np.maximum(kurtosis - (n - 3) / n, 0.0) / (n - 1))
        low, high = np.sqrt(c * var * np.exp(-z * se)), np.sqrt(c * var * np.exp(z * se))
    constant = var == 0.0  # every case the same value: the sd is exactly 0
    low, high = np.where(constant, 0.0, low), np.where(constant, 0.0, high)
    enough = count >= 5
    return np.where(enough, low, np.nan), np.where(enough, high, np.nan)


def quantile_interval(y: np.ndarray, p: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The p-quantile of each row of ``y`` over its finite values and the distribution-free
    order-statistic interval at ``CONFIDENCE`` (an end beyond the sample is NaN)."""
    from scipy import stats  # noqa: PLC0415  (on use: a study without noise or samples needs none)

    rows = y.shape[0]
    values = np.where(np.isfinite(y), y, np.nan)
    ordered = np.sort(values, axis=1)  # NaN last
    n = np.isfinite(ordered).sum(axis=1)
    alpha = 1.0 - CONFIDENCE
    q = np.full(rows, np.nan)
    some = n > 0
    if some.any():
        q[some] = np.nanquantile(values[some], p, axis=1)
    low_rank = stats.binom.ppf(alpha / 2, n, p)  # 1-based rank l: P(B ≤ l - 1) ≤ α/2
    high_rank = stats.binom.ppf(1 - alpha / 2, n, p) + 1
    low, high = np.full(rows, np.nan), np.full(rows, np.nan)
    ok_low = some & (low_rank >= 1)
    ok_high = some & (high_rank <= n)
    index = np.arange(rows)
    low[ok_low] = ordered[index[ok_low], low_rank[ok_low].astype(np.int64) - 1]
    high[ok_high] = ordered[index[ok_high], high_rank[ok_high].astype(np.int64) - 1]
    return q, low, high


def violation_counts(
    y: np.ndarray, limit: dict[str, float], none_means: str
) -> tuple[np.ndarray, np.ndarray]:
    """Per row of ``y``: the cases beyond ``limit`` (min/max) and the cases counted."""
    has = ~np.isnan(y)
    beyond = np.zeros(y.shape, dtype=bool)
    with np.errstate(invalid="ignore"):
        if "min" in limit:
            beyond |= has & (y < limit["min"])
        if "max" in limit:
            beyond |= has & (y > limit["max"])
    if none_means == "worst":
        beyond |= ~has
    counted = np.full(y.shape[0], y.shape[1]) if none_means in ("worst", "best") else has.sum(1)
    return beyond.sum(axis=1), counted


def wilson(k: np.ndarray, n: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """k/n and the Wilson score interval at ``CONFIDENCE`` per element (NaN where n = 0),
    from scipy's binomtest, once per distinct (k, n)."""
    from scipy import stats  # noqa: PLC0415  (on use: a study without noise or samples needs none)

    p_hat, low, high = (np.full(k.shape, np.nan) for _ in range(3))
    pairs, where = np.unique(np.stack([k, n], axis=-1), axis=0, return_inverse=True)
    for j, (kj, nj) in enumerate(pairs):
        if nj < 1:
            continue
        ci = stats.binomtest(int(kj), int(nj)).proportion_ci(CONFIDENCE, method="wilson")
        at = where.reshape(k.shape) == j
        p_hat[at], low[at], high[at] = kj / nj, ci.low, ci.high
    return p_hat, low, high
