"""Range analysis and analysis of variance of a study's results.

Both work on the results Dataset (see :mod:`studies.run.results`): dimension ``run``; for each
factor ``f`` the coordinates ``f`` (physical value, with ``units``) and ``f_level`` (0-based
level index); empty orthogonal-array columns as ``<name>_level`` coordinates only, named in the
global attribute ``error_columns``; factor names in the attribute ``factors`` (both JSON lists).
Runs whose response is NaN (failed cases) are left out.

Range analysis (Taguchi's "k, R" table): k_i = mean response at level i, R = max k - min k,
rank by R, best level by the sense of the response. ANOVA: sums of squares of the factor terms
in order (type I, as statsmodels' ``anova_lm(typ=1)``; for an orthogonal array they are
Taguchi's level sums SS = Σ n_i (k_i - ȳ)²; computed in O(N) by
:mod:`studies.analysis.sums_of_squares`), error = what the factors leave (the empty columns
and any other free degrees of freedom), F = MS / MS_error with P from the F distribution.
"""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from contextlib import ExitStack
from typing import Any

import numpy as np
import pandas as pd
import xarray as xr
from scipy import special

from studies.analysis import scratch
from studies.analysis.sums_of_squares import (
    ROUND_OFF,
    Centred,
    level_sums_in_blocks,
    round_off_of,
    term_sums_of_squares,
    without_round_off,
)
from studies.common.blocks import first_runs, level_count, run_slices, values_of
from studies.common.errors import StudyError
from studies.common.run_masks import run_mask

SENSES = ("smaller", "larger")
UNRANKED = "none"
"""The ``[sense]`` of a response that is tabulated but not ranked (no level is best)."""


def sense_words(sense: str) -> str:
    """``larger is better`` / ``smaller is better`` / ``not ranked``."""
    return "not ranked" if sense == UNRANKED else f"{sense} is better"


def _level_names(
    ds: xr.Dataset, names: Sequence[str] | None, attribute: str, default: str | None, what: str
) -> list[str]:
    """Names whose ``<name>_level`` coordinates the analysis uses: ``names``, else the JSON
    list in the global ``attribute`` (``default`` when absent; None: the attribute is required)."""
    if names is None:
        text = ds.attrs.get(attribute, default)
        if text is None:
            msg = f"the Dataset has no {attribute!r} attribute: pass {attribute}=[...]"
            raise StudyError(msg)
        names = json.loads(text)
    chosen = list(names)
    missing = [n for n in chosen if f"{n}_level" not in ds.coords]
    if missing:
        msg = f"no level coordinate for {what}(s) {missing} (expected '<{what}>_level' on run)"
        raise StudyError(msg)
    return chosen


def _factor_names(ds: xr.Dataset, factors: Sequence[str] | None) -> list[str]:
    return _level_names(ds, factors, "factors", None, "factor")


def _error_names(ds: xr.Dataset, error: Sequence[str] | None) -> list[str]:
    return _level_names(ds, error, "error_columns", "[]", "error column")


def has_values(ds: xr.Dataset, response: str) -> bool:
    """True if ``response`` is finite in some run (one NaN everywhere has nothing to analyse)."""
    return bool(np.isfinite(ds[response].values.astype(float)).any())


def _response(ds: xr.Dataset, response: str) -> tuple[xr.DataArray, np.ndarray]:
    """The response and the mask of runs where it is finite (held only where some run is
    not, :func:`studies.common.run_masks.run_mask`)."""
    if response not in ds.data_vars:
        msg = f"no response {response!r}; the Dataset has {sorted(map(str, ds.data_vars))}"
        raise StudyError(msg)
    y = ds[response]
    if y.dims != ("run",):
        msg = f"{response!r} has dims {y.dims}; analysis needs a scalar response on 'run'"
        raise StudyError(msg)
    values = values_of(y.variable)
    parts = run_slices(len(values))
    finite = run_mask(len(values), ((part, np.isfinite(values[part])) for part in parts))
    if not finite.any():
        msg = f"{response!r} has no finite value to analyse"
        raise StudyError(msg)
    return y, finite


def _sense(y: xr.DataArray, sense: str | None) -> str:
    chosen = sense if sense is not None else y.attrs.get("better", "smaller")
    if chosen == UNRANKED:  # the level means and ranges do not depend on the sense
        return "smaller"
    if chosen not in SENSES:
        msg = f"sense must be one of {SENSES}, got {chosen!r}"
        raise StudyError(msg)
    return chosen


def _level_table(
    ds: xr.Dataset, y: xr.DataArray, finite: np.ndarray, f: str, known: np.ndarray | None
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Levels of ``f`` with a finite response, their mean response and the factor's value
    there (NaN where it has none; ``known``: the values per level, else read from ``ds``);
    O(N) by ``bincount``."""
    codes = ds[f"{f}_level"].variable  # read a block of runs at a time
    n = level_count(codes)
    counts, sums = level_sums_in_blocks(codes, values_of(y.variable), n, finite)
    present = np.flatnonzero(counts)
    k = sums[present] / counts[present]
    value = np.full(present.size, np.nan)
    if known is not None:
        value = np.asarray(known, dtype=float)[present]
    elif f in ds.coords and np.issubdtype(ds[f].dtype, np.number):  # read at one run a level
        value = ds[f].isel(run=first_runs(codes, n)[present]).values.astype(float)
    return present, k, value


def _range_and_best(k: np.ndarray, sense: str) -> tuple[np.ndarray, np.ndarray]:
    """Range R of each row of level means and its best level (first of ties). Means equal to
    round-off (within ``ROUND_OFF`` of the largest |k|) are ties: R = 0, best = first level."""
    signed = k if sense == "smaller" else -k
    with np.errstate(invalid="ignore"):
        r = np.nanmax(k, axis=1) - np.nanmin(k, axis=1)
        tolerance = ROUND_OFF * np.nanmax(np.abs(k), axis=1)
        r = np.where(r <= tolerance, 0.0, r)
        best_value = np.nanmin(signed, axis=1)
        near = signed <= (best_value + tolerance)[:, None]
    return r, np.argmax(near, axis=1).astype(np.int64)


def _rank(r: np.ndarray, k: np.ndarray) -> np.ndarray:
    """Rank of each range (1 = largest); ranges within round-off of each other (``ROUND_OFF``
    of the largest |k|, the tolerance of R = 0) share the best of their ranks."""
    with np.errstate(invalid="ignore"):
        above = r[None, :] > r[:, None] + round_off_of(k)
    return 1 + np.count_nonzero(above, axis=1).astype(np.int64)


def range_analysis(
    ds: xr.Dataset,
    response: str,
    factors: Sequence[str] | None = None,
    sense: str | None = None,
    level_values: Mapping[str, np.ndarray] | None = None,
) -> xr.Dataset:
    """Range analysis of ``response``: level means k, range R, rank, best level per factor.

    ``sense`` is "smaller" or "larger" (is better); by default the response's ``better``
    attribute, else "smaller". Returns a Dataset on dims ``factor`` x ``level`` (0-based) with
    ``k`` (NaN where a factor has fewer levels), ``R``, ``rank`` (1 = largest R) and
    ``best_level``; coordinates ``level_value`` (the factor's value at each level, NaN where
    unknown or not numeric) and ``factor_units``. ``level_values``: each factor's value per
    level when known (an analysis of many responses reads them once, not per response).
    """
    names = _factor_names(ds, factors)
    y, finite = _response(ds, response)
    chosen = _sense(y, sense)
    known = level_values or {}
    tables = [_level_table(ds, y, finite, f, known.get(f)) for f in names]
    nlevels = max(int(present.max()) + 1 for present, _, _ in tables)
    k = np.full((len(names), nlevels), np.nan)
    level_value = np.full((len(names), nlevels), np.nan)
    for i, (present, means, values) in enumerate(tables):
        k[i, present] = means
        level_value[i, present] = values
    r, best = _range_and_best(k, chosen)
    units = y.attrs.get("units", "")
    long_name = y.attrs.get("long_name", response)
    factor_units = [str(ds[f].attrs.get("units", "")) if f in ds.coords else "" for f in names]
    return xr.Dataset(
        {
            "k": (("factor", "level"), k, {"units": units, "long_name": f"mean {long_name}"}),
            "R": ("factor", r, {"units": units, "long_name": "range of level means"}),
            "rank": ("factor", _rank(r, k), {"long_name": "rank of R (1 = largest)"}),
            "best_level": (
                "factor",
                best,
                {"long_name": f"level with the {chosen} mean (0-based)"},
            ),
        },
        coords={
            "factor": names,
            "level": np.arange(nlevels),
            "level_value": (("factor", "level"), level_value),
            "factor_units": ("factor", factor_units),
        },
        attrs={"response": response, "sense": chosen, "units": units, "long_name": long_name},
    )


def _f_test(ms: float, dof: int, ms_error: float, dof_error: int) -> tuple[float, float]:
    if dof == 0 or dof_error == 0:
        return np.nan, np.nan
    if ms_error == 0.0:  # no error term (an exact fit): no test
        return np.nan, np.nan
    f = ms / ms_error
    return f, f_survival(f, dof, dof_error)


def f_survival(f: float, dof: int, dof_error: int) -> float:
    """P(F > f) for Fisher's F(dof, dof_error): ``scipy.stats.f.sf`` without importing
    scipy.stats (a second of a small study's start-up). It is the same function (``fdtrc``),
    with stats' f < 0 → 1; equal to it bit for bit (tests/studies/test_analysis.py)."""
    return float(special.fdtrc(dof, dof_error, max(f, 0.0)))


def f_quantile(q: float, dof: int, dof_error: int) -> float:
    """The q-quantile of F(dof, dof_error): ``scipy.stats.f.ppf`` (``fdtri``), as above."""
    return float(special.fdtri(dof, dof_error, q))


def anova(
    ds: xr.Dataset,
    response: str,
    factors: Sequence[str] | None = None,
    error: Sequence[str] | None = None,
    pool: Sequence[str] | None = None,
    balanced: bool | None = None,
) -> pd.DataFrame:
    """ANOVA table of ``response``, indexed by source: each factor, "error", "total".

    Columns SS, dof, MS, F, P (F-distribution survival function), contribution (% of the total
    SS) and pooled. ``error`` names the empty columns that form the error term (default: the
    ``error_columns`` attribute); the error SS is everything the factors leave, so it also
    holds any other free degrees of freedom (e.g. a full factorial analysed for main effects).
    When the error has no degrees of freedom the factor with the smallest SS is pooled into
    it; ``pool=[...]`` pools the named factors instead (``pool=[]``: never pool; default: the
    ``pool`` attribute, from the study's ``[design] pool``, if there is one). Pooled rows
    keep their SS, dof and contribution, with F and P NaN; the error row includes them.
    ``df.attrs``: "response", "units" (of the response; SS in units²), "error_columns",
    "pooled" (list) and "note" (a sentence on pooling or dropped runs, else "").
    ``balanced``: whether the factors are balanced when every run has a value (True for a
    complete full factorial, by construction), else None: counted from the codes.
    """
    names = _factor_names(ds, factors)
    errors = _error_names(ds, error)
    clash = set(names) & set(errors)
    if clash:
        msg = f"{sorted(clash)} named both as factor and as error column"
        raise StudyError(msg)
    y_da, finite = _response(ds, response)
    complete = bool(finite.all())
    with ExitStack() as stack:  # the finite runs' values and codes, when too many to hold
        values = values_of(y_da.variable)  # an array in memory, else read a block at a time
        y = values if complete else _kept(values, finite, stack)
        codes = {  # complete: read a block of runs at a time; else the finite runs' codes
            f: ds[f"{f}_level"].variable
            if complete
            else _kept(ds[f"{f}_level"].variable, finite, stack)
            for f in names
        }
        return _table(ds, response, y_da, y, codes, finite, names, errors, pool, balanced)


def _table(
    ds: xr.Dataset,
    response: str,
    y_da: xr.DataArray,
    y: Any,
    codes: dict[str, Any],
    finite: np.ndarray,
    names: list[str],
    errors: list[str],
    pool: Sequence[str] | None,
    balanced: bool | None,
) -> pd.DataFrame:
    """The ANOVA table of :func:`anova` from the values ``y`` and ``codes`` it analyses."""
    complete = bool(finite.all())
    if pool is None and "pool" in ds.attrs:
        pool = json.loads(ds.attrs["pool"])
    pooled = list(pool) if pool is not None else []
    unknown = [p for p in pooled if p not in names]
    if unknown:
        msg = f"cannot pool {unknown}: not among the factors {names}"
        raise StudyError(msg)

    def fit(pooled: list[str]) -> dict[str, tuple[float, int]]:
        order = [f for f in names if f not in pooled] + pooled
        ss, dof, _ = term_sums_of_squares(
            y, [codes[f] for f in order], balanced if complete else None
        )
        return {f: (float(s), int(n)) for f, s, n in zip(order, ss, dof, strict=True)}

    terms = fit(pooled)
    ss_total, dof_total = Centred(y).squares(), y.size - 1
    notes = []
    if finite.sum() < finite.size:
        notes.append(
            f"{finite.size - finite.sum()} run(s) with no finite value (NaN or ±inf) left out."
        )
    free_dof = dof_total - sum(d for _, d in terms.values())
    if pool is None and free_dof == 0:
        smallest = min(names, key=lambda f: terms[f][0])
        pooled = [smallest]
        terms = fit(pooled)
        notes.append(
            f"The error term had no degrees of freedom, so {smallest} (smallest SS) "
            "was pooled into error."
        )
    elif pooled:
        notes.append(f"{', '.join(pooled)} pooled into error as requested.")
    elif free_dof == 0:
        notes.append("The error term has no degrees of freedom: F and P cannot be computed.")
    kept = [f for f in names if f not in pooled]
    ss_error = float(
        without_round_off(np.array([ss_total - sum(terms[f][0] for f in kept)]), ss_total)[0]
    )
    ss_error = max(ss_error, 0.0)
    dof_error = dof_total - sum(terms[f][1] for f in kept)
    ms_error = ss_error / dof_error if dof_error else np.nan
    if dof_error and ss_error == 0.0 and ss_total > 0.0:  # F = MS/0 would print as "inf"
        notes.append(
            "No error term (an exact fit: the terms explain every run, the error SS is 0): "
            "F and P cannot be computed."
        )

    def contribution(ss: float) -> float:
        return 100.0 * ss / ss_total if ss_total > 0.0 else np.nan

    rows = {}
    for f in names:
        ss, dof = terms[f]
        ms = ss / dof if dof else np.nan
        f_value, p = _f_test(ms, dof, ms_error, dof_error) if f in kept else (np.nan, np.nan)
        rows[f] = (ss, dof, ms, f_value, p, contribution(ss), f in pooled)
    rows["error"] = (ss_error, dof_error, ms_error, np.nan, np.nan, contribution(ss_error), False)
    rows["total"] = (ss_total, dof_total, np.nan, np.nan, np.nan, contribution(ss_total), False)
    table = pd.DataFrame.from_dict(
        rows,
        orient="index",
        columns=["SS", "dof", "MS", "F", "P", "contribution", "pooled"],
    )
    table.index.name = "source"
    table.attrs = {
        "response": response,
        "units": y_da.attrs.get("units", ""),
        "error_columns": errors,
        "pooled": pooled,
        "note": " ".join(notes),
    }
    return table


def _kept(values: Any, keep: np.ndarray, stack: ExitStack) -> Any:
    """The values (level codes, a response) of the runs ``keep`` selects, gathered a block of
    runs at a time into an array, or a scratch file when above a block
    (:func:`studies.analysis.scratch.column`, closed with ``stack``)."""
    dtype = np.asarray(values[0:1]).dtype
    out = scratch.column(int(np.count_nonzero(keep)), dtype, stack)
    at = 0
    for part in run_slices(len(values)):
        chosen = np.asarray(values[part])[keep[part]]
        out[at : at + chosen.size] = chosen
        at += chosen.size
    return out


def sweep_runs(ds: xr.Dataset, factor: str) -> xr.Dataset:
    """The runs of a one-factor sweep that move ``factor`` (plus the base run), by value."""
    swept = ds["swept_factor"].values
    keep = (swept == factor) | (swept == "base")
    return ds.isel(run=np.flatnonzero(keep)).sortby(factor)


def status_counts(y: xr.DataArray) -> xr.DataArray:
    """How many observations carry each value of a status code (``flag_values``) or each bit
    of a status mask (``flag_masks``; ``ok`` = no bit set), on the dimension ``<name>_flag``
    labelled with the CF flag meanings. A point counts once per bit it has set."""
    values = np.asarray(y.values).astype(np.int64).ravel()
    meanings = str(y.attrs["flag_meanings"]).split()
    if "flag_masks" in y.attrs:
        seen = values[values >= 0]
        masks = np.asarray(y.attrs["flag_masks"], dtype=np.int64)
        counts = [int((seen == 0).sum()), *(int(((seen & m) != 0).sum()) for m in masks)]
        labels, counts = ["ok", *meanings, "not_evaluated"], [*counts, int((values < 0).sum())]
    else:
        codes = np.asarray(y.attrs["flag_values"], dtype=np.int64)
        labels = meanings
        counts = list(np.bincount(values - codes[0], minlength=codes.size)[: codes.size])
    dim = f"{y.name}_flag"
    return xr.DataArray(
        np.asarray(counts, dtype=np.int64),
        dims=dim,
        coords={dim: labels},
        attrs={
            "units": "1",
            "long_name": f"design points by {y.name}",
            "comment": str(y.attrs.get("long_name", "")),
        },
    )
