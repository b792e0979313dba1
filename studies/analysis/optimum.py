"""The optimum and the trade-off in the analysis Dataset (:func:`studies.analysis.analyze.analyze`).

Two bases, named in the attribute ``optimum_basis``:

* ``"computed"`` — a complete full factorial: the best computed control combination
  (:mod:`studies.analysis.grid_optimum`), its run in each operating condition, the best run of each
  condition, and its neighbours; no model, no interval;
* ``"predicted"`` — an orthogonal array: Taguchi's additive prediction at the best control
  levels (:mod:`studies.analysis.prediction`) with its confidence intervals, in each condition.

Variables (``condition``: each combination of the operating factors' levels, one when there is
none): ``optimum_level`` (response, term; -1 for operating factors and interaction columns),
``optimum_value`` (mean over the conditions), ``optimum_worst``, ``optimum_at`` and
``optimum_run`` (response, condition; -1 where that combination was not run), ``best_value`` and
``best_run`` (response, condition; full factorials), ``optimum_ties`` and ``optimum_tie_rule``
(response: control combinations sharing the best rank and what chose among them), ``neighbour_value`` and ``neighbour_run``
(response, term, side), the array's ``predicted``, ``half_width``, ``confirmation_half_width``,
``n_eff``, ``error_ms``, ``error_dof``, ``model_terms``; the trade-off's ``chosen_level``,
``decided_by``, ``conflict`` (term), ``compromise``, ``compromise_worst``,
``compromise_half_width`` and ``compromise_confirmation_half_width`` (response; the intervals
of the mean and of a confirmation run at the chosen levels) and ``compromise_at`` (response,
condition).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import xarray as xr

from studies.analysis import prediction, tradeoff
from studies.analysis.grid_optimum import SIDES, Grid, GridOptimum
from studies.common.blocks import values_of

COMPUTED, PREDICTED = "computed", "predicted"


def condition_labels(
    conditions: Sequence[dict[str, int]],
    label: Mapping[str, Sequence[str]],
    units: Mapping[str, str],
) -> list[str]:
    """``engine_speed = 1200 rpm, max_pressure = 15 MPa`` per condition (``all design
    points`` when there is no operating factor)."""

    def one(f: str, level: int) -> str:
        shown = f"{label[f][level]} {units[f]}" if units[f] not in ("", "1") else label[f][level]
        return f"{f} = {shown}"

    return [", ".join(one(f, v) for f, v in c.items()) or "all design points" for c in conditions]


def optimum_frame(out: xr.Dataset, labels: list[str], models: list[str] | None = None) -> None:
    """The optimum variables (NaN / -1 until a response fills them) and the ``condition`` and
    ``side`` coordinates; with model factors, ``models`` is the model label of each condition
    (coordinate ``model`` and ``condition_model``, the model index of each condition)."""
    nr, nt, nc = out.sizes["response"], out.sizes["term"], len(labels)
    out.coords["condition"] = labels
    if models is not None:
        unique = list(dict.fromkeys(models))
        out.coords["model"] = unique
        out.coords["condition_model"] = ("condition", [unique.index(m) for m in models])
        nm = len(unique)
        out.update(
            {
                "model_mean": (("response", "model"), np.full((nr, nm), np.nan)),
                "model_worst": (("response", "model"), np.full((nr, nm), np.nan)),
                "model_worst_at": (("response", "model"), np.full((nr, nm), -1, np.int64)),
            }
        )
    out.coords["side"] = list(SIDES)
    rc, rts = ("response", "condition"), ("response", "term", "side")
    out.update(
        {
            "optimum_value": ("response", np.full(nr, np.nan)),
            "optimum_worst": ("response", np.full(nr, np.nan)),
            "optimum_at": (rc, np.full((nr, nc), np.nan)),
            "optimum_run": (rc, np.full((nr, nc), -1, dtype=np.int64)),
            "best_value": (rc, np.full((nr, nc), np.nan)),
            "best_run": (rc, np.full((nr, nc), -1, dtype=np.int64)),
            "neighbour_value": (rts, np.full((nr, nt, 2), np.nan)),
            "neighbour_run": (rts, np.full((nr, nt, 2), -1, dtype=np.int64)),
            "optimum_ties": ("response", np.ones(nr, dtype=np.int64)),
            "optimum_tie_rule": ("response", np.full(nr, "", dtype=object)),
        }
    )


def optimum(
    out: xr.Dataset,
    one: xr.Dataset,
    name: str,
    table: Any,
    grid: Grid | None,
    beyond: np.ndarray | None = None,
) -> tradeoff.Optimum | None:
    """Fill the optimum of ``name`` (the computed one on a grid, else the prediction);
    ``beyond``: the runs whose value is a bound (:attr:`studies.analysis.missing.Filled.beyond`)."""
    if grid is not None:
        return _computed(out, one, name, grid, beyond)
    return _predicted(out, one, name, table)


def _levels(out: xr.Dataset, name: str, levels: Mapping[str, int]) -> None:
    out["optimum_level"].loc[{"response": name}] = [
        levels.get(str(t), -1) for t in out["term"].values
    ]


def _summary(out: xr.Dataset, name: str, at: np.ndarray, sense: str) -> None:
    i = out.indexes["response"].get_loc(name)
    out["optimum_at"].values[i] = at
    out["optimum_value"].values[i] = float(np.mean(at))
    out["optimum_worst"].values[i] = float(at.max() if sense == "smaller" else at.min())
    if "model" not in out.coords:
        return
    signed = at if sense == "smaller" else -at
    for m in range(out.sizes["model"]):
        where = np.flatnonzero(out["condition_model"].values == m)
        out["model_mean"].values[i, m] = float(np.mean(at[where]))
        worst = int(where[int(np.argmax(signed[where]))])
        out["model_worst"].values[i, m] = float(at[worst])
        out["model_worst_at"].values[i, m] = worst


def _computed(
    out: xr.Dataset, one: xr.Dataset, name: str, grid: Grid, beyond: np.ndarray | None
) -> GridOptimum | None:
    sense = str(one[name].attrs.get("better", "smaller"))
    found = grid.optimum(values_of(one[name].variable), sense, beyond)
    if found is None:
        return None
    i = out.indexes["response"].get_loc(name)
    out["optimum_ties"].values[i], out["optimum_tie_rule"].values[i] = found.ties, found.tie_rule
    _levels(out, name, found.levels)
    _summary(out, name, found.at, sense)
    out["optimum_run"].values[i] = found.runs
    out["best_value"].values[i], out["best_run"].values[i] = found.best_values, found.best_runs
    terms = list(out["term"].values)
    for f, sides in found.neighbours.items():
        t = terms.index(f)
        for s, (value, run) in enumerate(sides):
            out["neighbour_value"].values[i, t, s] = value
            out["neighbour_run"].values[i, t, s] = run
    return found


def _predicted(out: xr.Dataset, one: xr.Dataset, name: str, table: Any) -> prediction.Prediction:
    p = prediction.predict_optimum(one, name, table=table)
    at = {"response": name}
    _levels(out, name, p.levels)
    _summary(out, name, np.asarray(p.at), p.sense)
    out["optimum_run"].loc[at] = [_run_at(one, p.levels | c) for c in p.conditions]
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


def _run_at(ds: xr.Dataset, levels: Mapping[str, int]) -> int:
    """The first run at exactly these factor levels (-1 when the array did not run them)."""
    hit = np.ones(ds.sizes["run"], dtype=bool)
    for f, level in levels.items():
        hit &= ds[f"{f}_level"].values == level
    runs = np.flatnonzero(hit)
    return int(runs[0]) if runs.size else -1


def trade(
    out: xr.Dataset,
    view: xr.Dataset,
    names: list[str],
    tables: dict[str, Any],
    optima: dict[str, tradeoff.Optimum],
    grid: Grid | None,
) -> None:
    """The trade-off of several responses (control levels only) into ``out``."""
    result = tradeoff.tradeoff(
        view,
        names,
        tables={n: tables[n] for n in names},
        optima={n: optima[n] for n in names},
        grid=grid,
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
    nr, nc = out.sizes["response"], out.sizes["condition"]
    columns = {"compromise": "compromise", "compromise_worst": "worst"}
    columns["compromise_half_width"] = "half width"
    columns["compromise_confirmation_half_width"] = "confirmation half width"
    values = {v: np.full(nr, np.nan) for v in columns}
    at = np.full((nr, nc), np.nan)
    for n, row in result.predictions.iterrows():
        i = out.indexes["response"].get_loc(n)
        for v, column in columns.items():
            values[v][i] = row[column]
        at[i] = result.at[str(n)]
    for v, data in values.items():
        out[v] = ("response", data)
    out["compromise_at"] = (("response", "condition"), at)
