"""Sobol' indices of a Saltelli design (:mod:`studies.define.sampling`) with bootstrap intervals.

With the runs in SALib's order (per base row j: A_j, A_B^(1)_j … A_B^(D)_j, B_j) and
V = Var[f(A) ∪ f(B)] (divisor 2N):

* first order, Saltelli et al. 2010, Table 2 (b):  S_i = mean(f(B) (f(A_B^(i)) − f(A))) / V
* total effect, Jansen 1999:                         ST_i = mean((f(A) − f(A_B^(i)))²) / 2V
* second order, where asked (``second_order``; runs B_A^(i) after the A_B^(i)), Saltelli 2002
  as SALib computes it:  S_ij = mean(f(B_A^(i)) f(A_B^(j)) − f(A) f(B)) / V − S_i − S_j
  (``S2`` on factor × ``factor_b``, i before j only; NaN elsewhere)

``S1_conf``/``ST_conf``/``S2_conf`` are half widths of the ``CONFIDENCE`` interval from a bootstrap over the
base rows (``RESAMPLES`` resamples, seeded by the study's seed): z · sd of the resampled
estimates, as SALib reports them. The estimators are SALib's (``SALib.analyze.sobol``), which
the tests check to 1e-12 on the same outputs; like SALib, the outputs are first centred and
scaled by their mean and sd over every run used (S_i's estimator is not invariant to a shift
at finite N; the scaling changes nothing). Base rows with a non-finite output in any of
their D + 2 (2D + 2) runs are left out (``rows_used``).
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from typing import Any

import numpy as np
import xarray as xr

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


def second_order(
    a: np.ndarray, ab: np.ndarray, ba: np.ndarray, b: np.ndarray, i: int, j: int
) -> np.ndarray:
    """S_ij of factors i < j [Saltelli 2002] (rows: base rows)."""
    var = np.var(np.concatenate([a, b], axis=0), axis=0)
    joint = np.mean(ba[..., i] * ab[..., j] - a * b, axis=0) / var
    first = first_order(a, ab[..., [i, j]], b)
    return joint - first[..., 0] - first[..., 1]


def split(y: np.ndarray, d: int, second: bool = False) -> tuple[np.ndarray, ...]:
    """f(A) (N), f(A_B^(i)) (N × D), f(B_A^(i)) (N × D, empty without ``second``) and f(B) (N)
    of the runs in SALib's order."""
    rows = y.reshape(-1, 2 * d + 2 if second else d + 2)
    ba = rows[:, d + 1 : 2 * d + 1] if second else rows[:, :0]
    return rows[:, 0], rows[:, 1 : d + 1], ba, rows[:, -1]


KEYS = ("S1", "S1_conf", "ST", "ST_conf")


def indices(y: np.ndarray, d: int, seed: int, second: bool = False) -> dict[str, np.ndarray]:
    """S1, S1_conf, ST, ST_conf (each length D), with ``second`` S2 and S2_conf (D × D, i < j
    only) and the base rows used."""
    from scipy import stats  # noqa: PLC0415  (on use: a study without noise or samples needs none)

    a, ab, ba, b = split(np.asarray(y, dtype=float), d, second)
    keep = np.isfinite(a) & np.isfinite(b) & np.isfinite(ab).all(axis=1) & np.isfinite(ba).all(1)
    a, ab, ba, b = a[keep], ab[keep], ba[keep], b[keep]
    used = np.concatenate([a, ab.ravel(), ba.ravel(), b])
    if used.size:  # centred and scaled over every run used, as SALib does: the first-order
        centre, scale = used.mean(), used.std()  # estimator is not shift-invariant at finite N
        scale = scale if scale > 0 else 1.0
        a, ab, ba, b = ((v - centre) / scale for v in (a, ab, ba, b))
    n = a.size
    out = {k: np.full(d, np.nan) for k in KEYS} | {
        k: np.full((d, d), np.nan) for k in ("S2", "S2_conf")
    }
    out["rows"] = np.asarray(n)
    if n < 2:
        return out
    r = np.random.default_rng(seed).integers(n, size=(n, RESAMPLES))
    z = stats.norm.ppf(0.5 + CONFIDENCE / 2)
    out["S1"] = first_order(a, ab, b)
    out["S1_conf"] = z * first_order(a[r], ab[r], b[r]).std(axis=0, ddof=1)
    out["ST"] = total_order(a, ab, b)
    out["ST_conf"] = z * total_order(a[r], ab[r], b[r]).std(axis=0, ddof=1)
    for i in range(d if second else 0):
        for j in range(i + 1, d):
            out["S2"][i, j] = second_order(a, ab, ba, b, i, j)
            resampled = second_order(a[r], ab[r], ba[r], b[r], i, j)
            out["S2_conf"][i, j] = z * resampled.std(ddof=1)
    return out


def sobol_analysis(ds: xr.Dataset, responses: Sequence[str]) -> xr.Dataset:
    """``S1``, ``S1_conf``, ``ST``, ``ST_conf`` on (response, factor), with the study's
    ``second_order`` also ``S2``, ``S2_conf`` on (response, factor, factor_b), and
    ``rows_used`` per response, for the responses with finite values (seed: the study's)."""
    factors = json.loads(ds.attrs["factors"])
    seed, second = int(ds.attrs.get("seed", 1)), bool(ds.attrs.get("second_order", 0))
    d = len(factors)
    keys = (*KEYS, "S2", "S2_conf") if second else KEYS
    found = [indices(ds[name].values, d, seed, second) for name in responses]
    data: dict[str, Any] = {}
    for k in keys:
        dims = ("response", "factor", "factor_b") if k.startswith("S2") else ("response", "factor")
        values = (
            np.stack([f[k] for f in found]) if found else np.empty((0,) + (d,) * (len(dims) - 1))
        )
        data[k] = (dims, values, {"units": "1"})
    data["rows_used"] = (("response",), np.array([int(f["rows"]) for f in found], dtype=np.int64))
    coords = {
        "response": list(responses),
        "factor": factors,
        **({"factor_b": factors} if second else {}),
        "units": ("response", [str(ds[r].attrs.get("units", "")) for r in responses]),
        "long_name": ("response", [str(ds[r].attrs.get("long_name", r)) for r in responses]),
    }
    attrs = {"resamples": RESAMPLES, "confidence": CONFIDENCE, "second_order": int(second)}
    return xr.Dataset(data, coords=coords, attrs=attrs)
