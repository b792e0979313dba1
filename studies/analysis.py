"""The analysis of a run, computed once: one ``xarray.Dataset`` that every renderer reads.

:func:`analyze` computes, per analysed variable (the study's responses, run means of
replicated ones, and their S/N ratios where Taguchi's S/N applies), everything that
``analysis.txt``, ``report.md`` and the figures show; it is written as ``analysis.nc`` beside
``results.nc``. The renderers (:mod:`studies.analysis_text`, :mod:`studies.markdown_report`,
:mod:`studies.plots`) compute no statistics.

Dimensions: ``response`` (the analysed variables), ``term`` (factors, then interaction
columns), ``level`` (0-based), ``source`` (the ANOVA rows: terms, ``error``, ``total``),
``interaction`` (assigned factor pairs of an orthogonal array), ``pair`` (every factor pair of
a full factorial) and ``level_a`` × ``level_b`` for two-way tables of means.

* range analysis: ``k``, ``R``, ``rank``, ``best_level`` (over the terms), ``grand_mean``
  (``pass_fail`` marks 0/1 checks, whose means are shares passing);
* ANOVA: ``SS``, ``dof``, ``MS``, ``F``, ``P``, ``contribution`` [%], ``pooled`` on
  (response, source), ``anova_note``;
* predicted optimum: ``optimum_level`` (per term; -1 for interaction columns), ``predicted``,
  ``half_width``, ``confirmation_half_width``, ``n_eff``, ``error_ms``, ``error_dof``,
  ``model_terms``;
* interactions of arrays: ``interaction_SS`` … and ``interaction_mean`` (response,
  interaction, level_a, level_b);
* full factorials (complete, the computer-experiment view): ``main_SS``, ``pair_SS``,
  ``remainder_SS``, ``first_order`` and ``total_effect`` Sobol indices, and the two-way
  mean over the strongest factor pair (``map_mean``, factors in ``map_x``/``map_y``);
* status codes and bit masks (counted, never averaged): ``<response>_count`` on
  ``<response>_flag`` (the CF flag meanings), the names in the attribute ``status_responses``;
* several responses: the trade-off (``chosen_level``, ``decided_by``, ``conflict`` per term,
  ``compromise`` and ``compromise_half_width`` per response).

Variables that hold a response's values carry its units in the ``units`` variable (per
response); the ANOVA SS are in units².
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from studies import prediction, taguchi, tradeoff
from studies.results import NOT_EVALUATED, PASS_FAIL, grid_order, is_status, write_netcdf
from studies.sensitivity import decompose
from studies.statistics import (
    SENSES,
    anova,
    has_values,
    range_analysis,
    status_counts,
    sweep_runs,
)

__all__ = ["SENSES", "analyze", "anova", "has_values", "range_analysis", "sweep_runs"]

ANALYSIS_NAME = "analysis.nc"
SOURCE_COLUMNS = ("SS", "dof", "MS", "F", "P", "contribution")
INTERACTION_COLUMNS = ("SS", "dof", "F", "P", "contribution")


def presence(ds: xr.Dataset, responses: Sequence[str]) -> tuple[list[str], int]:
    """The responses with a value in some run, and the number of runs with no value in any
    response (NaN, or -1 "not evaluated" for flags and status codes): points that did not run.
    Reads each response once."""
    present, any_value = [], np.zeros(ds.sizes["run"], dtype=bool)
    for r in responses:
        values = ds[r].values
        has = values != NOT_EVALUATED if values.dtype.kind == "i" else np.isfinite(values)
        has = has.reshape(values.shape[0], -1).any(axis=1)
        if has.any():
            present.append(r)
        any_value |= has
    return present, int((~any_value).sum())


def analyzed(ds: xr.Dataset, responses: Sequence[str]) -> tuple[xr.Dataset, list[str], int]:
    """The results with run means and S/N ratios added, the variables to analyse (each
    response with a finite value, or its run mean when replicated, then its S/N ratio) and the
    number of runs without any value."""
    present, without = presence(ds, responses)
    present = [r for r in present if not is_status(ds[r])]
    view = taguchi.with_sn(taguchi.with_means(ds, present), taguchi.sn_responses(ds, present))
    names = [taguchi.mean_name(view, r) for r in present]
    names += [taguchi.sn_name(r) for r in present if taguchi.sn_name(r) in view]
    return view, names, without


def analyze(
    ds: xr.Dataset, responses: Sequence[str] | None = None, pool: Sequence[str] | None = None
) -> xr.Dataset:
    """Everything the outputs of a run show, computed once (see the module docstring).

    ``responses`` default to the study's (attribute ``responses``); ``pool`` is passed to every
    ANOVA (default: the study's ``[design] pool``, else pool only when the error has no dof).
    """
    names = list(responses or json.loads(ds.attrs.get("responses", "[]")))
    design = str(ds.attrs.get("design", ""))
    attrs = {
        "design": design,
        "responses": json.dumps(names),
        "alpha": taguchi.ALPHA,
        "confirmation_runs": 1,
    }
    status = [r for r in names if is_status(ds[r])]
    counts = {f"{r}_count": status_counts(ds[r]) for r in status}
    attrs["status_responses"] = json.dumps(status)
    if design == "sweep":  # tables and plots of the runs themselves: nothing to estimate
        present, without = presence(ds, names)
        present = [r for r in present if r not in status]
        attrs |= {"points": ds.sizes["run"], "points_without_value": without}
        return xr.Dataset(counts, attrs=attrs | {"analysed": json.dumps(present)})
    view, analysed, without = analyzed(ds, names)
    attrs |= {"points": ds.sizes["run"], "points_without_value": without}
    terms = taguchi.model_terms(view)
    # The level codes once in memory, then one response at a time: a 10⁷-run result is never
    # held whole.
    base = view.drop_vars(list(view.data_vars))
    base = base.assign_coords(
        {f"{t}_level": base[f"{t}_level"].variable.copy(deep=False).load() for t in terms}
    )  # the level codes stay in memory (4 B per run and term); factor values are read on use
    out = _frame(base, view, analysed, terms)
    grid = _grid(base) if design == "full_factorial" else None
    if grid is not None:
        _factorial_frame(out, grid)
    tables, optima = {}, {}
    for name in analysed:
        # a bare Variable: no coordinates to compare (and load) on assignment; view stays lazy
        one = base.assign({name: view[name].variable.copy(deep=False).load()})
        out["varies"].loc[name] = int(taguchi.varies(one, name))
        tables[name] = anova(one, name, factors=terms, pool=pool)
        _range(out, one, name, terms)
        _anova(out, tables[name], name)
        optima[name] = _optimum(out, one, name, tables[name])
        _interactions(out, one, name, tables[name])
        if grid is not None:
            _factorial(out, one, name, grid)
    sn = {taguchi.sn_name(r) for r in names}
    optimised = [n for n in analysed if n not in sn and int(out["varies"].loc[n])]
    if len(optimised) > 1:
        lazy = base.assign({n: view[n].variable for n in optimised})
        _tradeoff(out, lazy, optimised, tables, optima)
    for r in names:  # run means of replicated responses, for the renderers' run tables
        if taguchi.mean_name(view, r) != r and taguchi.mean_name(view, r) in analysed:
            out[taguchi.mean_name(view, r)] = view[taguchi.mean_name(view, r)]
    out = out.assign(counts)
    out.attrs = attrs | {"analysed": json.dumps(analysed)}
    return out


def write_analysis_nc(an: xr.Dataset, folder: Path) -> Path:
    """Write the analysis Dataset as ``analysis.nc`` in ``folder``."""
    return write_netcdf(an, Path(folder) / ANALYSIS_NAME)


# --- the frame ------------------------------------------------------------------------------
def _frame(base: xr.Dataset, view: xr.Dataset, names: list[str], terms: list[str]) -> xr.Dataset:
    nlevels = max(int(base[f"{t}_level"].max()) + 1 for t in terms) if terms else 1
    pairs = list(taguchi.interaction_pairs(view))
    sources = [*terms, "error", "total"]
    nan = np.nan

    def full(dims: tuple[str, ...], value: Any = nan, dtype: Any = float) -> tuple:
        shape = tuple(sizes[d] for d in dims)
        return dims, np.full(shape, value, dtype=dtype)

    sizes = {
        "response": len(names),
        "term": len(terms),
        "level": nlevels,
        "source": len(sources),
        "interaction": len(pairs),
        "level_a": nlevels,
        "level_b": nlevels,
    }
    rt, rs = ("response", "term"), ("response", "source")
    data = {
        "varies": full(("response",), 0, np.int8),
        "units": ("response", [str(view[n].attrs.get("units", "")) for n in names]),
        "long_name": ("response", [str(view[n].attrs.get("long_name", n)) for n in names]),
        "sense": ("response", [str(view[n].attrs.get("better", "smaller")) for n in names]),
        "sn_kind": ("response", [str(view[n].attrs.get("sn_kind", "")) for n in names]),
        "pass_fail": (
            "response",
            [int(view[n].attrs.get("flag_meanings") == PASS_FAIL) for n in names],
        ),
        "observations": ("response", [int(view[n].attrs.get("observations", 0)) for n in names]),
        "grand_mean": full(("response",)),
        "k": full(("response", "term", "level")),
        "R": full(rt),
        "rank": full(rt, 0, np.int32),
        "best_level": full(rt, -1, np.int32),
        **{c: full(rs) for c in SOURCE_COLUMNS},
        "pooled": full(rs, 0, np.int8),
        "anova_note": ("response", np.full(len(names), "", dtype=object)),
        "optimum_level": full(rt, -1, np.int32),
        "model_terms": ("response", np.full(len(names), "", dtype=object)),
        **{
            v: full(("response",))
            for v in ("predicted", "half_width", "confirmation_half_width", "n_eff", "error_ms")
        },
        "error_dof": full(("response",), 0, np.int64),
        **{f"interaction_{c}": full(("response", "interaction")) for c in INTERACTION_COLUMNS},
        "interaction_pooled": full(("response", "interaction"), 0, np.int8),
        "interaction_mean": full(("response", "interaction", "level_a", "level_b")),
    }
    value, label, units = _level_values(base, terms, nlevels)
    coords = {
        "response": names,
        "term": terms,
        "level": np.arange(nlevels),
        "source": sources,
        "interaction": [f"{a} x {b}" for a, b in pairs],
        "level_value": (("term", "level"), value),
        "level_label": (("term", "level"), label),
        "term_units": ("term", units),
        "is_factor": ("term", [int(t in taguchi.factor_names(view)) for t in terms]),
        "interaction_a": ("interaction", [a for a, _ in pairs]),
        "interaction_b": ("interaction", [b for _, b in pairs]),
    }
    return xr.Dataset(data, coords=coords)


def _level_values(
    base: xr.Dataset, terms: list[str], nlevels: int
) -> tuple[np.ndarray, np.ndarray, list[str]]:
    """Each term's value at each level (NaN where not numeric or absent), its label ("" where
    absent: the value as text, or the 1-based level number without a value) and its units."""
    value = np.full((len(terms), nlevels), np.nan)
    label = np.full((len(terms), nlevels), "", dtype=object)
    units = []
    for i, t in enumerate(terms):
        numeric = t in base.coords and np.issubdtype(base[t].dtype, np.number)
        for level, v in taguchi.level_values(base, t).items():
            label[i, level] = str(v)
            if numeric:
                value[i, level] = float(v)
        units.append(str(base[t].attrs.get("units", "")) if t in base.coords else "")
    return value, label, units


# --- per response ---------------------------------------------------------------------------
def _range(out: xr.Dataset, view: xr.Dataset, name: str, terms: list[str]) -> None:
    ra = range_analysis(view, name, terms)
    at = {"response": name}
    out["k"].loc[at] = np.pad(
        ra.k.values, ((0, 0), (0, out.sizes["level"] - ra.sizes["level"])), constant_values=np.nan
    )
    for v in ("R", "rank", "best_level"):
        out[v].loc[at] = ra[v].values
    y = view[name].values.astype(float)
    out["grand_mean"].loc[at] = float(np.mean(y[np.isfinite(y)]))


def _anova(out: xr.Dataset, table: Any, name: str) -> None:
    at = {"response": name}
    for c in SOURCE_COLUMNS:
        out[c].loc[at] = table[c].to_numpy(dtype=float)
    out["pooled"].loc[at] = table["pooled"].to_numpy(dtype=np.int8)
    out["anova_note"].loc[at] = table.attrs["note"]


def _optimum(out: xr.Dataset, view: xr.Dataset, name: str, table: Any) -> prediction.Prediction:
    p = prediction.predict_optimum(view, name, table=table)
    at = {"response": name}
    levels = [p.levels.get(t, -1) for t in out["term"].values]
    out["optimum_level"].loc[at] = levels
    out["model_terms"].loc[at] = ",".join(p.terms)
    for v, value in (
        ("predicted", p.mean),
        ("half_width", p.half_width),
        ("confirmation_half_width", p.confirmation_half_width),
        ("n_eff", p.n_eff),
        ("error_ms", p.error_ms),
        ("error_dof", p.error_dof),
    ):
        out[v].loc[at] = value
    return p


def _interactions(out: xr.Dataset, view: xr.Dataset, name: str, table: Any) -> None:
    if not out.sizes["interaction"]:
        return
    inter = taguchi.interaction_anova(table, view)
    at = {"response": name}
    for c in INTERACTION_COLUMNS:
        out[f"interaction_{c}"].loc[at] = inter[c].to_numpy(dtype=float)
    out["interaction_pooled"].loc[at] = inter["pooled"].to_numpy(dtype=np.int8)
    for i, (a, b) in enumerate(taguchi.interaction_pairs(view)):
        means = taguchi.interaction_means(view, name, a, b)
        la, lb = means[f"{a}_level"].values, means[f"{b}_level"].values
        block = out["interaction_mean"].values[out.indexes["response"].get_loc(name), i]
        block[np.ix_(la, lb)] = means.values


# --- full factorial: the computer-experiment view -------------------------------------------
def _grid(base: xr.Dataset) -> tuple[list[str], tuple[int, ...], np.ndarray] | None:
    """Factors, level counts and grid order of a complete full factorial (None otherwise)."""
    try:
        return grid_order(base)
    except ValueError:
        return None


def _factorial_frame(out: xr.Dataset, grid: tuple[list[str], tuple[int, ...], np.ndarray]) -> None:
    """The full-factorial variables (NaN until a response fills them) and their coordinates."""
    factors, counts, _ = grid
    nr, nf, most = out.sizes["response"], len(factors), max(counts)
    pairs = [f"{a} x {b}" for i, a in enumerate(factors) for b in factors[i + 1 :]]
    out.update(
        {
            "main_SS": (("response", "factor"), np.full((nr, nf), np.nan)),
            "first_order": (("response", "factor"), np.full((nr, nf), np.nan)),
            "total_effect": (("response", "factor"), np.full((nr, nf), np.nan)),
            "pair_SS": (("response", "pair"), np.full((nr, len(pairs)), np.nan)),
            "remainder_SS": ("response", np.full(nr, np.nan)),
            "total_SS": ("response", np.full(nr, np.nan)),
            "map_x": ("response", np.full(nr, "", dtype=object)),
            "map_y": ("response", np.full(nr, "", dtype=object)),
            "map_mean": (
                ("response", "map_level_y", "map_level_x"),
                np.full((nr, most, most), np.nan),
            ),
        }
    )
    out.coords["factor"] = factors
    out.coords["pair"] = pairs


def _factorial(
    out: xr.Dataset,
    one: xr.Dataset,
    name: str,
    grid: tuple[list[str], tuple[int, ...], np.ndarray],
) -> None:
    """Main, two-factor and remainder SS and Sobol indices of a response that is finite in
    every run of a complete full factorial (otherwise the grid has holes: left NaN)."""
    factors, counts, order = grid
    y = one[name].values.astype(float)[order]
    if not np.isfinite(y).all():
        return
    i = out.indexes["response"].get_loc(name)
    values = y.reshape(counts)
    dec = decompose(values, tuple(factors))
    out["main_SS"].values[i], out["pair_SS"].values[i] = dec.main, dec.pair
    out["first_order"].values[i], out["total_effect"].values[i] = dec.first_order, dec.total_effect
    out["remainder_SS"].values[i], out["total_SS"].values[i] = dec.remainder, dec.total
    if len(factors) >= 2:
        a, b = np.argsort(-dec.total_effect, kind="stable")[:2]
        x, yy = sorted((int(a), int(b)))
        mean = values.mean(axis=tuple(k for k in range(len(factors)) if k not in (x, yy)))
        out["map_x"].values[i], out["map_y"].values[i] = factors[x], factors[yy]
        out["map_mean"].values[i, : counts[yy], : counts[x]] = mean.T


# --- several responses ----------------------------------------------------------------------
def _tradeoff(
    out: xr.Dataset,
    view: xr.Dataset,
    names: list[str],
    tables: dict[str, Any],
    optima: dict[str, prediction.Prediction],
) -> None:
    result = tradeoff.tradeoff(
        view, names, tables={n: tables[n] for n in names}, optima={n: optima[n] for n in names}
    )
    terms = list(out["term"].values)
    table = result.table
    out["chosen_level"] = ("term", np.array([result.levels.get(t, -1) for t in terms], np.int32))
    out["decided_by"] = (
        "term",
        np.array(
            [str(table.loc[t, "decided by"]) if t in table.index else "" for t in terms], object
        ),
    )
    out["conflict"] = (
        "term",
        np.array([int(bool(table.loc[t, "conflict"])) if t in table.index else 0 for t in terms]),
    )
    compromise = np.full(out.sizes["response"], np.nan)
    half = np.full(out.sizes["response"], np.nan)
    for n, row in result.predictions.iterrows():
        i = out.indexes["response"].get_loc(n)
        compromise[i], half[i] = row["compromise"], row["half width"]
    out["compromise"] = ("response", compromise)
    out["compromise_half_width"] = ("response", half)
