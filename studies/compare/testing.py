"""Assertions for a user's own test suite: is a fresh run still the baseline?

from studies.pipeline import run_study
from studies.compare.testing import assert_results_close

def test_my_cam_still_matches_the_baseline(tmp_path):
    fresh = run_study("my_cam.toml", outputs=tmp_path, progress=False).dataset
    assert_results_close(fresh, "tests/data/my_cam_baseline.nc", {"max_jerk": 1e-6})
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import xarray as xr

from studies.compare.regress import (
    DEFAULT_ATOL,
    DEFAULT_RTOL,
    Tolerance,
    check_results,
    format_checks,
)
from studies.compare.runs import matched_points, point_label
from studies.run.results import readable

ToleranceSpec = float | dict[str, float] | Tolerance


def assert_results_close(
    results: xr.Dataset | str | Path,
    baseline: xr.Dataset | str | Path,
    tolerances: dict[str, ToleranceSpec] | None = None,
    rtol: float = DEFAULT_RTOL,
    atol: float = DEFAULT_ATOL,
) -> None:
    """Raise AssertionError with a table of the responses that moved when ``results`` differ
    from ``baseline`` beyond tolerance at any design point (matched by factor values).

    ``tolerances`` maps a response to its rtol (a number), to ``{"rtol": …, "atol": …}`` or to a
    :class:`studies.compare.regress.Tolerance`; other responses use ``rtol``/``atol``. Each response is
    checked with :func:`xarray.testing.assert_allclose`, whose message follows the table.
    """
    actual, expected = _dataset(results), _dataset(baseline)
    limits = {name: _tolerance(spec, rtol, atol) for name, spec in (tolerances or {}).items()}
    checks = check_results(actual, expected, limits, Tolerance(rtol, atol))
    both = _on_common_points(actual, expected)
    failures = []
    for c in checks:
        if c.problem:
            failures.append(f"{c.response}: {c.problem}")
            continue
        try:
            xr.testing.assert_allclose(
                both[f"{c.response}_other"].rename(c.response),
                both[c.response],
                rtol=c.tolerance.rtol,
                atol=c.tolerance.atol,
            )
        except AssertionError as exc:
            failures.append(f"{c.response}: {exc}")
    if failures:
        raise AssertionError(format_checks(checks) + "\n\n" + "\n\n".join(failures))


def _dataset(value: xr.Dataset | str | Path) -> xr.Dataset:
    if isinstance(value, xr.Dataset):
        return value
    with readable(value) as ds:
        return ds.load()


def _tolerance(spec: ToleranceSpec, rtol: float, atol: float) -> Tolerance:
    if isinstance(spec, Tolerance):
        return spec
    if isinstance(spec, dict):
        return Tolerance(float(spec.get("rtol", rtol)), float(spec.get("atol", atol)))
    return Tolerance(float(spec), atol)


def _on_common_points(actual: xr.Dataset, expected: xr.Dataset) -> xr.Dataset:
    """Both runs' responses on their common design points, labelled by the factor values
    (``<response>`` from the baseline, ``<response>_other`` from the run)."""
    factors = json.loads(expected.attrs.get("factors", "[]"))
    common = matched_points(expected, actual, factors)
    labels = [point_label(common, i) for i in range(len(common))]
    return xr.Dataset(
        {str(k): ("point", v.to_numpy(np.float64)) for k, v in common.items()}
    ).assign_coords(point=labels)
