"""Range analysis and analysis of variance of a study's results.

Both work on the results Dataset (see :mod:`studies.results`): dimension ``run``; for each
factor ``f`` the coordinates ``f`` (physical value, with ``units``) and ``f_level`` (0-based
level index); empty orthogonal-array columns as ``<name>_level`` coordinates only, named in the
global attribute ``error_columns``; factor names in the attribute ``factors`` (both JSON lists).
Runs whose response is NaN (failed cases) are left out.

Range analysis (Taguchi's "k, R" table): k_i = mean response at level i, R = max k - min k,
rank by R, best level by the sense of the response. ANOVA: sums of squares of the factor terms
in order (type I, as statsmodels' ``anova_lm(typ=1)``; for an orthogonal array they are
Taguchi's level sums SS = Σ n_i (k_i - ȳ)²; computed in O(N) by
:mod:`studies.sums_of_squares`), error = what the factors leave (the empty columns
and any other free degrees of freedom), F = MS / MS_error with P from the F distribution.
"""

from __future__ import annotations

import json
from collections.abc import Sequence

import numpy as np
import pandas as pd
import xarray as xr
from scipy import stats

from studies.sums_of_squares import centred, term_sums_of_squares

SENSES = ("smaller", "larger")


def _factor_names(ds: xr.Dataset, factors: Sequence[str] | None) -> list[str]:
    if factors is None:
        if "factors" not in ds.attrs:
            msg = "the Dataset has no 'factors' attribute: pass factors=[...]"
            raise ValueError(msg)
        factors = json.loads(ds.attrs["factors"])
    names = list(factors)
    missing = [f for f in names if f"{f}_level" not in ds.coords]
    if missing:
        msg = f"no level coordinate for factor(s) {missing} (expected '<factor>_level' on run)"
        raise ValueError(msg)
    return names


def _error_names(ds: xr.Dataset, error: Sequence[str] | None) -> list[str]:
    if error is None:
        error = json.loads(ds.attrs.get("error_columns", "[]"))
    names = list(error)
    missing = [e for e in names if f"{e}_level" not in ds.coords]
    if missing:
        msg = f"no level coordinate for error column(s) {missing} (expected '<name>_level')"
        raise ValueError(msg)
    return names


def has_values(ds: xr.Dataset, response: str) -> bool:
    """True if ``response`` is finite in some run (one NaN everywhere has nothing to analyse)."""
    return bool(np.isfinite(ds[response].values.astype(float)).any())


def _response(ds: xr.Dataset, response: str) -> tuple[xr.DataArray, np.ndarray]:
    """The response and the mask of runs where it is finite."""
    if response not in ds.data_vars:
        msg = f"no response {response!r}; the Dataset has {sorted(map(str, ds.data_vars))}"
        raise ValueError(msg)
    y = ds[response]
    if y.dims != ("run",):
        msg = f"{response!r} has dims {y.dims}; analysis needs a scalar response on 'run'"
        raise ValueError(msg)
    finite = np.isfinite(y.values.astype(float))
    if not finite.any():
        msg = f"{response!r} has no finite value to analyse"
        raise ValueError(msg)
    return y, finite


def _sense(y: xr.DataArray, sense: str | None) -> str:
    chosen = sense if sense is not None else y.attrs.get("better", "smaller")
    if chosen not in SENSES:
        msg = f"sense must be one of {SENSES}, got {chosen!r}"
        raise ValueError(msg)
    return chosen


def _level_table(ds: xr.Dataset, y: xr.DataArray, finite: np.ndarray, f: str) -> pd.DataFrame:
    """Per level of ``f``: mean response and the factor's value (first run at that level)."""
    values = ds[f].values if f in ds.coords else np.full(y.size, np.nan)
    frame = pd.DataFrame(
        {"level": ds[f"{f}_level"].values, "y": y.values.astype(float), "value": values}
    )[finite]
    return frame.groupby("level").agg(k=("y", "mean"), value=("value", "first"))


def range_analysis(
    ds: xr.Dataset, response: str, factors: Sequence[str] | None = None, sense: str | None = None
) -> xr.Dataset:
    """Range analysis of ``response``: level means k, range R, rank, best level per factor.

    ``sense`` is "smaller" or "larger" (is better); by default the response's ``better``
    attribute, else "smaller". Returns a Dataset on dims ``factor`` x ``level`` (0-based) with
    ``k`` (NaN where a factor has fewer levels), ``R``, ``rank`` (1 = largest R) and
    ``best_level``; coordinates ``level_value`` (the factor's value at each level, NaN where
    unknown or not numeric) and ``factor_units``.
    """
    names = _factor_names(ds, factors)
    y, finite = _response(ds, response)
    chosen = _sense(y, sense)
    tables = [_level_table(ds, y, finite, f) for f in names]
    nlevels = max(int(t.index.max()) + 1 for t in tables)
    k = np.full((len(names), nlevels), np.nan)
    level_value = np.full((len(names), nlevels), np.nan)
    for i, table in enumerate(tables):
        k[i, table.index] = table["k"].to_numpy()
        if pd.api.types.is_numeric_dtype(table["value"]):
            level_value[i, table.index] = table["value"].to_numpy()
    means = pd.DataFrame(k, index=names)
    r = means.max(axis=1) - means.min(axis=1)
    best = means.idxmin(axis=1) if chosen == "smaller" else means.idxmax(axis=1)
    units = y.attrs.get("units", "")
    long_name = y.attrs.get("long_name", response)
    factor_units = [str(ds[f].attrs.get("units", "")) if f in ds.coords else "" for f in names]
    return xr.Dataset(
        {
            "k": (("factor", "level"), k, {"units": units, "long_name": f"mean {long_name}"}),
            "R": ("factor", r.to_numpy(), {"units": units, "long_name": "range of level means"}),
            "rank": (
                "factor",
                r.rank(ascending=False, method="min").to_numpy(dtype=np.int64),
                {"long_name": "rank of R (1 = largest)"},
            ),
            "best_level": (
                "factor",
                best.to_numpy(dtype=np.int64),
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
    if ms_error == 0.0:
        return (np.inf, 0.0) if ms > 0.0 else (np.nan, np.nan)
    f = ms / ms_error
    return f, float(stats.f.sf(f, dof, dof_error))


def anova(
    ds: xr.Dataset,
    response: str,
    factors: Sequence[str] | None = None,
    error: Sequence[str] | None = None,
    pool: Sequence[str] | None = None,
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
    """
    names = _factor_names(ds, factors)
    errors = _error_names(ds, error)
    clash = set(names) & set(errors)
    if clash:
        msg = f"{sorted(clash)} named both as factor and as error column"
        raise ValueError(msg)
    y_da, finite = _response(ds, response)
    y = y_da.values.astype(float)[finite]
    codes = {f: ds[f"{f}_level"].values[finite] for f in names}
    if pool is None and "pool" in ds.attrs:
        pool = json.loads(ds.attrs["pool"])
    pooled = list(pool) if pool is not None else []
    unknown = [p for p in pooled if p not in names]
    if unknown:
        msg = f"cannot pool {unknown}: not among the factors {names}"
        raise ValueError(msg)

    def fit(pooled: list[str]) -> dict[str, tuple[float, int]]:
        order = [f for f in names if f not in pooled] + pooled
        ss, dof, _ = term_sums_of_squares(y, [codes[f] for f in order])
        return {f: (float(s), int(n)) for f, s, n in zip(order, ss, dof, strict=True)}

    terms = fit(pooled)
    ss_total, dof_total = float(np.sum(centred(y) ** 2)), y.size - 1
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
    ss_error = max(ss_total - sum(terms[f][0] for f in kept), 0.0)
    dof_error = dof_total - sum(terms[f][1] for f in kept)
    ms_error = ss_error / dof_error if dof_error else np.nan

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


def _number(value: float) -> str:
    return "—" if not np.isfinite(value) else f"{value:.4g}"


def format_tables(
    ds: xr.Dataset,
    response: str,
    factors: Sequence[str] | None = None,
    sense: str | None = None,
    error: Sequence[str] | None = None,
    pool: Sequence[str] | None = None,
) -> str:
    """Range-analysis and ANOVA tables of ``response`` as text, with units."""
    ra = range_analysis(ds, response, factors, sense)
    table = anova(ds, response, factors, error, pool)
    units = ra.attrs["units"]
    unit = f" [{units}]" if units else ""
    nlevels = ra.sizes["level"]
    rows = []
    for f in ra.factor.values:
        r = ra.sel(factor=f)
        values = [v for v in r.level_value.values if np.isfinite(v)]
        fu = str(r.factor_units.values)
        best = int(r.best_level)
        best_value = r.level_value.values[best]
        rows.append(
            {
                "factor": f,
                "levels": ", ".join(_number(v) for v in values) + (f" {fu}" if fu else ""),
                **{f"k{i + 1}": _number(r.k.values[i]) for i in range(nlevels)},
                "R": _number(float(r.R)),
                "rank": int(r["rank"]),
                "best": f"{best + 1}"
                + (f" ({_number(best_value)} {fu})".rstrip() if np.isfinite(best_value) else ""),
            }
        )
    ra_text = pd.DataFrame(rows).to_string(index=False)
    shown = table.copy()
    shown.index = [
        f"{s} (pooled)" if p else s for s, p in zip(table.index, table["pooled"], strict=True)
    ]
    shown = shown.drop(columns="pooled").rename(columns={"contribution": "contribution %"})
    anova_text = shown.to_string(
        formatters=dict.fromkeys(["SS", "MS", "F", "P", "contribution %"], _number), na_rep=""
    )
    ss_unit = f" (SS in ({units})^2)" if units not in ("", "1", "-") else ""
    lines = [
        (
            f"Range analysis of {response} ({ra.attrs['long_name']}){unit}; "
            f"{ra.attrs['sense']} is better; k_i = mean at level i"
        ),
        ra_text,
        "",
        f"ANOVA of {response}{ss_unit}",
        anova_text,
    ]
    if table.attrs["note"]:
        lines.append(f"Note: {table.attrs['note']}")
    return "\n".join(lines)


def sweep_runs(ds: xr.Dataset, factor: str) -> xr.Dataset:
    """The runs of a one-factor sweep that move ``factor`` (plus the base run), by value."""
    swept = ds["swept_factor"].values
    keep = (swept == factor) | (swept == "base")
    return ds.isel(run=np.flatnonzero(keep)).sortby(factor)


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
