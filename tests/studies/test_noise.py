"""Noise factors (issue 27): the ``[noise]`` and ``[limits]`` tables, the noise cases of each
design point, results on ``run × noise`` and the statistics under noise.

The crank scene's mean piston speed cm = S n / 30 [K4] is linear in the engine speed n, so a
normal noise on n gives a normal cm with mean S μ/30 and sd S σ/30: the closed forms the
statistics are checked against.
"""

from __future__ import annotations

import errno
import math
import os
from pathlib import Path
from unittest import mock

import numpy as np
import pytest
from scipy import stats

from studies.analysis.uncertainty.noise_statistics import QUANTILES, quantile_interval, wilson
from studies.common.errors import StudyError
from studies.define.plan import plan_text
from studies.pipeline import run_plan
from studies.run.results import open_results

BASE = """
name = "crank_noise"
scene = "crank"
responses = ["mean_piston_speed"]
[design]
type = "L4"
[parameters]
engine_speed = 2600.0
[factors.stroke]
levels = [150.0, 170.0]
[factors.rod_ratio]
levels = [0.25, 0.3]
"""
SOBOL = """
[noise]
type = "sobol"
samples = 1024
seed = 7
[noise.engine_speed]
distribution = "normal"
sd = 100
[limits]
mean_piston_speed = { max = 13.5 }
"""


def problems_of(text: str) -> str:
    with pytest.raises(StudyError) as info:
        plan_text(text)
    return str(info.value)


@pytest.mark.parametrize(
    ("noise", "expected"),
    [
        (  # a negative standard deviation
            '[noise]\ntype = "L4"\n[noise.engine_speed]\ndistribution = "normal"\nsd = -5',
            "[noise.engine_speed] sd = -5 must be a number > 0",
        ),
        (  # explicit levels on a control factor: they would replace its levels
            '[noise]\ntype = "L4"\n[noise.stroke]\nlevels = [149, 151]',
            "stroke is also a factor in [factors]",
        ),
        (  # 2600 ± 6·500 rpm reaches -400 rpm: refused, not truncated
            '[noise]\ntype = "L4"\n[noise.engine_speed]\ndistribution = "normal"\nsd = 500',
            "reaches -400 rpm ± 6 sd, outside the valid range: engine_speed allows",
        ),
        (  # a uniform distribution past the range's end (engine speed ≤ 30000 rpm)
            (
                '[noise]\ntype = "L4"\n[noise.engine_speed]\ndistribution = "uniform"\n'
                "half_width = 40000"
            ),
            "reaches 42600 rpm, outside the valid range",
        ),
        (
            '[noise]\ntype = "L4"\n[noise.engine_speed]\ndistribution = "normal"\nsd = 5\nmean = 1',
            "unknown key 'mean' in [noise.engine_speed]",
        ),
        (
            '[noise]\ntype = "L7"\n[noise.engine_speed]\ndistribution = "normal"\nsd = 5',
            "[noise] type = 'L7' must be an orthogonal array name",
        ),
        (
            (
                '[noise]\ntype = "sobol"\nsamples = 100\n[noise.engine_speed]\n'
                'distribution = "normal"\nsd = 5'
            ),
            "[noise] samples = 100 must be a power of two",
        ),
        (
            '[noise]\ntype = "lhs"\n[noise.engine_speed]\ndistribution = "gamma"\nsd = 5',
            "[noise] samples = 0 must be a whole number",
        ),
        (
            '[noise]\ntype = "L4"\n[noise.engine_speed]\ndistribution = "gamma"\nsd = 5',
            "[noise.engine_speed] distribution = 'gamma' must be one of 'normal', 'uniform'",
        ),
        (  # a count takes explicit levels, not a distribution
            '[noise]\ntype = "L4"\n[noise.cylinders]\ndistribution = "normal"\nsd = 1',
            "[noise.cylinders]: cylinders is a whole number (a count): give explicit levels",
        ),
        (
            '[noise]\ntype = "L4"\n[noise.engine_sped]\ndistribution = "normal"\nsd = 5',
            "did you mean 'engine_speed'?",
        ),
        (
            (
                '[noise]\ntype = "L4"\n[noise.engine_speed]\ndistribution = "normal"\nsd = 5\n'
                "[limits]\nmax_piston_velocity = { min = 1 }"
            ),
            "[limits] names 'max_piston_velocity', which is not in responses",
        ),
    ],
)
def test_hostile_noise_tables_get_one_clear_message(noise: str, expected: str) -> None:
    assert expected in problems_of(BASE + noise)


def test_a_refused_noise_study_writes_nothing(tmp_path: Path) -> None:
    from studies.pipeline import run_study

    study = tmp_path / "bad.toml"
    study.write_text(
        BASE + '[noise]\ntype = "L4"\n[noise.engine_speed]\nsd = -1\ndistribution = "normal"',
        encoding="utf-8",
    )
    outputs = tmp_path / "outputs"
    with pytest.raises(StudyError):
        run_study(study, outputs=outputs, progress=False)
    assert not outputs.exists() or not any(outputs.rglob("*.nc"))


def test_outer_arrays_put_distributions_at_taguchis_levels() -> None:
    # Phadke 1989 §8.4: 2-level columns μ ± σ, 3-level columns μ, μ ± σ·√(3/2); uniform
    # half width a has σ = a/√3.
    l4 = plan_text(
        BASE + '[noise]\ntype = "L4"\n[noise.engine_speed]\ndistribution = "normal"\nsd = 100\n'
        '[noise.stroke]\ndistribution = "uniform"\nhalf_width = 3\n'
    )
    assert l4.noise_cases == 4
    speeds = l4.noise_values["engine_speed"]
    assert levels_of(speeds[0]) == pytest.approx([2500.0, 2700.0], rel=1e-12)
    strokes = l4.noise_values["stroke"]  # a tolerance about each design point's level
    assert levels_of(strokes[0]) == pytest.approx([150 - math.sqrt(3), 150 + math.sqrt(3)])
    assert levels_of(strokes[-1]) == pytest.approx([170 - math.sqrt(3), 170 + math.sqrt(3)])
    l9 = plan_text(
        BASE + '[noise]\ntype = "L9"\n[noise.engine_speed]\ndistribution = "normal"\nsd = 10\n'
        "relative = true\n"
    )
    expected = [2600 * (1 - 0.1 * math.sqrt(1.5)), 2600.0, 2600 * (1 + 0.1 * math.sqrt(1.5))]
    assert levels_of(l9.noise_values["engine_speed"][0]) == pytest.approx(expected, rel=1e-12)
    # every design point × noise case is one computed point, design point major
    assert l9.cases == 4 * 9
    assert np.allclose(
        l9.points["engine_speed"][:9] * 30 / math.pi, l9.noise_values["engine_speed"][0]
    )


def levels_of(values: np.ndarray) -> list[float]:
    """The distinct values (to 1e-9 relative), sorted."""
    ordered = np.sort(values)
    keep = np.concatenate([[True], np.diff(ordered) > 1e-9 * np.abs(ordered[1:])])
    return list(ordered[keep])


@pytest.fixture(scope="module")
def sobol_run(tmp_path_factory: pytest.TempPathFactory):
    outputs = tmp_path_factory.mktemp("outputs")
    plan = plan_text(BASE + SOBOL)
    return run_plan(plan, outputs, chunk_size=1000, progress=False)  # 1000 → 0 whole points: 1024


def test_results_hold_run_by_noise_with_the_noise_values_as_coordinates(sobol_run) -> None:
    ds = sobol_run.dataset
    assert ds["mean_piston_speed"].dims == ("run", "noise")
    assert ds.sizes == {"run": 4, "noise": 1024}
    speed = ds["engine_speed_noise"]
    assert speed.dims == ("run", "noise")
    stroke_m = ds["stroke"].values[:, None] * 1e-3
    # cm = S n / 30 with n in rpm [K4]: each case computed at its own noise value
    expected = stroke_m * speed.values / 30.0
    assert np.allclose(ds["mean_piston_speed"].values, expected, rtol=1e-12)
    sd = ds["mean_piston_speed"].std("noise", ddof=1).values
    assert np.allclose(sd, ds["stroke"].values * 1e-3 * 100 / 30, rtol=0.05)


def test_statistics_under_noise_match_the_closed_form(sobol_run) -> None:
    import xarray as xr

    an = xr.open_dataset(sobol_run.folder / "analysis.nc")
    row = an.sel(noise_response="mean_piston_speed")
    for run, stroke in enumerate(sobol_run.dataset["stroke"].values):
        s = stroke * 1e-3
        mu, sigma = s * 2600 / 30, s * 100 / 30  # cm = S n/30, n ~ N(2600, 100) rpm
        at = row.isel(run=run)
        assert float(at.noise_mean_low) <= mu <= float(at.noise_mean_high)
        assert float(at.noise_sd_low) <= sigma <= float(at.noise_sd_high)
        for j, p in enumerate(QUANTILES):
            exact = mu + sigma * stats.norm.ppf(p)
            q = at.noise_quantile_low.values[j], at.noise_quantile_high.values[j]
            assert q[0] <= exact <= q[1], (p, q, exact)
        exceed = stats.norm.sf(13.5, mu, sigma)  # P(cm > 13.5 m/s)
        assert float(at.violation_low) <= exceed <= float(at.violation_high), (run, exceed)
    assert int(row.robust_run) in (0, 1)  # the 150 mm stroke keeps cm lowest
    text = (sobol_run.folder / "analysis.txt").read_text(encoding="utf-8")
    assert "P(mean_piston_speed > 13.5 m/s) [95 % Wilson]" in text
    report = (sobol_run.folder / "report.md").read_text(encoding="utf-8")
    assert "## Under noise" in report
    assert "![mean_piston_speed under noise](noise_mean_piston_speed.png)" in report
    assert (sobol_run.folder / "noise_mean_piston_speed.png").read_bytes()[:4] == b"\x89PNG"


def test_an_outer_l4_gives_the_sn_ratio_computed_by_hand(tmp_path: Path) -> None:
    plan = plan_text(
        BASE + '[noise]\ntype = "L4"\n[noise.engine_speed]\ndistribution = "normal"\nsd = 100\n'
        '[noise.stroke]\ndistribution = "normal"\nsd = 1.5\n'
    )
    result = run_plan(plan, tmp_path, progress=False)
    import xarray as xr

    an = xr.open_dataset(result.folder / "analysis.nc")
    # By hand, run 1 (stroke 150 mm): the L4's first two columns cross S = 148.5, 151.5 mm with
    # n = 2500, 2700 rpm; cm = S n / 30:
    #   0.1485·2500/30 = 12.375, 0.1485·2700/30 = 13.365,
    #   0.1515·2500/30 = 12.625, 0.1515·2700/30 = 13.635 m/s.
    # Smaller is better: η = -10 log10((12.375² + 13.365² + 12.625² + 13.635²)/4)
    #   = -10 log10((153.140625 + 178.623225 + 159.390625 + 185.913225)/4)
    #   = -10 log10(169.266925) = -22.285721 dB
    assert float(an["mean_piston_speed_sn"].isel(run=0)) == pytest.approx(-22.285721, abs=1e-6)
    assert float(an["mean_piston_speed_mean"].isel(run=0)) == pytest.approx(
        (12.375 + 13.365 + 12.625 + 13.635) / 4, rel=1e-12
    )


def test_order_statistic_and_wilson_intervals_agree_with_references() -> None:
    y = np.arange(1.0, 101.0)[None, :]  # 1..100
    _, low, high = quantile_interval(y, 0.5)
    # scipy.stats.quantile_test's interval for the median of 1..100 (an independent solver)
    ci = stats.quantile_test(y[0], q=50.5, p=0.5).confidence_interval(0.95)
    assert (float(low[0]), float(high[0])) == (ci.low, ci.high)
    p, lo, hi = wilson(np.array([3]), np.array([40]))
    # Wilson score interval by its closed form, z = 1.959964
    z, n, ph = stats.norm.ppf(0.975), 40, 3 / 40
    centre = (ph + z * z / (2 * n)) / (1 + z * z / n)
    half = z / (1 + z * z / n) * math.sqrt(ph * (1 - ph) / n + z * z / (4 * n * n))
    assert (float(lo[0]), float(hi[0])) == pytest.approx((centre - half, centre + half), 1e-12)
    assert float(p[0]) == 3 / 40


L4_NOISE = (
    BASE + '[noise]\ntype = "L4"\n[noise.engine_speed]\ndistribution = "normal"\nsd = 100\n'
    '[noise.stroke]\ndistribution = "normal"\nsd = 1.5\n'
)


def test_a_noise_run_stopped_at_a_checkpoint_resumes_to_the_same_numbers(tmp_path: Path) -> None:
    from run_faults import failing_on_call

    from studies import pipeline
    from studies.cli import EXIT_OUTPUT_ERROR, main
    from studies.tracking.store import RunStore

    study = tmp_path / "study.toml"
    study.write_text(L4_NOISE, encoding="utf-8")
    whole, broken = tmp_path / "whole", tmp_path / "broken"
    args = ["run", str(study), "--no-progress", "--chunk-size", "6"]  # 6 → 4: one design point
    assert main([*args, "--outputs", str(whole)]) == 0
    crash = OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
    with mock.patch.object(
        pipeline, "_save_chunk", failing_on_call(pipeline._save_chunk, 3, crash)
    ):
        assert main([*args, "--outputs", str(broken)]) == EXIT_OUTPUT_ERROR
    (row,) = RunStore(broken).list_runs()
    assert len(list((Path(row["folder"]) / "chunks").glob("*.npz"))) == 2  # design points 1-2
    assert main(["run", "--resume", row["run_id"], "--outputs", str(broken)]) == 0
    (done,) = RunStore(broken).list_runs()
    (reference,) = RunStore(whole).list_runs()
    resumed = open_results(Path(done["folder"]) / "results.nc")
    expected = open_results(Path(reference["folder"]) / "results.nc")
    assert resumed["mean_piston_speed"].dims == ("run", "noise")
    np.testing.assert_array_equal(resumed["mean_piston_speed"], expected["mean_piston_speed"])
    np.testing.assert_array_equal(resumed["stroke_noise"], expected["stroke_noise"])


def test_a_noise_study_larger_than_the_machine_allows_is_refused(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    # 4 design points × 2^20 noise cases = 4.2e6 points > the limit set here: refused in the
    # plan, before any point is allocated beyond the noise table.
    monkeypatch.setenv("ENGINE_STUDIES_MAX_POINTS", "1000000")
    text = BASE + SOBOL.replace("samples = 1024", f"samples = {2**20}")
    problems = problems_of(text)
    assert "noise study of 4 design points x 1048576 noise cases = 4.194e+06 design points" in (
        problems
    )
    assert "the limit is 1e+06 points (ENGINE_STUDIES_MAX_POINTS=1000000)" in problems


def test_the_noise_table_prints_each_design_points_own_statistics(
    sobol_run, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Each row of the table under noise holds its run's factor values, mean and sd — checked
    against numpy over that run's noise cases in results.nc (not against the analysis) — and a
    design larger than MAX_ROWS lists MAX_ROWS rows."""
    import xarray as xr

    from studies.report.markdown_format import num
    from studies.report.uncertainty import noise_report

    ds = sobol_run.dataset
    an = xr.open_dataset(sobol_run.folder / "analysis.nc")
    header, rows = noise_report._rows(ds, an, "mean_piston_speed")
    assert len(rows) == ds.sizes["run"] == 4
    y = ds["mean_piston_speed"].values
    for i, row in enumerate(rows):
        cells = dict(zip(header, row, strict=True))
        assert cells["run"] == str(i + 1)
        assert cells["stroke"] == num(float(ds["stroke"].values[i]))
        assert cells["rod_ratio"] == num(float(ds["rod_ratio"].values[i]))
        assert cells["mean [95 % CI]"].startswith(f"{num(float(y[i].mean()))} [")
        assert cells["sd"] == num(float(y[i].std(ddof=1)))
    monkeypatch.setattr(noise_report, "MAX_ROWS", 2)
    assert len(noise_report._rows(ds, an, "mean_piston_speed")[1]) == 2


def test_the_sd_interval_is_bonetts_and_covers_a_skewed_response() -> None:
    """Bonett's (2006) interval, written row by row with scipy's trimmed mean, equals the
    vectorised one (rows of different lengths, NaN cases left out); and on a log-normal
    response (σ = 1: sd = √((e − 1) e), closed form) it covers the true sd in 200 fresh
    scrambled Sobol' samples of 64 cases where the normal-theory χ² interval does not."""
    from scipy.stats import qmc

    from studies.analysis.uncertainty.noise_statistics import sd_interval

    rng = np.random.default_rng(3)
    y = rng.lognormal(size=(3, 40))
    y[1, 30:] = np.nan
    finite = np.isfinite(y)
    n = finite.sum(axis=1)
    var = np.array([np.var(r[np.isfinite(r)], ddof=1) for r in y])
    low, high = sd_interval(y, finite, n, var)
    z = stats.norm.ppf(0.975)
    for i, row in enumerate(y):
        v = row[np.isfinite(row)]
        k = v.size
        m = stats.trim_mean(v, 1 / (2 * np.sqrt(k - 4)))
        g4 = k * np.sum((v - m) ** 4) / np.sum((v - v.mean()) ** 2) ** 2
        c = k / (k - z)
        se = c * np.sqrt((g4 - (k - 3) / k) / (k - 1))
        expected = np.sqrt(c * v.var(ddof=1) * np.exp([-z * se, z * se]))
        assert (low[i], high[i]) == pytest.approx(tuple(expected), rel=1e-12)
    flat = np.full((1, 8), 15.6)  # a response the noise does not move: sd exactly 0
    assert sd_interval(flat, np.ones((1, 8), bool), np.array([8]), np.array([0.0])) == (
        np.array([0.0]),
        np.array([0.0]),
    )
    true_sd = np.sqrt((np.e - 1) * np.e)
    ours = chi2 = 0
    for seed in range(200):
        u = qmc.Sobol(1, scramble=True, rng=np.random.default_rng(seed)).random(64)[:, 0]
        sample = np.exp(stats.norm.ppf(u))
        s2 = np.array([sample.var(ddof=1)])
        lo, hi = sd_interval(sample[None, :], np.ones((1, 64), bool), np.array([64]), s2)
        ours += lo[0] <= true_sd <= hi[0]
        bounds = np.sqrt(63 * s2[0] / stats.chi2.ppf([0.975, 0.025], 63))
        chi2 += bounds[0] <= true_sd <= bounds[1]
    assert chi2 / 200 < 0.8  # the defect: a normal-theory interval on a skewed response
    assert ours / 200 >= 0.95


def test_a_response_inf_in_every_noise_case_is_reported_without_a_robust_point(
    tmp_path: Path,
) -> None:
    # An audit: a cycloidal cam concave at every design point (physics §3: max_contact_stress
    # is +inf where the cam is not convex) under an outer L9 crashed the report with a
    # KeyError (no max_contact_stress_mean: the analysis leaves such a response out), and
    # once that was mended named run 1 "most robust" with a mean of "—".
    text = (
        'name = "all_inf"\nscene = "cam"\nresponses = ["max_contact_stress"]\n'
        '[design]\ntype = "L4"\n[parameters]\nlaw = "cycloidal"\ncam_speed = 2400\n'
        "[factors.base_radius]\nlevels = [16.73, 18.16]\n"
        "[factors.rise_angle]\nlevels = [60.9, 64.1]\n"
        '[noise]\ntype = "L4"\n[noise.spring_rate]\ndistribution = "uniform"\n'
        "half_width = 10\nrelative = true\n"
    )
    result = run_plan(plan_text(text), tmp_path, progress=False)
    stress = result.dataset["max_contact_stress"].values
    assert np.isposinf(stress).all()  # concave everywhere: the case this test is about
    report = (result.folder / "report.md").read_text(encoding="utf-8")
    assert "| 1 | 16.73 | 60.9 | inf |" in report  # the run's mean over its noise cases
    assert "Most robust" not in report  # no value anywhere: nothing to call robust
    import xarray as xr

    assert int(xr.open_dataset(result.folder / "analysis.nc")["robust_run"][0]) == -1
