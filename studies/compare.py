"""What changed between recorded runs: definitions, code, versions, timings and responses.

Everything is read from the run folders (``study.toml``, ``run.json``, ``results.nc``) and the
registry, never from scene code, so runs of scenes that are no longer installed still compare.
Design points are matched by the values of the factors the runs share: two different designs
over the same factors compare on the points they have in common.
"""

from __future__ import annotations

import json
import tomllib
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import xarray as xr

from studies import tracking
from studies.results import is_status, open_results

TOP_POINTS = 3  # design points listed per response, those that moved most
MISSING = "—"
SECTIONS = {"parameters": "fixed parameter", "settings": "setting", "factors": "factor"}


@dataclass
class RecordedRun:
    """A run as its folder recorded it."""

    run_id: str
    record: dict[str, Any]
    definition: dict[str, Any]
    results: xr.Dataset

    @property
    def factors(self) -> list[str]:
        return list(json.loads(self.results.attrs.get("factors", "[]")))

    def responses(self) -> list[str]:
        """Numeric responses on ``run`` (status codes and bit masks excluded)."""
        names = json.loads(self.results.attrs.get("responses", "[]"))
        return [
            n
            for n in names
            if n in self.results
            and self.results[n].dims == ("run",)
            and self.results[n].dtype.kind in "fiu"
            and not is_status(self.results[n])
        ]


@dataclass
class Difference:
    """One entry of a definition that differs between runs (a value per run)."""

    kind: str  # "fixed parameter", "setting", "factor", "study"
    name: str
    values: list[str]


@dataclass
class ResponseChange:
    """How one response moved from the reference run to another run on their common points."""

    response: str
    units: str
    run_id: str
    points: int
    max_abs: float
    max_rel: float
    moved: list[tuple[str, float, float]]  # (point, reference value, value), largest first

    @property
    def changed(self) -> bool:
        return bool(self.moved)


@dataclass
class Comparison:
    runs: list[RecordedRun]
    definition: list[Difference]
    code: list[Difference]
    versions: list[Difference]
    matched_on: list[str]
    changes: list[ResponseChange]

    def moved(self) -> list[str]:
        """Responses that moved in any run (reference order)."""
        return list(dict.fromkeys(c.response for c in self.changes if c.changed))


def load_run(outputs: Path, ref: str) -> RecordedRun:
    """The run named by an id, a unique id prefix or a tag (KeyError if none)."""
    row = tracking.resolve_run(outputs, ref)
    folder = Path(row["folder"])
    results = folder / "results.nc"
    if not results.exists():
        msg = f"run {row['run_id']} has no results.nc (status {row['status']}): nothing to compare"
        raise FileNotFoundError(msg)
    record = json.loads((folder / "run.json").read_text(encoding="utf-8"))
    definition = tomllib.loads((folder / "study.toml").read_text(encoding="utf-8"))
    return RecordedRun(row["run_id"], record, definition, open_results(results).load())


def compare(runs: list[RecordedRun]) -> Comparison:
    """Compare runs with the first (the reference)."""
    if len(runs) < 2:
        raise ValueError("name at least two runs to compare")
    shared = [r for r in runs[0].responses() if all(r in x.responses() for x in runs[1:])]
    if not shared:
        msg = "the runs share no response: " + "; ".join(
            f"{x.run_id}: {', '.join(x.responses()) or 'none'}" for x in runs
        )
        raise ValueError(msg)
    factors = shared_factors(runs)
    changes = []
    for other in runs[1:]:
        common = matched_points(runs[0].results, other.results, factors)
        changes += [
            _change(common, r, str(runs[0].results[r].attrs.get("units", "")), other.run_id)
            for r in shared
        ]
    return Comparison(
        runs,
        _definition_differences(runs),
        _code_differences(runs),
        _version_differences(runs),
        factors,
        changes,
    )


def shared_factors(runs: list[RecordedRun]) -> list[str]:
    factors = [f for f in runs[0].factors if all(f in x.factors for x in runs[1:])]
    if not factors:
        msg = "the runs share no factor, so no design point of one can be matched to the other"
        raise ValueError(msg)
    return factors


def point_table(ds: xr.Dataset, factors: list[str], responses: list[str]) -> pd.DataFrame:
    """Responses indexed by the values of ``factors`` (ValueError if they repeat)."""
    frame = pd.DataFrame({f: ds[f].values for f in factors})
    for r in responses:
        frame[r] = ds[r].values.astype(np.float64)
    indexed = frame.set_index(factors)
    if not indexed.index.is_unique:
        msg = (
            f"run {ds.attrs.get('run_id', '?')} has several design points with the same values "
            f"of {', '.join(factors)}: the points cannot be matched by the shared factors"
        )
        raise ValueError(msg)
    return indexed


def matched_points(reference: xr.Dataset, other: xr.Dataset, factors: list[str]) -> pd.DataFrame:
    """The design points both runs have, columns ``<response>`` (reference) and
    ``<response>_other``, indexed by the factor values."""
    names = [n for n in reference.data_vars if n in other.data_vars and other[n].dims == ("run",)]
    names = [n for n in names if reference[n].dims == ("run",)]
    a = point_table(reference, factors, [str(n) for n in names])
    b = point_table(other, factors, [str(n) for n in names])
    common = a.join(b.add_suffix("_other"), how="inner")
    if common.empty:
        msg = f"the runs have no design point in common over {', '.join(factors)}"
        raise ValueError(msg)
    return common


def point_label(index: Any, factors: list[str]) -> str:
    values = index if isinstance(index, tuple) else (index,)
    return ", ".join(f"{f}={_short(v)}" for f, v in zip(factors, values, strict=True))


def _change(common: pd.DataFrame, response: str, units: str, run_id: str) -> ResponseChange:
    a = common[response].to_numpy()
    b = common[f"{response}_other"].to_numpy()
    same = (a == b) | (np.isnan(a) & np.isnan(b))  # equal, the same infinity, or both NaN
    with np.errstate(invalid="ignore", divide="ignore"):
        diff = np.where(same, 0.0, np.abs(b - a))
        diff = np.where(np.isnan(diff), np.inf, diff)  # NaN in one run only: it moved
        rel = np.where(diff == 0, 0.0, diff / np.abs(a))
    order = [i for i in np.argsort(-diff, kind="stable")[:TOP_POINTS] if diff[i] > 0]
    factors = [str(n) for n in common.index.names]
    moved = [(point_label(common.index[i], factors), float(a[i]), float(b[i])) for i in order]
    return ResponseChange(
        response,
        units,
        run_id,
        len(common),
        float(diff.max(initial=0.0)),
        float(rel.max(initial=0.0)),
        moved,
    )


def _flatten(table: dict[str, Any], prefix: str = "") -> dict[str, Any]:
    out: dict[str, Any] = {}
    for key, value in table.items():
        name = f"{prefix}{key}"
        if isinstance(value, dict):
            out |= _flatten(value, f"{name}.")
        else:
            out[name] = value
    return out


def _definition_differences(runs: list[RecordedRun]) -> list[Difference]:
    flat = [_flatten({k: v for k, v in x.definition.items() if k != "description"}) for x in runs]
    keys = list(dict.fromkeys(k for f in flat for k in f))
    out = []
    for key in keys:
        values = [_short(f.get(key, MISSING)) for f in flat]
        if len(set(values)) > 1:
            section, _, name = key.partition(".")
            out.append(Difference(SECTIONS.get(section, "study"), name or section, values))
    return out


def _code_differences(runs: list[RecordedRun]) -> list[Difference]:
    commits = [
        f"{x.record.get('git_commit', '?')[:10]}{' +dirty' if x.record.get('git_dirty') else ''}"
        for x in runs
    ]
    return [Difference("code", "commit", commits)] if len(set(commits)) > 1 else []


def _version_differences(runs: list[RecordedRun]) -> list[Difference]:
    versions = [x.record.get("versions", {}) for x in runs]
    names = list(dict.fromkeys(k for v in versions for k in v))
    return [
        Difference("version", n, [str(v.get(n, MISSING)) for v in versions])
        for n in names
        if len({str(v.get(n, MISSING)) for v in versions}) > 1
    ]


def _short(value: Any) -> str:
    if isinstance(value, float | np.floating):
        return f"{float(value):.6g}"
    if isinstance(value, list):
        return "[" + ", ".join(_short(v) for v in value) + "]"
    if isinstance(value, np.generic):
        return str(value.item())
    return str(value)


def format_comparison(c: Comparison) -> str:
    """The comparison as text: differences, timings, then a table per response."""
    ids = [x.run_id for x in c.runs]
    lines = [f"reference {ids[0]}; compared: {', '.join(ids[1:])}", ""]
    differing = c.definition + c.code + c.versions
    lines.append("what differs:" if differing else "definitions, code and versions: identical")
    width = max((len(f"{d.kind} {d.name}") for d in differing), default=0)
    lines += [f"  {f'{d.kind} {d.name}':<{width}}  {' | '.join(d.values)}" for d in differing]
    lines += ["", "timings:"]
    for x in c.runs:
        t = x.record.get("timings", {})
        lines.append(
            f"  {x.run_id:<30} compile {t.get('compile_s', float('nan')):.2f} s, "
            f"run {t.get('run_s', float('nan')):.3f} s, {x.results.sizes['run']} design points"
        )
    lines += ["", f"responses (matched on {', '.join(c.matched_on)}):"]
    header = f"  {'response':<34} {'run':<30} {'points':>6} {'max |Δ|':>12} {'max |Δ|/|ref|':>14}"
    lines.append(header)
    for ch in c.changes:
        name = f"{ch.response} [{ch.units}]" if ch.units not in ("", "1") else ch.response
        lines.append(
            f"  {name:<34} {ch.run_id:<30} {ch.points:>6} {ch.max_abs:>12.4g} {ch.max_rel:>14.3g}"
        )
        lines += [f"      moved most at {p}: {a:.6g} → {b:.6g}" for p, a, b in ch.moved]
    moved = c.moved()
    still = [r for r in dict.fromkeys(ch.response for ch in c.changes) if r not in moved]
    lines += [
        "",
        f"moved: {', '.join(moved) or 'none'}",
        f"unchanged: {', '.join(still) or 'none'}",
    ]
    return "\n".join(lines)
