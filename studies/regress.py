"""Regression check: did any response move beyond its tolerance from a baseline run?

A point passes when ``|value - baseline| <= atol + rtol * |baseline|`` (the criterion of
``numpy.isclose`` and ``xarray.testing.assert_allclose``; NaN matches NaN). Points are matched
by the factor values (:func:`studies.compare.matched_points`); a baseline point that the run
does not have fails, and so do differing units. Tolerances per response come from a TOML file::

    [max_contact_stress]   # MPa
    rtol = 1e-6
    [cost_per_case]        # a wall-clock timing: never compared
    rtol = inf
"""

from __future__ import annotations

import json
import math
import tomllib
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import xarray as xr

from studies.bounded_files import TABLE_FILE_BYTES, read_bounded_text
from studies.compare import matched_points, point_label, point_table
from studies.results import is_status

DEFAULT_RTOL = 1e-7
DEFAULT_ATOL = 0.0


@dataclass(frozen=True)
class Tolerance:
    rtol: float = DEFAULT_RTOL
    atol: float = DEFAULT_ATOL


@dataclass(frozen=True)
class Check:
    """One response's verdict."""

    response: str
    units: str
    tolerance: Tolerance
    points: int
    beyond: int
    max_abs: float
    max_rel: float
    worst: str
    problem: str = ""  # units differ, points missing

    @property
    def ok(self) -> bool:
        return self.beyond == 0 and not self.problem


def read_tolerances(path: Path) -> dict[str, Tolerance]:
    """``[response] rtol = …, atol = …`` tables of a TOML file (ValueError on anything else)."""
    try:
        raw = tomllib.loads(read_bounded_text(path, "--tolerances", TABLE_FILE_BYTES))
    except tomllib.TOMLDecodeError as exc:
        raise ValueError(f"{path}: not valid TOML ({exc})") from None
    out = {}
    for name, table in raw.items():
        unknown = set(table) - {"rtol", "atol"} if isinstance(table, dict) else {"(not a table)"}
        if unknown:
            msg = f"{path}: [{name}] may hold rtol and atol only, not {', '.join(sorted(unknown))}"
            raise ValueError(msg)
        out[name] = Tolerance(
            float(table.get("rtol", DEFAULT_RTOL)), float(table.get("atol", DEFAULT_ATOL))
        )
    return out


def compared_responses(ds: xr.Dataset) -> list[str]:
    names = json.loads(ds.attrs.get("responses", "[]")) or list(ds.data_vars)
    return [str(n) for n in names if n in ds and ds[n].dims == ("run",)]


def check_results(
    results: xr.Dataset,
    baseline: xr.Dataset,
    tolerances: dict[str, Tolerance] | None = None,
    default: Tolerance = Tolerance(),
) -> list[Check]:
    """A :class:`Check` per response of the baseline (ValueError when nothing is comparable)."""
    tolerances = tolerances or {}
    responses = compared_responses(baseline)
    unknown = sorted(set(tolerances) - set(responses))
    if unknown:
        msg = f"tolerances name responses the baseline does not have: {', '.join(unknown)}"
        raise ValueError(msg)
    shared = [r for r in responses if r in results]
    if not shared:
        msg = f"the run has none of the baseline's responses ({', '.join(responses)})"
        raise ValueError(msg)
    factors = json.loads(baseline.attrs.get("factors", "[]"))
    common = matched_points(baseline, results, factors)
    expected_points = len(point_table(baseline, factors, []))
    checks = []
    for r in responses:
        tol = tolerances.get(r, default)
        units = str(baseline[r].attrs.get("units", ""))
        if r not in results:
            checks.append(Check(r, units, tol, 0, 0, math.nan, math.nan, "", "missing in the run"))
            continue
        problems = []
        if str(results[r].attrs.get("units", "")) != units:
            problems.append(f"units {results[r].attrs.get('units', '')!r} ≠ baseline {units!r}")
        if len(common) < expected_points:
            problems.append(f"{expected_points - len(common)} baseline points missing")
        checks.append(
            _check(common, r, units, tol, factors, "; ".join(problems), is_status(baseline[r]))
        )
    return checks


def _check(
    common, response: str, units: str, tol: Tolerance, factors: list[str], problem: str, exact: bool
) -> Check:
    expected = common[response].to_numpy(np.float64)
    actual = common[f"{response}_other"].to_numpy(np.float64)
    rtol, atol = (0.0, 0.0) if exact else (tol.rtol, tol.atol)
    with np.errstate(invalid="ignore"):
        diff = np.abs(actual - expected)
        same = (actual == expected) | (np.isnan(actual) & np.isnan(expected))  # incl. ±inf
        inside = same | (np.isfinite(diff) & (diff <= atol + rtol * np.abs(expected)))
        if math.isinf(rtol) or math.isinf(atol):
            inside[:] = True
        diff = np.where(same, 0.0, np.where(np.isnan(diff), np.inf, diff))
        rel = np.where(diff == 0, 0.0, diff / np.abs(expected))
    worst = int(np.argmax(diff)) if diff.size else 0
    where = point_label(common.index[worst], factors) if diff.size and diff[worst] > 0 else ""
    if where:
        where += f": {expected[worst]:.8g} → {actual[worst]:.8g}"
    return Check(
        response,
        units,
        Tolerance(rtol, atol),
        len(common),
        int((~inside).sum()),
        float(diff.max(initial=0.0)),
        float(rel.max(initial=0.0)),
        where,
        problem,
    )


def format_checks(checks: list[Check]) -> str:
    """The verdicts as a table, failures marked, the worst point of each response below it."""
    lines = [
        (
            f"{'':2}{'response':<40} {'rtol':>8} {'atol':>8} {'beyond':>9} {'max |Δ|':>10} "
            f"{'max rel':>9}"
        )
    ]
    for c in checks:
        name = f"{c.response} [{c.units}]" if c.units not in ("", "1") else c.response
        mark = "  " if c.ok else "✗ "
        lines.append(
            f"{mark}{name:<40} {c.tolerance.rtol:>8.2g} {c.tolerance.atol:>8.2g} "
            f"{f'{c.beyond}/{c.points}':>9} {c.max_abs:>10.3g} {c.max_rel:>9.3g}"
        )
        if not c.ok:
            lines += [f"{'':4}{text}" for text in (c.problem, c.worst) if text]
    failed = [c.response for c in checks if not c.ok]
    lines.append(
        f"FAILED: {', '.join(failed)} moved beyond tolerance" if failed else "all within tolerance"
    )
    return "\n".join(lines)
