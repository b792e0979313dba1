"""Taguchi analysis on a results Dataset: S/N ratios, run means of replicates, the model terms,
ANOVA tables and interaction effects. The predicted optimum is :mod:`studies.analysis.prediction`, the
trade-off of several responses :mod:`studies.analysis.tradeoff`, the confirmation run
:mod:`studies.analysis.confirmation`.

Builds on :mod:`studies.analysis.statistics` (range analysis, ANOVA with pooling) and the Dataset layout
of :mod:`studies.run.results`; interaction columns are the ``<name>_level`` coordinates listed in
the attribute ``interaction_columns`` (JSON: column name → the two factors).

Signal-to-noise ratios over the n observations y_i of one run (dimension ``replicate``:
repeated runs, or ``noise``: the noise cases of a study's [noise]; n = 1 without either), in
dB (Phadke 1989, ch. 5):

* smaller is better  η = -10 log10( (1/n) Σ y_i² ) for y_i ≥ 0; none if any y_i < 0
* larger is better   η = -10 log10( (1/n) Σ 1/y_i² ) for y_i > 0; -∞ if any y_i ≤ 0
* nominal is best    η = 10 log10( ȳ² / s² ), s² the sample variance (divisor n - 1)

References: M. S. Phadke, *Quality Engineering Using Robust Design*, 1989; P. J. Ross,
*Taguchi Techniques for Quality Engineering*, 2nd ed., 1996; R. Roy, *A Primer on the Taguchi
Method*, 1990.
"""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from typing import Any, cast

import numpy as np
import pandas as pd
import xarray as xr

from studies.analysis.grid_codes import computed
from studies.analysis.statistics import anova, f_survival
from studies.common.blocks import finite_summary, first_runs, level_count
from studies.common.errors import StudyError
from studies.run.results import NOISE

SN_KINDS = ("smaller", "larger", "nominal")
REPLICATE = "replicate"
OBSERVATIONS = (REPLICATE, NOISE)  # dimensions of repeated observations of one run
ALPHA = 0.05
VARIATION_TOLERANCE = 1e-9  # relative spread below which a response counts as constant


# --- signal-to-noise ratios -------------------------------------------------------------------
def signal_to_noise(y: xr.DataArray, kind: str) -> xr.DataArray:
    """S/N ratio [dB] of ``y`` per run, over its ``replicate`` dimension when it has one.

    ``kind`` is "smaller", "larger" or "nominal" (is best). NaN observations are left out (n
    counts the finite ones); a run without any is NaN. Nominal-is-best needs n ≥ 2 (NaN
    otherwise; ValueError when no run has two observations). Larger-is-better is defined for
    y > 0 and falls to −∞ as a value falls to 0: a run with a value ≤ 0 (a violated margin,
    a concave cam's radius, −∞ where a point has no value) gets −∞, the worst S/N, not the
    S/N of |y| (1/y² is the same for −y and y). Smaller-is-better measures the distance from 0
    (target 0, values ≥ 0): where any value is below 0 it would rate −y as y, against the
    level means, so every run's S/N is NaN and the analysis leaves it out
    (:func:`sn_left_out`).
    """
    if kind not in SN_KINDS:
        msg = f"S/N kind must be one of {SN_KINDS}, got {kind!r}"
        raise StudyError(msg)
    y = y.astype(float)
    dim = observation_dim(y) or REPLICATE
    if dim not in y.dims:
        y = y.expand_dims(dim, axis=-1)
    seen = y.notnull()  # noqa: PD004 (xarray, not pandas)
    n = seen.sum(dim)
    with np.errstate(divide="ignore", invalid="ignore"):
        if kind == "smaller":
            eta = -10.0 * np.log10(xr.where(seen, y**2, 0.0).sum(dim) / n)
            if bool((seen & (y < 0.0)).any()):
                eta = xr.full_like(eta, np.nan)
        elif kind == "larger":
            eta = -10.0 * np.log10(xr.where(seen, 1.0 / y**2, 0.0).sum(dim) / n)
            eta = xr.where((seen & (y <= 0.0)).any(dim), -np.inf, eta)
        else:
            if int(n.max()) < 2:
                msg = "nominal-is-best S/N needs at least 2 observations (replicates) per run"
                raise StudyError(msg)
            mean = xr.where(seen, y, 0.0).sum(dim) / n
            var = xr.where(seen, (y - mean) ** 2, 0.0).sum(dim) / (n - 1)
            eta = xr.where(n >= 2, 10.0 * np.log10(mean**2 / var), np.nan)
    eta.attrs = {"units": "dB", "long_name": f"S/N ratio ({kind} is better)"}
    return eta


def sn_left_out(ds: xr.Dataset, response: str) -> str:
    """Why ``response`` has no S/N to analyse although its design gives it one
    (:func:`sn_responses`): a sentence, or "" when it has one (or gets none anyway)."""
    if not sn_responses(ds, [response]):
        return ""
    kind = ds[response].attrs.get("better", "smaller")
    if (
        kind not in ("smaller", "larger")
        or np.isfinite(signal_to_noise(ds[response], kind).values).any()
    ):
        return ""
    if kind == "smaller":
        return (
            "No S/N ratio: the smaller-the-better S/N measures the distance from 0 (it rates "
            f"−y as y), and {response} is below 0 in some runs; the level means above say which "
            "level gives the smaller value."
        )
    return (
        "No S/N ratio: the larger-the-better S/N is −∞ (the worst) for a value ≤ 0, and "
        f"{response} is ≤ 0 in every run."
    )


def observation_dim(y: xr.DataArray) -> str | None:
    """The dimension of repeated observations of ``y`` per run (``replicate`` or ``noise``),
    or None."""
    return next((d for d in OBSERVATIONS if d in y.dims), None)


def varies(ds: xr.Dataset, response: str) -> bool:
    """Whether ``response`` takes more than one value (relative spread above round-off)."""
    seen = finite_summary(ds[response].variable)  # a block of runs at a time
    return seen.count > 1 and seen.high - seen.low > VARIATION_TOLERANCE * seen.largest


def sn_responses(ds: xr.Dataset, responses: Sequence[str]) -> list[str]:
    """The responses that get an S/N ratio: measured (not pass/fail flags), varying, and
    replicated or from an orthogonal-array experiment (one deterministic observation per run
    of a full factorial makes the S/N a mere log transform)."""
    array = ds.attrs.get("design") not in ("full_factorial", "sweep")
    return [
        r
        for r in responses
        if "flag_values" not in ds[r].attrs
        and (array or observation_dim(ds[r]) is not None)
        and varies(ds, r)  # last: it reads the response
    ]


def mean_name(ds: xr.Dataset, response: str) -> str:
    """The run-mean variable of ``response``: itself, or ``<response>_mean`` with replicates."""
    return f"{response}_mean" if observation_dim(ds[response]) else response


def sn_name(response: str) -> str:
    return f"{response}_sn"


def with_means(ds: xr.Dataset, responses: str | Sequence[str]) -> xr.Dataset:
    """``ds`` plus ``<response>_mean`` on run (same attributes) for replicated responses."""
    names = [responses] if isinstance(responses, str) else list(responses)
    return ds.assign(
        {
            mean_name(ds, r): ds[r].mean(str(observation_dim(ds[r]))).assign_attrs(ds[r].attrs)
            for r in names
            if observation_dim(ds[r])
        }
    )


def with_sn(
    ds: xr.Dataset, responses: str | Sequence[str], kinds: Mapping[str, str] | None = None
) -> xr.Dataset:
    """``ds`` plus ``<response>_sn`` (and ``<response>_mean`` for replicated responses) on run.

    The S/N kind of each response is ``kinds[response]``, else its ``better`` attribute, else
    "smaller". S/N variables are "larger is better" for range analysis and carry ``sn_kind``
    and ``observations`` (replicates per run) attributes; means keep the response's attributes.
    """
    names = [responses] if isinstance(responses, str) else list(responses)
    kinds = kinds or {}
    new = {}
    for r in names:
        y = ds[r]
        if set(y.dims) not in ({"run"}, *({"run", d} for d in OBSERVATIONS)):
            msg = f"{r!r} has dims {y.dims}: S/N needs ('run',) or ('run', '{REPLICATE}'|'{NOISE}')"
            raise StudyError(msg)
        kind = kinds.get(r, y.attrs.get("better", "smaller"))
        eta = signal_to_noise(y, kind).transpose("run")
        eta.attrs = {
            "units": "dB",
            "long_name": f"S/N ratio of {y.attrs.get('long_name', r)} ({kind} is better)",
            "better": "larger",
            "sn_kind": kind,
            "observations": y.sizes.get(observation_dim(y) or REPLICATE, 1),
        }
        new[sn_name(r)] = eta
    return with_means(ds, names).assign(new)


# --- model terms and interactions ------------------------------------------------------------
def factor_names(ds: xr.Dataset) -> list[str]:
    return list(json.loads(ds.attrs.get("factors", "[]")))


def interaction_columns(ds: xr.Dataset) -> dict[str, tuple[str, str]]:
    """Interaction column name → its two factors (attribute ``interaction_columns``)."""
    raw = json.loads(ds.attrs.get("interaction_columns", "{}"))
    return {name: (a, b) for name, (a, b) in raw.items()}


def interaction_pairs(ds: xr.Dataset) -> dict[tuple[str, str], list[str]]:
    """Each assigned interaction (factor pair) → its columns, in column order."""
    pairs: dict[tuple[str, str], list[str]] = {}
    for name, pair in interaction_columns(ds).items():
        pairs.setdefault(pair, []).append(name)
    return pairs


def model_terms(ds: xr.Dataset) -> list[str]:
    """Factors, then interaction columns: the terms of the ANOVA and of the prediction."""
    return factor_names(ds) + list(interaction_columns(ds))


def anova_table(ds: xr.Dataset, response: str, pool: Sequence[str] | None = None) -> pd.DataFrame:
    """:func:`studies.analysis.statistics.anova` over factors and interaction columns (error: the rest)."""
    return anova(ds, response, factors=model_terms(ds), pool=pool)


def number(table: pd.DataFrame, row: str, column: str) -> float:
    """One numeric cell of an ANOVA table."""
    return float(cast("float", table.loc[row, column]))


def interaction_anova(table: pd.DataFrame, ds: xr.Dataset) -> pd.DataFrame:
    """One row per interaction ``"A x B"``: SS, dof and contribution summed over its columns;
    F and P of the columns not pooled, tested together against the error."""
    rows = {}
    ms_error, dof_error = number(table, "error", "MS"), int(number(table, "error", "dof"))
    for (a, b), columns in interaction_pairs(ds).items():
        part = table.loc[columns]
        kept = part[~part["pooled"].astype(bool)]
        ss, dof = float(kept["SS"].sum()), int(kept["dof"].sum())
        f_value, p = np.nan, np.nan
        if dof and dof_error and ms_error > 0.0:
            f_value = (ss / dof) / ms_error
            p = f_survival(f_value, dof, dof_error)
        rows[f"{a} x {b}"] = (
            float(part["SS"].sum()),
            int(part["dof"].sum()),
            f_value,
            p,
            float(part["contribution"].sum()),
            len(kept) < len(part),
        )
    columns = ["SS", "dof", "F", "P", "contribution", "pooled"]
    return pd.DataFrame.from_dict(rows, orient="index", columns=columns)


def plain(value: Any) -> Any:
    """numpy scalar → Python scalar (str, int or float)."""
    return value.item() if isinstance(value, np.generic) else value


def level_values(ds: xr.Dataset, factor: str) -> dict[int, Any]:
    """Level index → the factor's physical value (level number + 1 when it has none)."""
    levels = ds[f"{factor}_level"].variable  # read a block of runs at a time
    grid = computed(levels)  # a full factorial in grid order: known without reading
    first = grid.first_runs() if grid is not None else first_runs(levels, level_count(levels))
    present = np.flatnonzero(first >= 0)
    runs = first[present]  # the factor's values are read at these runs only
    values = ds[factor].isel(run=runs).values if factor in ds.coords else present + 1
    return {int(lv): plain(v) for lv, v in zip(present, values, strict=True)}


def interaction_means(ds: xr.Dataset, response: str, a: str, b: str) -> xr.DataArray:
    """Mean response for every level pair of factors ``a`` and ``b`` (dims ``a`` x ``b``).

    Coordinates are the factors' values; ``<factor>_level`` holds the 0-based level index.
    """
    y = ds[response].values.astype(float)
    finite = np.isfinite(y)
    frame = pd.DataFrame(
        {"a": ds[f"{a}_level"].values[finite], "b": ds[f"{b}_level"].values[finite], "y": y[finite]}
    )
    table = frame.pivot_table(index="a", columns="b", values="y", aggfunc="mean")
    va, vb = level_values(ds, a), level_values(ds, b)
    rows, cols = table.index.to_numpy(dtype=int), table.columns.to_numpy(dtype=int)
    return xr.DataArray(
        table.to_numpy(),
        dims=(a, b),
        coords={
            a: [va[int(i)] for i in rows],
            b: [vb[int(j)] for j in cols],
            f"{a}_level": (a, rows),
            f"{b}_level": (b, cols),
        },
        attrs=dict(ds[response].attrs),
        name=response,
    )


# --- prediction --------------------------------------------------------------------------------


# --- confirmation run ----------------------------------------------------------------------------


# --- several responses -------------------------------------------------------------------------
