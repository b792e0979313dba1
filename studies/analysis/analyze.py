"""The analysis of a run, computed once: one ``xarray.Dataset`` that every renderer reads.

:func:`analyze` computes, per analysed variable (the study's responses, run means of
replicated ones, and their S/N ratios where Taguchi's S/N applies), everything that
``analysis.txt``, ``report.md`` and the figures show; it is written as ``analysis.nc`` beside
``results.nc``. The renderers (:mod:`studies.report.text`, :mod:`studies.report.markdown_report`,
:mod:`studies.report.plots`) compute no statistics.

Dimensions: ``response`` (the analysed variables), ``term`` (factors, then interaction
columns), ``level`` (0-based), ``source`` (the ANOVA rows: terms, ``error``, ``total``),
``interaction`` (assigned factor pairs of an orthogonal array), ``pair`` (every factor pair of
a full factorial) and ``level_a`` × ``level_b`` for two-way tables of means.

* range analysis: ``k``, ``R``, ``rank``, ``best_level`` (over the terms; -1 for operating
  factors, interaction columns and a range of 0), ``grand_mean`` (``pass_fail`` marks 0/1
  checks, whose means are shares passing);
* runs without a finite value (:mod:`studies.analysis.missing`): ``none_means`` (response), per level
  ``left_out`` (runs the analysis leaves out) and ``bounded`` (runs counted at the best or worst
  value seen, ``best_bound`` / ``worst_bound``) on (response, term, level);
* ANOVA: ``SS``, ``dof``, ``MS``, ``F``, ``P``, ``contribution`` [%], ``pooled`` on
  (response, source), ``anova_note``;
* the optimum of the control factors (:mod:`studies.analysis.optimum`): the best computed
  point of a full factorial or the additive prediction of an array, per operating condition;
* interactions of arrays: ``interaction_SS`` … and ``interaction_mean`` (response,
  interaction, level_a, level_b);
* full factorials (complete, the computer-experiment view): ``main_SS``, ``pair_SS``,
  ``remainder_SS``, ``first_order`` and ``total_effect`` Sobol indices, and the two-way
  mean over the strongest factor pair (``map_mean``, factors in ``map_x``/``map_y``);
* status codes and bit masks (counted, never averaged): ``<response>_count`` on
  ``<response>_flag`` (the CF flag meanings), the names in the attribute ``status_responses``;
* responses under noise (:mod:`studies.analysis.uncertainty.noise_statistics`): per design point ``noise_mean``,
  ``noise_sd``, ``noise_quantile`` and, for responses with ``[limits]``, the probability of
  violating the limit with its Wilson interval, on (``noise_response``, ``run``), and its
  ``violation_map`` (:mod:`studies.analysis.uncertainty.violation_map`); S/N and means as replicates;
* a Saltelli design (:mod:`studies.analysis.uncertainty.sobol_indices`): ``S1``, ``S1_conf``, ``ST``,
  ``ST_conf`` on (response, factor) (and ``S2``, ``S2_conf`` where asked) instead of
  everything above; a Sobol' or Latin-hypercube sample
  (:mod:`studies.analysis.uncertainty.sample_statistics`): moments, quantiles and correlations instead;
* several responses: the trade-off (``chosen_level``, ``decided_by``, ``conflict`` per term,
  ``compromise``, ``compromise_worst``, ``compromise_half_width`` and
  ``compromise_confirmation_half_width`` per response and
  ``compromise_at`` per condition).

Coordinates ``term_role`` ("control", "operating", "model" or "column") and ``condition`` (the
labels of the operating conditions: model rungs count among them); attributes
``operating_factors`` (model factors included), ``model_factors`` and ``optimum_basis``.

Variables that hold a response's values carry its units in the ``units`` variable (per
response); the ANOVA SS are in units².
"""

from __future__ import annotations

import json
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from studies.analysis import grid_codes, missing, prediction, scratch, taguchi
from studies.analysis import optimum as analysis_optimum
from studies.analysis.factorial import factorial, factorial_frame
from studies.analysis.filled_array import filled_variable
from studies.analysis.grid_optimum import Grid
from studies.analysis.statistics import (
    SENSES,
    UNRANKED,
    anova,
    has_values,
    range_analysis,
    status_counts,
    sweep_runs,
)
from studies.analysis.uncertainty.noise_statistics import robust_statistics
from studies.analysis.uncertainty.sample_statistics import sample_analysis
from studies.analysis.uncertainty.sobol_indices import sobol_analysis
from studies.analysis.uncertainty.violation_map import with_violation_maps
from studies.common import blocks as run_blocks
from studies.common.blocks import (
    blocks,
    compact_codes,
    finite_summary,
    level_count,
    run_slices,
    values_of,
)
from studies.common.run_masks import false_count, run_mask
from studies.define.sampling import SAMPLING_DESIGNS
from studies.run.results import NOT_EVALUATED, PASS_FAIL, is_status, write_netcdf

__all__ = ["SENSES", "analyze", "anova", "has_values", "range_analysis", "sweep_runs"]

ANALYSIS_NAME = "analysis.nc"
SOURCE_COLUMNS = ("SS", "dof", "MS", "F", "P", "contribution")
INTERACTION_COLUMNS = ("SS", "dof", "F", "P", "contribution")


def presence(ds: xr.Dataset, responses: Sequence[str]) -> tuple[list[str], np.ndarray]:
    """The responses with a finite value in some run, and the runs with a value (finite or
    ±inf; for flags and status codes anything but -1 "not evaluated") in some response: the
    others did not run; a mask held only where some run did not, :func:`run_mask`). Reads a
    block of runs at a time, flags and status codes first (a byte a run), and skips a
    response in a block once it has a finite value and every run of the block is known to
    have run."""
    order = sorted(responses, key=lambda r: ds[r].dtype.kind != "i")
    present: set[str] = set()

    def blocks() -> Iterator[tuple[slice, np.ndarray]]:
        for part in run_slices(ds.sizes["run"]):
            any_value = np.zeros(part.stop - part.start, dtype=bool)
            for r in order:
                if r in present and any_value.all():
                    continue
                values = np.asarray(ds[r].variable[part])
                integer = values.dtype.kind == "i"
                has = values != NOT_EVALUATED if integer else ~np.isnan(values)
                if (has if integer else np.isfinite(values)).any():
                    present.add(r)
                any_value |= has.reshape(values.shape[0], -1).any(axis=1)
            yield part, any_value

    ran = run_mask(ds.sizes["run"], blocks())
    return [r for r in responses if r in present], ran


def analyzed(ds: xr.Dataset, responses: Sequence[str]) -> tuple[xr.Dataset, list[str], np.ndarray]:
    """The results with run means and S/N ratios added, the variables to analyse (each
    response with a finite value, or its run mean when replicated, then its S/N ratio) and the
    runs with a value in some response (:func:`presence`)."""
    present, ran = presence(ds, responses)
    present = [r for r in present if not is_status(ds[r])]
    view = taguchi.with_sn(taguchi.with_means(ds, present), taguchi.sn_responses(ds, present))
    names = [taguchi.mean_name(view, r) for r in present]
    # an S/N that is -inf in every run (larger is better, no run without a value ≤ 0) has
    # nothing to analyse: it is left out, not an error that stops the analysis
    names += [
        taguchi.sn_name(r)
        for r in present
        if taguchi.sn_name(r) in view and np.isfinite(view[taguchi.sn_name(r)].values).any()
    ]
    return view, names, ran


def analyze(
    ds: xr.Dataset, responses: Sequence[str] | None = None, pool: Sequence[str] | None = None
) -> xr.Dataset:
    """Everything the outputs of a run show, computed once (see the module docstring).

    ``responses`` default to the study's (attribute ``responses``); ``pool`` is passed to every
    ANOVA (default: the study's ``[design] pool``, else pool only when the error has no dof).
    """
    with scratch.in_folder(ds):  # a response too large to hold is read from beside ds
        return _analyze(ds, responses, pool)


def _analyze(
    ds: xr.Dataset, responses: Sequence[str] | None, pool: Sequence[str] | None
) -> xr.Dataset:
    names = list(responses or json.loads(ds.attrs.get("responses", "[]")))
    ds = missing.not_evaluated_as_missing(ds, names)
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
    if design in SAMPLING_DESIGNS:  # Sobol' indices of the sample, no level means
        present, ran = presence(ds, names)
        present = [r for r in present if r not in status]
        attrs |= {"points": ds.sizes["run"], "points_without_value": false_count(ran)}
        sampled = (sobol_analysis if design == "saltelli" else sample_analysis)(ds, present)
        return sampled.assign(counts).assign_attrs(attrs | {"analysed": json.dumps(present)})
    if design == "sweep":  # tables and plots of the runs themselves: nothing to estimate
        present, ran = presence(ds, names)
        present = [r for r in present if r not in status]
        attrs |= {"points": ds.sizes["run"], "points_without_value": false_count(ran)}
        robust = robust_statistics(ds, present)
        return xr.Dataset(counts, attrs=attrs | {"analysed": json.dumps(present)}).merge(robust)
    view, analysed, ran = analyzed(ds, names)
    attrs |= {"points": ds.sizes["run"], "points_without_value": false_count(ran)}
    terms = taguchi.model_terms(view)
    operating = prediction.operating_factors(view)
    models = [f for f in json.loads(view.attrs.get("model_factors", "[]")) if f in operating]
    # One response at a time (above a block of runs: from a scratch file, a block at a time),
    # over level codes computed from the run index or held compactly (with_level_codes);
    # factor values are read where used: a 10⁸-run result is never held whole.
    base = with_level_codes(view.drop_vars(list(view.data_vars)))
    out = _frame(base, view, analysed, terms, operating, models)
    order = grid_codes.grid_in_order(base)
    grid = None if order is None else Grid(*order, operating)
    if order is not None:
        factorial_frame(out, order)
    attrs["optimum_basis"] = analysis_optimum.COMPUTED if grid else analysis_optimum.PREDICTED
    tables, optima, replaced = {}, {}, {}
    for name in analysed:
        with scratch.held(view[name].variable) as raw:
            variable, filled = _filled(out, base, raw, ran, name, terms)
            if filled is not None:  # the trade-off reads it again: lazily, where it can
                rule = filled.rule if variable.dims == ("run",) else None
                replaced[name] = (
                    variable if rule is None else filled_variable(view[name].variable, ran, rule)
                )
            beyond = None if filled is None else filled.beyond
            del filled
            one = base.assign({name: variable})
            del variable
            tables[name], found = _response(out, one, name, terms, operating, pool, grid, beyond)
            if found is not None:
                optima[name] = found
            if order is not None:
                factorial(out, one, name, order)
    sn = {taguchi.sn_name(r) for r in names}
    optimised = [n for n in analysed if n not in sn and int(out["varies"].loc[n]) and n in optima]
    if len(optimised) > 1:
        lazy = base.assign({n: replaced.get(n, view[n].variable) for n in optimised})
        analysis_optimum.trade(out, lazy, optimised, tables, optima, grid)
    for r in names:  # run means and S/N of replicated responses (or under noise), per run
        mean = taguchi.mean_name(view, r)
        if mean != r:  # analysed or not (inf in every run): the runs table shows it
            out[mean] = (view if mean in view else taguchi.with_means(ds, r))[mean]
            if taguchi.sn_name(r) in analysed:
                out[taguchi.sn_name(r)] = view[taguchi.sn_name(r)]
    out = with_violation_maps(out.assign(counts).merge(robust_statistics(ds, names)), ds)
    out.attrs = attrs | {
        "analysed": json.dumps(analysed),
        "operating_factors": json.dumps(operating),
        "model_factors": json.dumps(models),
    }
    return out


def with_level_codes(ds: xr.Dataset) -> xr.Dataset:
    """``ds`` with every ``<name>_level`` coordinate on ``run`` as the analysis reads it: the
    factors of a full factorial in grid order of more than a block of runs computed from the
    run index when read (:mod:`studies.analysis.grid_codes`: nothing held per run), any other
    (and every code of a smaller study, which renderers may index run by run) in memory as compact
    codes (:func:`studies.common.blocks.compact_codes`: 1 byte per run up to 127 levels),
    read a block of runs at a time."""
    grid = grid_codes.grid_in_order(ds) if ds.sizes.get("run", 0) > run_blocks.BLOCK else None
    computed = {}
    if grid is not None and grid[2] is None:
        computed = grid_codes.grid_coordinates(ds, grid[0], grid[1])
    levels = [c for c in ds.coords if str(c).endswith("_level") and ds[c].dims == ("run",)]
    held = {
        c: ds[c].variable.copy(data=compact_codes(ds[c].variable))
        for c in levels
        if c not in computed and grid_codes.computed(ds[c].variable) is None
    }
    return ds.assign_coords(computed | held)


def write_analysis_nc(an: xr.Dataset, folder: Path) -> Path:
    """Write the analysis Dataset as ``analysis.nc`` in ``folder``."""
    return write_netcdf(an, Path(folder) / ANALYSIS_NAME)


# --- the frame ------------------------------------------------------------------------------
def _frame(
    base: xr.Dataset,
    view: xr.Dataset,
    names: list[str],
    terms: list[str],
    operating: list[str],
    models: list[str],
) -> xr.Dataset:
    nlevels = max(level_count(base[f"{t}_level"].variable) for t in terms) if terms else 1
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
        "none_means": ("response", [missing.none_means(view[n]) for n in names]),
        "left_out": full(("response", "term", "level"), 0, np.int32),
        "bounded": full(("response", "term", "level"), 0, np.int32),
        "best_bound": full(("response",)),
        "worst_bound": full(("response",)),
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
        "term_role": ("term", [_role(view, t, operating, models) for t in terms]),
        "level_runs": (("term", "level"), _level_runs(base, terms, nlevels)),
        "interaction_a": ("interaction", [a for a, _ in pairs]),
        "interaction_b": ("interaction", [b for _, b in pairs]),
    }
    out = xr.Dataset(data, coords=coords)
    conditions = prediction.conditions(base)
    shown = {
        str(t): [f"{v:g}" if np.isfinite(v) else str(text) for v, text in zip(*pair, strict=True)]
        for t, pair in zip(terms, zip(value, label, strict=True), strict=True)
    }
    term_units = dict(zip(terms, units, strict=True))
    labels = analysis_optimum.condition_labels(conditions, shown, term_units)
    model_labels = analysis_optimum.condition_labels(
        [{f: c[f] for f in models} for c in conditions], shown, term_units
    )
    analysis_optimum.optimum_frame(out, labels, model_labels if models else None)
    return out


def _level_runs(base: xr.Dataset, terms: list[str], nlevels: int) -> np.ndarray:
    """Runs at each level of each term (O(N), ``bincount`` a block of runs at a time)."""
    counts = np.zeros((len(terms), nlevels), dtype=np.int64)
    for i, t in enumerate(terms):
        for codes in blocks(base[f"{t}_level"].variable):
            counts[i] += np.bincount(codes, minlength=nlevels)[:nlevels]
    return counts


def _role(view: xr.Dataset, term: str, operating: list[str], models: list[str]) -> str:
    if term not in taguchi.factor_names(view):
        return "column"
    if term in models:
        return "model"
    return "operating" if term in operating else "control"


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
def _filled(
    out: xr.Dataset,
    base: xr.Dataset,
    raw: xr.Variable,
    ran: np.ndarray,
    name: str,
    terms: list[str],
) -> tuple[xr.Variable, missing.Filled | missing.Resolved | None]:
    """The values the analysis uses (runs without a finite value resolved by
    :mod:`studies.analysis.missing`), with the per-level counts of what was done written into
    ``out``. A bare Variable (no coordinates to compare and load on assignment): ``raw`` when
    every value is finite, else the resolved values, in memory when ``raw`` is, else resolved
    where read (:func:`studies.analysis.filled_array.filled_variable`); and how they were
    resolved (None when every value was finite)."""
    values = values_of(raw)
    if all(np.isfinite(part).all() for part in blocks(values)):
        return raw, None
    sense = str(raw.attrs.get("better", "smaller"))
    meaning = missing.none_means(raw)
    i = out.indexes["response"].get_loc(name)
    nlevels = out.sizes["level"]
    codes = [base[f"{t}_level"].variable for t in terms]
    resolved = None
    if not isinstance(values, np.ndarray):
        resolved = missing.resolve(values, ran, meaning, sense, codes, nlevels)
    if resolved is not None:
        out["left_out"].values[i], out["bounded"].values[i] = resolved.left_out, resolved.bounded
        out["best_bound"].values[i] = resolved.best_bound
        out["worst_bound"].values[i] = resolved.worst_bound
        return filled_variable(raw, ran, resolved.rule), resolved
    filled = missing.fill(np.asarray(values[:], dtype=float), ran, meaning, sense)
    for j, c in enumerate(codes):
        out["left_out"].values[i, j] = missing.per_level(filled.left_out, c, nlevels)
        out["bounded"].values[i, j] = missing.per_level(filled.bounded, c, nlevels)
    out["best_bound"].values[i], out["worst_bound"].values[i] = (
        filled.best_bound,
        filled.worst_bound,
    )
    return xr.Variable(raw.dims, filled.values, raw.attrs), filled


def _response(
    out: xr.Dataset,
    one: xr.Dataset,
    name: str,
    terms: list[str],
    operating: list[str],
    pool: Sequence[str] | None,
    grid: Grid | None,
    beyond: Any,
) -> tuple[Any, Any]:
    """Range analysis, ANOVA, optimum and interactions of one response into ``out``; its
    ANOVA table and optimum (None when not ranked or not found)."""
    out["varies"].loc[name] = int(taguchi.varies(one, name))
    table = anova(one, name, factors=terms, pool=pool, balanced=True if grid is not None else None)
    _range(out, one, name, terms, operating)
    _anova(out, table, name)
    found = None
    if str(one[name].attrs.get("better")) != UNRANKED:
        found = analysis_optimum.optimum(out, one, name, table, grid, beyond)
    _interactions(out, one, name, table)
    return table, found


def _range(
    out: xr.Dataset, view: xr.Dataset, name: str, terms: list[str], operating: list[str]
) -> None:
    values = dict(zip(terms, out["level_value"].values, strict=True))
    ra = range_analysis(view, name, terms, level_values=values)
    at = {"response": name}
    out["k"].loc[at] = np.pad(
        ra.k.values, ((0, 0), (0, out.sizes["level"] - ra.sizes["level"])), constant_values=np.nan
    )
    for v in ("R", "rank"):
        out[v].loc[at] = ra[v].values
    ranked = str(view[name].attrs.get("better")) != UNRANKED
    chosen = [ranked and t not in operating and t in taguchi.factor_names(view) for t in terms]
    best = np.where(np.asarray(chosen) & (ra["R"].values > 0), ra["best_level"].values, -1)
    out["best_level"].loc[at] = best
    out["grand_mean"].loc[at] = finite_summary(view[name].variable).mean


def _anova(out: xr.Dataset, table: Any, name: str) -> None:
    at = {"response": name}
    for c in SOURCE_COLUMNS:
        out[c].loc[at] = table[c].to_numpy(dtype=float)
    out["pooled"].loc[at] = table["pooled"].to_numpy(dtype=np.int8)
    out["anova_note"].loc[at] = table.attrs["note"]


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
