"""Sobol' indices of a Saltelli design (:mod:`studies.define.sampling`) with bootstrap intervals.

With the runs in SALib's order (per base row j: A_j, A_B^(1)_j … A_B^(D)_j, B_j) and
V = Var[f(A) ∪ f(B)] (divisor 2N):

* first order, Saltelli et al. 2010, Table 2 (b):  S_i = mean(f(B) (f(A_B^(i)) − f(A))) / V
* total effect, Jansen 1999:                         ST_i = mean((f(A) − f(A_B^(i)))²) / 2V

``S1_conf``/``ST_conf`` are half widths of the ``CONFIDENCE`` interval from a bootstrap over the
base rows (``RESAMPLES`` resamples, seeded by the study's seed): z · sd of the resampled
estimates, as SALib reports them. The estimators are SALib's (``SALib.analyze.sobol``), which
the tests check to 1e-12 on the same outputs; like SALib, the outputs are first centred and
scaled by their mean and sd over every run used (S_i's estimator is not invariant to a shift
at finite N; the scaling changes nothing). Base rows with a non-finite output in any of
their D + 2 runs are left out (``rows_used``).
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from typing import Any

import numpy as np
import xarray as xr
from scipy import stats

RESAMPLES = 100
CONFIDENCE = 0.95


def first_order(a: np.ndarray, ab: np.ndarray, b: np.ndarray) -> np.ndarray:
    """S_i per column of ``ab`` (rows: base rows) [Saltelli 2010]."""
    var = np.var(np.concatenate([a, b], axis=0), axis=0)
    return np.mean(b[..., None] * (ab - a[..., None]), axis=0) / var[..., None]


def total_order(a: np.ndarray, ab: np.ndarray, b: np.ndarray) -> np.ndarray:
    """ST_i per column of ``ab`` [Jansen 1999]."""
    var = np.var(np.concatenate([a, b], axis=0), axis=0)
    return 0.5 * np.mean((a[..., None] - ab) ** 2, axis=0) / var[..., None]


def split(y: np.ndarray, d: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """f(A) (N), f(A_B^(i)) (N × D) and f(B) (N) of the runs in SALib's order."""
    rows = y.reshape(-1, d + 2)
    return rows[:, 0], rows[:, 1 : d + 1], rows[:, d + 1]


def indices(y: np.ndarray, d: int, seed: int) -> dict[str, np.ndarray]:
    """S1, S1_conf, ST, ST_conf (each length D) and the base rows used."""
    a, ab, b = split(np.asarray(y, dtype=float), d)
    keep = np.isfinite(a) & np.isfinite(b) & np.isfinite(ab).all(axis=1)
    a, ab, b = a[keep], ab[keep], b[keep]
    used = np.concatenate([a, ab.ravel(), b])
    if used.size:  # centred and scaled over every run used, as SALib does: the first-order
        centre, scale = used.mean(), used.std()  # estimator is not shift-invariant at finite N
        scale = scale if scale > 0 else 1.0
        a, ab, b = (a - centre) / scale, (ab - centre) / scale, (b - centre) / scale
    n = a.size
    if n < 2:
        nan = np.full(d, np.nan)
        return {"S1": nan, "S1_conf": nan, "ST": nan, "ST_conf": nan, "rows": np.asarray(n)}
    r = np.random.default_rng(seed).integers(n, size=(n, RESAMPLES))
    z = stats.norm.ppf(0.5 + CONFIDENCE / 2)
    return {
        "S1": first_order(a, ab, b),
        "S1_conf": z * first_order(a[r], ab[r], b[r]).std(axis=0, ddof=1),
        "ST": total_order(a, ab, b),
        "ST_conf": z * total_order(a[r], ab[r], b[r]).std(axis=0, ddof=1),
        "rows": np.asarray(n),
    }


def sobol_analysis(ds: xr.Dataset, responses: Sequence[str], seed: int) -> xr.Dataset:
    """``S1``, ``S1_conf``, ``ST``, ``ST_conf`` on (response, factor) and ``rows_used`` per
    response, for the responses with finite values."""
    factors = json.loads(ds.attrs["factors"])
    d = len(factors)
    out = {k: np.full((len(responses), d), np.nan) for k in ("S1", "S1_conf", "ST", "ST_conf")}
    rows = np.zeros(len(responses), dtype=np.int64)
    for i, name in enumerate(responses):
        found = indices(ds[name].values, d, seed)
        for k, values in out.items():
            values[i] = found[k]
        rows[i] = int(found["rows"])
    dims = ("response", "factor")
    data: dict[str, Any] = {k: (dims, v, {"units": "1"}) for k, v in out.items()}
    data["rows_used"] = (("response",), rows, {"units": "1"})
    coords = {
        "response": list(responses),
        "factor": factors,
        "units": ("response", [str(ds[r].attrs.get("units", "")) for r in responses]),
        "long_name": ("response", [str(ds[r].attrs.get("long_name", r)) for r in responses]),
    }
    return xr.Dataset(data, coords=coords, attrs={"resamples": RESAMPLES, "confidence": CONFIDENCE})
