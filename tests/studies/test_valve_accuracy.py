"""The speed–accuracy study: reference solved once per pair, convergence, spacing, timing logic."""

from __future__ import annotations

import math
import re
from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from studies.define.definition import StudyFileError
from studies.define.plan import plan_study, plan_text
from studies.pipeline import run_plan
from studies.scenes.valve.reference import accuracy as acc
from study_text import run

# Issue #26's reproduction: a separating cycloidal cam on a very stiff seat, at three tolerances.
ISSUE_26_CASE = """
name = "issue_26_case"
scene = "valve_accuracy"
responses = ["error_estimate", "reference_error", "tolerance_met", "integrator_used", "status"]
[parameters]
law = "cycloidal"
rise_angle = 101.5
valve_lift = 5.697
lash = 0.2253
cam_speed = 9010
seat_stiffness = 1.451e7
spring_preload = 205
drive_stiffness = 10710
equivalent_mass = 0.04494
drive_damping = 35.91
seat_damping = 58.77
external_damping = 36.46
spring_rate = 35.21
integrator = "lanes"
angle_step = 0.5
[factors.tolerance]
levels = [1e-3, 1e-4, 1e-5]
"""


def test_valve_step_accuracy_runs_with_one_reference_per_pair(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    solves: list[float] = []
    reference = acc.reference_lift

    def counting(fine, row, theta, method, rtol):
        solves.append(row[0])
        return reference(fine, row, theta, method, rtol)

    monkeypatch.setattr(acc, "reference_lift", counting)
    # The timings' precision is not checked here (cost_per_case need only be a positive
    # timing), and the study's default budget (5 repeats of at least 64 copies, fixed cost
    # under 5 %) was half of this test's time: a lighter one.
    timing = acc.timing_per_case
    monkeypatch.setattr(acc, "COST_CASES", 4)
    monkeypatch.setattr(
        acc, "timing_per_case", lambda run, row: timing(run, row, max_overhead=0.25, repeats=3)
    )
    plan = plan_study("valve_step_accuracy")
    plan.scene.reference_cache.entries.clear()
    result = run_plan(plan, tmp_path, progress=False)
    everything = result.dataset
    assert everything.sizes["run"] == 160
    assert len(solves) == 4  # camshaft speed × seat stiffness pairs
    assert (result.folder / "error_vs_cost.png").stat().st_size > 10_000
    assert "timing" in everything["cost_per_case"].attrs["long_name"]
    assert (everything["cost_per_case"] > 0.0).all()
    # Every finished point has an error bar; under the tolerance it is met wherever the bar
    # is within it, and the true error (against scipy) is within 1 µm.
    finished = everything["status"] == 0
    assert np.isfinite(everything["error_estimate"].where(finished, drop=True)).all()
    tolerant = everything.where(everything["tolerance"] > 0.0, drop=True)
    assert (tolerant["tolerance_met"] == 1).all()
    assert (tolerant["reference_error"] <= 1e-3).all()
    ds = everything.where(everything["tolerance"] == 0.0, drop=True)
    # The lane kernel integrates the same RK4 scheme as rk4: the same trajectory error.
    lanes = ds.where(ds["integrator"] == "lanes", drop=True)
    rk4 = ds.where(ds["integrator"] == "rk4", drop=True)
    np.testing.assert_array_equal(lanes["reference_error"], rk4["reference_error"])
    # Single precision has its own trajectory. Where the valve follows the cam (3500 rpm) its
    # round-off is far below the RK4 error, so the errors agree to 0.5 %; in the violent
    # separation at 6000 rpm the flight amplifies round-off like any perturbation, so only
    # to 10 % (measured: 7 %, at 0.125 deg, 0.36 µm against 0.34 µm).
    single = ds.where(ds["integrator"] == "lanes_f32", drop=True)
    follows = (single["cam_speed"] < 4000.0).values
    error, double = single["reference_error"].values, lanes["reference_error"].values
    np.testing.assert_allclose(error[follows], double[follows], rtol=0.005)
    np.testing.assert_allclose(error[~follows], double[~follows], rtol=0.10)
    # The adaptive pair (its own fine table and located switches) is within 1 µm of the
    # reference at every step, speed and seat of the study (docs/accuracy.md: ≤ 0.52 µm on 48 random
    # points at its default 1e-7 m per step).
    dopri = ds.where(ds["integrator"] == "dopri", drop=True)
    assert (dopri["reference_error"] <= 1e-3).all()
    assert (error != double).any()
    # Convergence towards the reference: the switch-aware runs at 0.125 deg are at least five
    # times closer to it than at 1 deg, for every speed and seat stiffness.
    aware = ds.where(ds["integrator"] == "rk4_switch_aware", drop=True)
    coarse = aware.where(aware["angle_step"] == 1.0, drop=True)["reference_error"].values
    fine = aware.where(aware["angle_step"] == 0.125, drop=True)["reference_error"].values
    assert (fine * 5.0 < coarse).all()
    # The report says what ran wherever it names a run's levels (issue 23 re-read, S0): with a
    # tolerance the scene picks the integrator and step per point. Every run named in the
    # reference_error section's condition table is checked against the results themselves
    # (integrator_used, angle_step_used): "ran integrator = X" exactly where X is not the
    # requested integrator.
    report = (result.folder / "report.md").read_text(encoding="utf-8")
    section = report.split("## reference_error")[1].split("\n## ")[0]
    used = everything["integrator_used"]
    meanings = str(used.attrs["flag_meanings"]).split()
    codes = [int(c) for c in used.attrs["flag_values"]]
    named = re.findall(r"\(run (\d+): ([^|]*)\) \|", section)
    assert len(named) == 4  # the best run of each of the 4 conditions
    replaced = 0
    for number, text in named:
        index = int(number) - 1
        ran = meanings[codes.index(int(used.values[index]))]
        asked = str(everything["integrator"].values[index])
        assert (f"ran integrator = {ran}" in text) == (ran != asked), text
        replaced += ran != asked
    assert replaced  # the shipped case: lanes at 1 degree answered by dopri


def test_accuracy_scene_checks_each_step_factor() -> None:
    text = """
name = "acc"
scene = "valve_accuracy"
responses = ["reference_error"]
[factors.angle_step]
levels = [0.5, 0.3]
[factors.integrator]
levels = ["rk4", "lanes"]
"""
    with pytest.raises(StudyFileError) as info:
        plan_text(text)
    assert "design points 2–3: angle_step = 0.3 deg is not allowed" in str(info.value)


@given(st.lists(st.integers(1, 400), min_size=1, max_size=5), st.sampled_from([64, 100, 1000]))
def test_common_spacing_is_the_largest_common_divisor(numerators: list[int], scale: int) -> None:
    # Brute force: the largest d (in 1/scale units) dividing every step.
    steps = [n / scale for n in numerators]
    best = max(d for d in range(1, min(numerators) + 1) if all(n % d == 0 for n in numerators))
    assert Fraction(acc.common_spacing(steps)).limit_denominator(10**6) == Fraction(best, scale)


def test_max_error_compares_on_the_shared_nodes() -> None:
    # The fine reference holds three nodes per coarse one; only the shared nodes count.
    reference = np.array([0.0, 9.0, 9.0, 1.0, 9.0, 9.0, 2.5])
    assert acc.max_error(np.array([0.0, 1.0, 2.0]), reference, 3) == pytest.approx(0.5)


def test_seconds_per_case_grows_the_batch_until_the_call_overhead_is_small() -> None:
    sizes: list[int] = []
    row = np.arange(3.0)

    def run(rows: np.ndarray) -> None:
        sizes.append(rows.shape[0])
        np.testing.assert_array_equal(rows, np.tile(row, (rows.shape[0], 1)))

    # a call that costs the same whatever its size is all overhead: the batch grows to the cap
    seconds = acc.seconds_per_case(run, row, max_overhead=0.0, repeats=2)
    doublings = int(math.log2(acc.MAX_COST_CASES // acc.COST_CASES))
    grown = [acc.COST_CASES * 2**k for k in range(doublings + 1)]
    assert sizes == [1, 1, *grown, acc.MAX_COST_CASES]
    assert 0.0 <= seconds < math.inf
    sizes.clear()
    acc.seconds_per_case(run, row, max_overhead=math.inf, repeats=3)
    assert sizes == [1, 1, 1] + [acc.COST_CASES] * 3


def test_timing_is_the_median_of_repeats_with_its_interquartile_range(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    # Timings replaced by known numbers (no wall clock in a test): 5 one-case calls, then the
    # calibration run at COST_CASES copies and 4 more; median and IQR per case from numpy.
    timed = iter([1e-3] * 5 + [0.64, 0.96, 0.32, 6.4, 0.64])
    monkeypatch.setattr(acc, "_seconds", lambda run, rows: next(timed))
    median, iqr = acc.timing_per_case(lambda rows: None, np.arange(3.0), repeats=5)
    runs = np.array([0.64, 0.96, 0.32, 6.4, 0.64]) / acc.COST_CASES
    assert median == pytest.approx(np.median(runs))
    assert iqr == pytest.approx(np.percentile(runs, 75) - np.percentile(runs, 25))
    assert iqr < 0.1 * runs.max()  # one outlier (6.4) moves neither the median nor the IQR


@pytest.mark.slow
def test_tolerance_met_holds_against_scipy_on_the_issue_26_case() -> None:
    # Issue #26: at 1e-4 mm dopri answered with an error bar of 2.8e-5 mm, tolerance_met 1 and
    # a true error of 2.2e-3 mm. At lash take-up the drive force jumps by ~65 N; the steps had
    # grown fivefold per step while the valve rested, and the switch was returned at the far
    # end of a long bracket after a fixed 60 iterations; the companion run made the same late
    # switch. Now switches are bracketed to 1e-9 rad of cam and the companion caps its steps
    # at the grid step. Expected values: reference_error, the scene's event-restarted scipy
    # DOP853 (rtol 1e-10) on the chain's lift every 1/512 deg.
    out = run(ISSUE_26_CASE).scalars
    assert (out["status"] == 0).all()
    tolerance = np.array([1e-3, 1e-4, 1e-5])
    met = out["tolerance_met"] == 1.0
    print(
        f"bar {out['error_estimate']}, true {out['reference_error']}, met {met}, "
        f"integrator {out['integrator_used']}"
    )
    assert met[0]  # 1e-3 mm is met (true error 3.2e-4 mm on this machine)
    # At 1e-4 mm the bar (1.5e-4 mm) exceeds the tolerance while the true error is 6.7e-5 mm:
    # reported as not met, conservative but true. What must never happen is the issue's case,
    # "met" above the tolerance, and a bar below the true error:
    assert (out["reference_error"][met] <= tolerance[met]).all()
    assert (out["reference_error"] <= out["error_estimate"]).all()
