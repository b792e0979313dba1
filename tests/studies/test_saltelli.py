"""Saltelli designs and Sobol' indices (issue 27): a study of the Ishigami function, a test
scene registered for this module, gives first-order and total indices that agree with the
closed forms within their bootstrap intervals at N = 2^12, with SALib's estimators on the same
outputs to 1e-12, and intervals that shrink as 1/√N.

Ishigami f = sin x1 + a sin² x2 + b x3⁴ sin x1, a = 7, b = 0.1, x_i uniform on [−π, π]; its
variances (Ishigami & Homma 1990; Sobol' & Levitan 1999): V1 = (1 + bπ⁴/5)²/2, V2 = a²/8,
V3 = 0, V13 = b²π⁸ (1/18 − 1/50), V = V1 + V2 + V13.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
from function_scenes import function_scene, registered

from studies.analysis.analyze import analyze
from studies.common.errors import StudyError
from studies.define.plan import plan_text
from studies.run.results import build_dataset
from studies.run.runner import evaluate

A, B = 7.0, 0.1
PI = math.pi
V1 = 0.5 * (1 + B * PI**4 / 5) ** 2
V2 = A**2 / 8
V13 = B**2 * PI**8 * (1 / 18 - 1 / 50)
V = V1 + V2 + V13
S1_EXACT = np.array([V1 / V, V2 / V, 0.0])
ST_EXACT = np.array([(V1 + V13) / V, V2 / V, V13 / V])


IshigamiScene = function_scene(
    "ishigami",
    "f",
    lambda x1, x2, x3: np.sin(x1) + A * np.sin(x2) ** 2 + B * x3**4 * np.sin(x1),
    "Ishigami function",
)


@pytest.fixture(autouse=True)
def ishigami(monkeypatch: pytest.MonkeyPatch) -> Iterator[None]:
    with registered(monkeypatch, IshigamiScene):
        yield


def study(samples: int, seed: int = 1, second_order: bool = False) -> str:
    ranges = "\n".join(f"[factors.x{i}]\nrange = [{-PI!r}, {PI!r}]" for i in (1, 2, 3))
    return (
        f'name = "ishigami"\nscene = "ishigami"\nresponses = ["f"]\n[design]\n'
        f'type = "saltelli"\nsamples = {samples}\nseed = {seed}\n'
        f"second_order = {str(second_order).lower()}\n{ranges}\n"
    )


def indices(samples: int, second_order: bool = False) -> tuple[xr.Dataset, xr.Dataset]:
    plan = plan_text(study(samples, second_order=second_order))
    ds = build_dataset(plan, evaluate(plan, progress=False), {})
    return ds, analyze(ds)


def test_sobol_indices_of_ishigami_match_the_closed_forms_within_their_intervals() -> None:
    assert pytest.approx([0.3139, 0.4424, 0.0], abs=1e-4) == S1_EXACT  # the values
    assert pytest.approx([0.5576, 0.4424, 0.2437], abs=1e-4) == ST_EXACT
    ds, an = indices(2**12)
    assert ds.sizes["run"] == 2**12 * 5  # N (D + 2)
    row = an.sel(response="f")
    assert np.all(np.abs(row["S1"].values - S1_EXACT) <= row["S1_conf"].values)
    assert np.all(np.abs(row["ST"].values - ST_EXACT) <= row["ST_conf"].values)


def test_indices_agree_with_salib_on_the_same_outputs() -> None:
    from SALib.analyze import sobol

    ds, an = indices(2**10)
    problem = {"num_vars": 3, "names": ["x1", "x2", "x3"], "bounds": [[-PI, PI]] * 3}
    reference = sobol.analyze(problem, ds["f"].values, calc_second_order=False, seed=1)
    row = an.sel(response="f")
    assert row["S1"].values == pytest.approx(reference["S1"], abs=1e-12)
    assert row["ST"].values == pytest.approx(reference["ST"], abs=1e-12)


def test_intervals_shrink_as_one_over_root_n() -> None:
    conf = [
        np.concatenate([an["S1_conf"].values[0], an["ST_conf"].values[0]])
        for an in (indices(n)[1] for n in (2**10, 2**12, 2**14))
    ]
    for coarse, fine in itertools.pairwise(conf):
        ratio = coarse[[0, 1, 3, 4, 5]] / fine[[0, 1, 3, 4, 5]]  # S1 of x3 is 0: noise only
        assert np.all((ratio > 1.4) & (ratio < 2.9)), ratio  # 4× the samples: about 2×


def test_a_saltelli_design_needs_ranges_and_a_power_of_two() -> None:
    with pytest.raises(StudyError, match=r"samples = 1000 must be a power of two"):
        plan_text(study(1000))
    text = study(64).replace("range = ", "levels = ", 1)
    with pytest.raises(StudyError, match=r"factor x1: a saltelli design needs range"):
        plan_text(text)


def test_the_outputs_of_a_saltelli_run_render_the_indices(tmp_path: Path) -> None:
    from studies.report.write import write_analysis

    ds, an = indices(2**8)
    names = {p.name for p in write_analysis(ds, tmp_path)}
    assert {"analysis.txt", "report.md", "tornado_f.png", "analysis.nc"} <= names
    text = (tmp_path / "analysis.txt").read_text(encoding="utf-8")
    s1 = an["S1"].sel(response="f", factor="x2").item()
    assert f"{s1:.3g}" in text  # the table shows the analysis' value
    report = (tmp_path / "report.md").read_text(encoding="utf-8")
    assert "## f: Sobol' indices" in report
    assert "![S1 and ST of f](tornado_f.png)" in report


S13_EXACT = V13 / V  # the only interaction of the Ishigami function (module docstring)
PROBLEM = {"num_vars": 3, "names": ["x1", "x2", "x3"], "bounds": [[-PI, PI]] * 3}


def test_a_second_order_design_is_salibs_sample_in_salibs_order() -> None:
    from SALib.sample import sobol as sobol_sample

    plan = plan_text(study(2**6, seed=4, second_order=True))
    assert plan.runs == 2**6 * (2 * 3 + 2)  # N (2D + 2): A, AB_1..AB_3, BA_1..BA_3, B per row
    reference = sobol_sample.sample(
        PROBLEM, 2**6, calc_second_order=True, seed=np.random.default_rng(4)
    )
    points = np.column_stack([plan.points[f"x{i}"] for i in (1, 2, 3)])
    assert points == pytest.approx(reference, abs=1e-12)


def test_second_order_indices_agree_with_salib_on_the_same_outputs() -> None:
    from SALib.analyze import sobol

    ds, an = indices(2**9, second_order=True)
    reference = sobol.analyze(PROBLEM, ds["f"].values, calc_second_order=True, seed=1)
    row = an.sel(response="f")
    for key in ("S1", "S1_conf", "ST", "ST_conf"):  # the same resamples: the same intervals
        assert row[key].values == pytest.approx(reference[key], abs=1e-12), key
    upper = np.triu_indices(3, k=1)
    for key in ("S2", "S2_conf"):
        assert row[key].values[upper] == pytest.approx(reference[key][upper], abs=1e-12), key
        assert np.isnan(row[key].values[np.tril_indices(3)]).all()  # i < j only, as SALib


def test_second_order_indices_of_ishigami_match_the_closed_form_within_their_intervals() -> None:
    assert pytest.approx(0.2437, abs=1e-4) == S13_EXACT  # the value
    _, an = indices(2**12, second_order=True)
    row = an.sel(response="f")
    s2, conf = row["S2"].values, row["S2_conf"].values
    for (i, j), exact in {(0, 1): 0.0, (0, 2): S13_EXACT, (1, 2): 0.0}.items():
        assert abs(s2[i, j] - exact) <= conf[i, j], (i, j, s2[i, j], conf[i, j])
    assert np.all(np.abs(row["S1"].values - S1_EXACT) <= row["S1_conf"].values)
    assert np.all(np.abs(row["ST"].values - ST_EXACT) <= row["ST_conf"].values)


def test_the_report_of_a_second_order_design_has_the_table_of_s2(tmp_path: Path) -> None:
    from studies.report.write import write_analysis

    ds, an = indices(2**6, second_order=True)
    write_analysis(ds, tmp_path)
    s13 = an["S2"].sel(response="f", factor="x1", factor_b="x3").item()
    for name in ("analysis.txt", "report.md"):
        text = (tmp_path / name).read_text(encoding="utf-8")
        assert "Second-order indices (Saltelli 2002)" in text
        assert "x1 × x3" in text
        assert f"{s13:.3g}" in text
    _, first = indices(2**6)
    assert "S2" not in first  # only where asked
