"""Taguchi analysis on a results Dataset: S/N ratios, predicted optimum, confirmation run,
interaction effects and a trade-off summary for several responses.

Builds on :mod:`studies.analysis` (range analysis, ANOVA with pooling) and the Dataset layout of
:mod:`studies.results`; interaction columns are the ``<name>_level`` coordinates listed in the
attribute ``interaction_columns`` (JSON: column name → the two factors).

Signal-to-noise ratios over the n observations y_i of one run (dimension ``replicate``:
repeated runs or noise conditions; n = 1 without it), in dB (Phadke 1989, ch. 5):

* smaller is better  η = -10 log10( (1/n) Σ y_i² )
* larger is better   η = -10 log10( (1/n) Σ 1/y_i² )
* nominal is best    η = 10 log10( ȳ² / s² ), s² the sample variance (divisor n - 1)

Predicted response (additive model): ŷ = T̄ + Σ_t (m_t - T̄) over the model terms t (factors
and interaction columns not pooled into error), m_t the mean response at the term's level,
T̄ the grand mean. Confidence interval of that mean and of the mean of r confirmation runs
(Ross 1996, ch. 8; Roy 1990):

    ± sqrt(F(1 - α; 1, ν_e) · V_e / n_eff)   and   ± sqrt(F(1 - α; 1, ν_e) · V_e · (1/n_eff + 1/r))

with Taguchi's effective number of replications n_eff = N / (1 + Σ_t dof_t), V_e and ν_e the
error mean square and dof of the ANOVA. F(1 - α; 1, ν) = t(1 - α/2; ν)², so these are t
intervals; for a balanced array they equal the OLS confidence interval of the fitted mean.

References: M. S. Phadke, *Quality Engineering Using Robust Design*, 1989; P. J. Ross,
*Taguchi Techniques for Quality Engineering*, 2nd ed., 1996; R. Roy, *A Primer on the Taguchi
Method*, 1990.
"""

from __future__ import annotations

import itertools
import json
import math
import re
import tomllib
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any, cast

import numpy as np
import pandas as pd
import xarray as xr
from scipy import stats

from studies.statistics import SENSES, anova
from studies.sums_of_squares import first_runs, level_sums

SN_KINDS = ("smaller", "larger", "nominal")
REPLICATE = "replicate"
ALPHA = 0.05
VARIATION_TOLERANCE = 1e-9  # relative spread below which a response counts as constant
_BARE_KEY = re.compile(r"^[A-Za-z0-9_-]+$")


# --- signal-to-noise ratios -------------------------------------------------------------------
def signal_to_noise(y: xr.DataArray, kind: str) -> xr.DataArray:
    """S/N ratio [dB] of ``y`` per run, over its ``replicate`` dimension when it has one.

    ``kind`` is "smaller", "larger" or "nominal" (is best). NaN observations are left out (n
    counts the finite ones); a run without any is NaN. Nominal-is-best needs n ≥ 2 (NaN
    otherwise; ValueError when no run has two observations).
    """
    if kind not in SN_KINDS:
        msg = f"S/N kind must be one of {SN_KINDS}, got {kind!r}"
        raise ValueError(msg)
    y = y.astype(float)
    if REPLICATE not in y.dims:
        y = y.expand_dims(REPLICATE, axis=-1)
    seen = y.notnull()  # noqa: PD004 (xarray, not pandas)
    n = seen.sum(REPLICATE)
    with np.errstate(divide="ignore", invalid="ignore"):
        if kind == "smaller":
            eta = -10.0 * np.log10(xr.where(seen, y**2, 0.0).sum(REPLICATE) / n)
        elif kind == "larger":
            eta = -10.0 * np.log10(xr.where(seen, 1.0 / y**2, 0.0).sum(REPLICATE) / n)
        else:
            if int(n.max()) < 2:
                msg = "nominal-is-best S/N needs at least 2 observations (replicates) per run"
                raise ValueError(msg)
            mean = xr.where(seen, y, 0.0).sum(REPLICATE) / n
            var = xr.where(seen, (y - mean) ** 2, 0.0).sum(REPLICATE) / (n - 1)
            eta = xr.where(n >= 2, 10.0 * np.log10(mean**2 / var), np.nan)
    eta.attrs = {"units": "dB", "long_name": f"S/N ratio ({kind} is better)"}
    return eta


def varies(ds: xr.Dataset, response: str) -> bool:
    """Whether ``response`` takes more than one value (relative spread above round-off)."""
    y = ds[response].values.astype(float)
    y = y[np.isfinite(y)]
    return y.size > 1 and float(np.ptp(y)) > VARIATION_TOLERANCE * float(np.abs(y).max())


def sn_responses(ds: xr.Dataset, responses: Sequence[str]) -> list[str]:
    """The responses that get an S/N ratio: measured (not pass/fail flags), varying, and
    replicated or from an orthogonal-array experiment (one deterministic observation per run
    of a full factorial makes the S/N a mere log transform)."""
    array = ds.attrs.get("design") not in ("full_factorial", "sweep")
    return [
        r
        for r in responses
        if "flag_values" not in ds[r].attrs and varies(ds, r) and (array or REPLICATE in ds[r].dims)
    ]


def mean_name(ds: xr.Dataset, response: str) -> str:
    """The run-mean variable of ``response``: itself, or ``<response>_mean`` with replicates."""
    return f"{response}_mean" if REPLICATE in ds[response].dims else response


def sn_name(response: str) -> str:
    return f"{response}_sn"


def with_means(ds: xr.Dataset, responses: str | Sequence[str]) -> xr.Dataset:
    """``ds`` plus ``<response>_mean`` on run (same attributes) for replicated responses."""
    names = [responses] if isinstance(responses, str) else list(responses)
    return ds.assign(
        {
            mean_name(ds, r): ds[r].mean(REPLICATE).assign_attrs(ds[r].attrs)
            for r in names
            if REPLICATE in ds[r].dims
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
        if set(y.dims) not in ({"run"}, {"run", REPLICATE}):
            msg = f"{r!r} has dims {y.dims}: S/N needs ('run',) or ('run', '{REPLICATE}')"
            raise ValueError(msg)
        kind = kinds.get(r, y.attrs.get("better", "smaller"))
        eta = signal_to_noise(y, kind).transpose("run")
        eta.attrs = {
            "units": "dB",
            "long_name": f"S/N ratio of {y.attrs.get('long_name', r)} ({kind} is better)",
            "better": "larger",
            "sn_kind": kind,
            "observations": y.sizes.get(REPLICATE, 1),
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
    """:func:`studies.statistics.anova` over factors and interaction columns (error: the rest)."""
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
            p = float(stats.f.sf(f_value, dof, dof_error))
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


def level_values(ds: xr.Dataset, factor: str) -> dict[int, Any]:
    """Level index → the factor's physical value (level number + 1 when it has none)."""
    levels = ds[f"{factor}_level"].values
    values = ds[factor].values if factor in ds.coords else levels + 1
    first = first_runs(levels, int(levels.max()) + 1)
    return {int(lv): _plain(values[run]) for lv, run in enumerate(first) if run >= 0}


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
@dataclass(frozen=True)
class Prediction:
    """Additive-model prediction of ``response`` at ``levels`` (0-based level per factor)."""

    response: str
    units: str
    sense: str
    levels: dict[str, int]
    terms: tuple[str, ...]
    mean: float
    grand_mean: float
    n_eff: float
    error_ms: float
    error_dof: int
    alpha: float
    half_width: float
    confirmation_runs: int
    confirmation_half_width: float

    @property
    def interval(self) -> tuple[float, float]:
        return self.mean - self.half_width, self.mean + self.half_width

    @property
    def confirmation_interval(self) -> tuple[float, float]:
        return self.mean - self.confirmation_half_width, self.mean + self.confirmation_half_width


class _Model:
    """Level means of the model terms and the ANOVA error of one response."""

    def __init__(
        self,
        ds: xr.Dataset,
        response: str,
        pool: Sequence[str] | None,
        terms: Sequence[str] | None,
        table: pd.DataFrame | None = None,
    ) -> None:
        self.ds, self.response = ds, response
        self.table = anova_table(ds, response, pool) if table is None else table
        available = model_terms(ds)
        if terms is None:
            terms = [t for t in available if not self.table.loc[t, "pooled"]]
        unknown = [t for t in terms if t not in available]
        if unknown:
            msg = f"unknown model term(s) {unknown}; terms are {available}"
            raise ValueError(msg)
        self.terms = tuple(terms)
        self.pairs = interaction_columns(ds)
        y = ds[response].values.astype(float)
        self.finite = np.isfinite(y)
        self.y_all = y
        self.y = y if self.finite.all() else y[self.finite]
        self.grand = float(self.y.mean())
        self.means = {t: self.level_means(t) for t in self.terms}
        dof = sum(int(number(self.table, t, "dof")) for t in self.terms)
        self.n_eff = self.finite.sum() / (1 + dof)

    def level_means(self, name: str) -> np.ndarray:
        """Mean response at each level index of a factor or column (NaN where no value)."""
        codes = self.ds[f"{name}_level"].values
        counts, sums = level_sums(codes, self.y_all, int(codes.max()) + 1, self.finite)
        with np.errstate(invalid="ignore", divide="ignore"):
            return sums / counts

    def level_of(self, term: str, levels: Mapping[str, int]) -> int:
        if term not in self.pairs:
            return int(levels[term])
        a, b = self.pairs[term]
        hit = (self.ds[f"{a}_level"].values == levels[a]) & (
            self.ds[f"{b}_level"].values == levels[b]
        )
        found = np.unique(self.ds[f"{term}_level"].values[hit])
        if found.size != 1:
            msg = f"column {term} does not carry the interaction {a} x {b}: levels {found}"
            raise ValueError(msg)
        return int(found[0])

    def value(self, levels: Mapping[str, int]) -> float:
        effects = [self.means[t][self.level_of(t, levels)] - self.grand for t in self.terms]
        return self.grand + float(np.sum(effects))

    def prediction(
        self, levels: Mapping[str, int], sense: str, alpha: float, runs: int
    ) -> Prediction:
        ms_e, dof_e = number(self.table, "error", "MS"), int(number(self.table, "error", "dof"))
        half = confirm = np.nan
        if dof_e > 0 and np.isfinite(ms_e):
            f = float(stats.f.ppf(1.0 - alpha, 1, dof_e))
            half = math.sqrt(f * ms_e / self.n_eff)
            confirm = math.sqrt(f * ms_e * (1.0 / self.n_eff + 1.0 / runs))
        return Prediction(
            response=self.response,
            units=str(self.ds[self.response].attrs.get("units", "")),
            sense=sense,
            levels={f: int(v) for f, v in levels.items()},
            terms=self.terms,
            mean=self.value(levels),
            grand_mean=self.grand,
            n_eff=float(self.n_eff),
            error_ms=ms_e,
            error_dof=dof_e,
            alpha=alpha,
            half_width=half,
            confirmation_runs=runs,
            confirmation_half_width=confirm,
        )


def predict(
    ds: xr.Dataset,
    response: str,
    levels: Mapping[str, int],
    pool: Sequence[str] | None = None,
    terms: Sequence[str] | None = None,
    alpha: float = ALPHA,
    confirmation_runs: int = 1,
    table: pd.DataFrame | None = None,
) -> Prediction:
    """Predicted mean of ``response`` at ``levels`` (factor → 0-based level) with intervals.

    ``terms`` are the model terms (factors, interaction columns); by default those the ANOVA
    keeps (not pooled, see :func:`anova_table`). ``pool`` is passed to the ANOVA; ``table`` is
    that ANOVA when the caller has it already.
    """
    model = _Model(ds, response, pool, terms, table)
    missing = sorted({f for f in factor_names(ds) if f not in levels})
    if missing:
        msg = f"levels missing for factor(s) {missing}"
        raise ValueError(msg)
    sense = str(ds[response].attrs.get("better", "smaller"))
    return model.prediction(levels, sense, alpha, confirmation_runs)


def predict_optimum(
    ds: xr.Dataset,
    response: str,
    sense: str | None = None,
    pool: Sequence[str] | None = None,
    terms: Sequence[str] | None = None,
    alpha: float = ALPHA,
    confirmation_runs: int = 1,
    table: pd.DataFrame | None = None,
) -> Prediction:
    """The best level combination of ``response`` and its predicted mean with intervals.

    Each factor takes the level with the best mean, as in range analysis (``sense``: "smaller"
    or "larger", default the response's ``better`` attribute; ties go to the lower level);
    factors linked by an interaction term take the best combination of the additive model,
    searched over all their level combinations.
    """
    chosen = sense or str(ds[response].attrs.get("better", "smaller"))
    if chosen not in SENSES:
        msg = f"sense must be one of {SENSES}, got {chosen!r}"
        raise ValueError(msg)
    sign = 1.0 if chosen == "smaller" else -1.0
    model = _Model(ds, response, pool, terms, table)
    factors = factor_names(ds)
    levels = {}
    for f in factors:
        scores = sign * model.level_means(f)
        levels[f] = int(np.where(np.isnan(scores), np.inf, scores).argmin())
    linked = [f for f in factors if any(f in model.pairs.get(t, ()) for t in model.terms)]
    if linked:
        best, best_levels = math.inf, levels
        counts = [range(int(ds[f"{f}_level"].max()) + 1) for f in linked]
        for combo in itertools.product(*counts):
            trial = levels | dict(zip(linked, combo, strict=True))
            score = sign * model.value(trial)
            if score < best:
                best, best_levels = score, trial
        levels = best_levels
    return model.prediction(levels, chosen, alpha, confirmation_runs)


# --- confirmation run ----------------------------------------------------------------------------
def confirmation_values(ds: xr.Dataset, levels: Mapping[str, int]) -> dict[str, Any]:
    """Factor → its physical value at the chosen level (plain Python types)."""
    return {f: level_values(ds, f)[int(levels[f])] for f in factor_names(ds)}


def confirmation_toml(ds: xr.Dataset, levels: Mapping[str, int]) -> str:
    """A study file that runs the chosen levels once: the original study (attribute
    ``study_toml``) with ``design = "full_factorial"`` and one level per factor.

    Without the original text, only the ``[factors]`` tables are written.
    """
    values = confirmation_values(ds, levels)
    original = tomllib.loads(ds.attrs["study_toml"]) if ds.attrs.get("study_toml") else {}
    study = {k: v for k, v in original.items() if k not in ("design", "factors")}
    name = str(original.get("name", ds.attrs.get("study_name", "study")))
    if original:
        study["name"] = f"{name}_confirmation"
        study["description"] = f"Confirmation run of {name}: every factor at its chosen level"
        study["design"] = {"type": "full_factorial"}
    factors = {}
    for f, value in values.items():
        units = ds[f].attrs.get("units", "") if f in ds.coords else ""
        factors[f] = {"levels": [value]} | ({"units": str(units)} if units else {})
    study["factors"] = factors
    run = ds.attrs.get("run_id", "")
    header = f"# Confirmation run of {name}{f' (run {run})' if run else ''}: the chosen levels.\n"
    return header + _toml(study)


def _plain(value: Any) -> Any:
    """numpy scalar → Python scalar (str, int or float)."""
    return value.item() if isinstance(value, np.generic) else value


def _toml_value(value: Any) -> str:
    value = _plain(value)
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if math.isfinite(value):
            return repr(value)
        return "nan" if math.isnan(value) else ("inf" if value > 0 else "-inf")
    if isinstance(value, str):
        return json.dumps(value, ensure_ascii=False)
    if isinstance(value, list):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    if isinstance(value, dict):
        return "{ " + ", ".join(f"{_key(k)} = {_toml_value(v)}" for k, v in value.items()) + " }"
    msg = f"cannot write {value!r} ({type(value).__name__}) as TOML"
    raise TypeError(msg)


def _key(key: str) -> str:
    return key if _BARE_KEY.match(key) else json.dumps(key, ensure_ascii=False)


def _toml(data: Mapping[str, Any]) -> str:
    """TOML text of a study dict: top-level values, then tables (a table of tables as
    ``[name.sub]`` sections)."""
    lines = [f"{_key(k)} = {_toml_value(v)}" for k, v in data.items() if not isinstance(v, dict)]
    for key, table in data.items():
        if not isinstance(table, dict):
            continue
        if table and all(isinstance(v, dict) for v in table.values()):
            for sub, inner in table.items():
                lines += ["", f"[{_key(key)}.{_key(sub)}]"]
                lines += [f"{_key(k)} = {_toml_value(v)}" for k, v in inner.items()]
        else:
            lines += ["", f"[{_key(key)}]"]
            lines += [f"{_key(k)} = {_toml_value(v)}" for k, v in table.items()]
    return "\n".join(lines) + "\n"


# --- several responses -------------------------------------------------------------------------
@dataclass(frozen=True)
class TradeOff:
    """Best levels per response and the compromise for conflicting objectives.

    ``table`` (index factor): per response ``best <r>`` (1-based level) and ``% <r>``
    (contribution to that response's variation), then ``conflict`` (the responses disagree),
    ``choice`` (1-based compromise level) and ``decided by`` (the response the factor
    contributes most to, whose best level is taken). ``predictions`` (index response): the
    predicted mean at the response's own optimum and at the compromise, with the confidence
    half-width at the compromise, ``units`` and ``sense``. ``levels``: compromise, 0-based.
    """

    table: pd.DataFrame
    predictions: pd.DataFrame
    levels: dict[str, int]


def tradeoff(
    ds: xr.Dataset,
    responses: Sequence[str],
    alpha: float = ALPHA,
    tables: Mapping[str, pd.DataFrame] | None = None,
    optima: Mapping[str, Prediction] | None = None,
) -> TradeOff:
    """Trade-off summary of several responses on the same runs (each with its own ANOVA;
    ``tables`` and ``optima``: those ANOVAs and optima when the caller has them already)."""
    factors = factor_names(ds)
    tables = {r: anova_table(ds, r) for r in responses} if tables is None else tables
    if optima is None:
        optima = {r: predict_optimum(ds, r, alpha=alpha, table=tables[r]) for r in responses}
    share = {r: tables[r]["contribution"] for r in responses}
    rows = {}
    levels = {}
    for f in factors:
        row: dict[str, Any] = {}
        for r in responses:
            row[f"best {r}"] = optima[r].levels[f] + 1
            row[f"% {r}"] = float(share[r][f])
        lead = max(responses, key=lambda r: np.nan_to_num(share[r][f], nan=-1.0))
        levels[f] = optima[lead].levels[f]
        row["conflict"] = len({optima[r].levels[f] for r in responses}) > 1
        row["choice"] = levels[f] + 1
        row["decided by"] = lead
        rows[f] = row
    table = pd.DataFrame.from_dict(rows, orient="index")
    table.index.name = "factor"
    preds = {}
    for r in responses:
        at = predict(ds, r, levels, alpha=alpha, table=tables[r])
        preds[r] = {
            "own optimum": optima[r].mean,
            "compromise": at.mean,
            "half width": at.half_width,
            "units": optima[r].units,
            "sense": optima[r].sense,
        }
    predictions = pd.DataFrame.from_dict(preds, orient="index")
    predictions.index.name = "response"
    return TradeOff(table, predictions, levels)
