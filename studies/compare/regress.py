"""Regression check: did any response move beyond its tolerance from a baseline run?

A point passes when ``|value - baseline| <= atol + rtol * |baseline|`` (the criterion of
``numpy.isclose`` and ``xarray.testing.assert_allclose``; NaN matches NaN). Points are matched
by the factor values (:func:`studies.compare.runs.matched_points`); under ``[noise]`` every
(design point, noise case) value is a point, matched on the noise case too. A baseline point
that the run does not have fails, and so do differing units. Tolerances per response come from
a TOML file::

    [max_contact_stress]   # MPa
    rtol = 1e-6
    [cost_per_case]        # a wall-clock timing: never compared
    rtol = inf
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass

import numpy as np
import xarray as xr

from studies.common.errors import StudyError
from studies.compare.runs import matched_points, point_label, point_table
from studies.compare.tolerances import (
    DEFAULT,
    DEFAULT_ATOL,
    DEFAULT_RTOL,
    Tolerance,
    deviations,
    read_tolerances,
)
from studies.run.results import is_scalar, is_status

__all__ = ["DEFAULT_ATOL", "DEFAULT_RTOL", "Tolerance", "read_tolerances"]


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


def compared_responses(ds: xr.Dataset) -> list[str]:
    names = json.loads(ds.attrs.get("responses", "[]")) or list(ds.data_vars)
    return [str(n) for n in names if n in ds and is_scalar(ds[n])]


def check_results(
    results: xr.Dataset,
    baseline: xr.Dataset,
    tolerances: dict[str, Tolerance] | None = None,
    default: Tolerance = DEFAULT,
) -> list[Check]:
    """A :class:`Check` per response of the baseline (ValueError when nothing is comparable)."""
    tolerances = tolerances or {}
    responses = compared_responses(baseline)
    unknown = sorted(set(tolerances) - set(responses))
    if unknown:
        msg = f"tolerances name responses the baseline does not have: {', '.join(unknown)}"
        raise StudyError(msg)
    shared = [r for r in responses if r in results]
    if not shared:
        msg = f"the run has none of the baseline's responses ({', '.join(responses)})"
        raise StudyError(msg)
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
        checks.append(_check(common, r, units, tol, "; ".join(problems), is_status(baseline[r])))
    return checks


def _check(common, response: str, units: str, tol: Tolerance, problem: str, exact: bool) -> Check:
    expected = common[response].to_numpy(np.float64)
    actual = common[f"{response}_other"].to_numpy(np.float64)
    tol = Tolerance(0.0, 0.0) if exact else tol
    inside, diff, rel = deviations(expected, actual, tol)
    worst = int(np.argmax(diff)) if diff.size else 0
    where = point_label(common, worst) if diff.size and diff[worst] > 0 else ""
    if where:
        where += f": {expected[worst]:.8g} → {actual[worst]:.8g}"
    return Check(
        response,
        units,
        tol,
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
