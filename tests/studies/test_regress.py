"""regress and studies.compare.testing.assert_results_close: a changed kernel fails, a rerun passes."""

from __future__ import annotations

import math
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from studies.cli import main
from studies.compare.testing import assert_results_close
from studies.pipeline import run_study
from studies.tracking.store import RunStore

ROOT = Path(__file__).resolve().parents[2]
HERTZ = "return math.sqrt(force * modulus / (math.pi * width * radius))"
CHANGED_PI = 3.0  # π in the Hertz formula of the scratch copy: stress × sqrt(π/3)


@pytest.fixture(scope="module")
def runs(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, str, str, str]:
    """isac_l9 run twice on this code, then once from a scratch copy with a kernel constant
    changed: (outputs, baseline id, rerun id, changed id)."""
    outputs = tmp_path_factory.mktemp("out")
    base = run_study("isac_l9", outputs=outputs, progress=False).record.run_id
    rerun = run_study("isac_l9", outputs=outputs, progress=False).record.run_id
    scratch = tmp_path_factory.mktemp("scratch")
    for package in ("studies", "engine_kernels"):
        shutil.copytree(
            ROOT / package, scratch / package, ignore=shutil.ignore_patterns("__pycache__")
        )
    contact = scratch / "engine_kernels" / "cam" / "contact.py"
    text = contact.read_text(encoding="utf-8")
    assert text.count(HERTZ) == 1
    contact.write_text(text.replace(HERTZ, HERTZ.replace("math.pi", repr(CHANGED_PI))), "utf-8")
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    done = subprocess.run(
        [
            sys.executable,
            "-m",
            "studies",
            "run",
            "isac_l9",
            "--outputs",
            str(outputs),
            "--no-progress",
        ],
        cwd=scratch,
        env=env,
        capture_output=True,
        text=True,
        check=False,
        timeout=600,
    )
    assert done.returncode == 0, done.stderr
    (changed,) = {r["run_id"] for r in RunStore(outputs).list_runs()} - {base, rerun}
    return outputs, base, rerun, changed


@pytest.mark.slow
def test_a_rerun_on_the_same_commit_passes(runs, capsys: pytest.CaptureFixture[str]) -> None:
    outputs, base, rerun, _ = runs
    assert main(["regress", base, rerun, "--outputs", str(outputs)]) == 0
    assert "all within tolerance" in capsys.readouterr().out


@pytest.mark.slow
def test_a_changed_kernel_constant_fails_with_a_table(
    runs, capsys: pytest.CaptureFixture[str]
) -> None:
    outputs, base, _, changed = runs
    assert main(["regress", base, changed, "--outputs", str(outputs)]) == 1
    out = capsys.readouterr().out
    assert "FAILED: max_contact_stress moved beyond tolerance" in out
    line = next(x for x in out.splitlines() if x.startswith("✗ max_contact_stress [MPa]"))
    assert line.split()[-3] == "9/9"  # every design point moved
    # σ = sqrt(F E / (π w ρ)): with π → 3 every stress grows by sqrt(π/3)
    expected = math.sqrt(math.pi / CHANGED_PI) - 1  # printed to 3 digits
    assert float(line.split()[-1]) == pytest.approx(expected, rel=5e-3)
    for unchanged in ("max_jerk [mm/rad^3]", "max_lubrication_coefficient_nose"):
        assert re.search(rf"^  {re.escape(unchanged)} .* 0/9 ", out, re.MULTILINE)


@pytest.mark.slow
def test_a_tolerance_file_can_allow_the_change(
    runs, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    outputs, base, _, changed = runs
    loose = tmp_path / "tolerances.toml"
    loose.write_text("[max_contact_stress]  # MPa\nrtol = 0.03\n", encoding="utf-8")
    assert (
        main(["regress", base, changed, "--tolerances", str(loose), "--outputs", str(outputs)]) == 0
    )
    wrong = tmp_path / "wrong.toml"
    wrong.write_text("[max_stress]\nrtol = 0.03\n", encoding="utf-8")
    capsys.readouterr()
    assert (
        main(["regress", base, changed, "--tolerances", str(wrong), "--outputs", str(outputs)]) == 2
    )
    assert "max_stress" in capsys.readouterr().err


@pytest.mark.slow
def test_assert_results_close_in_a_users_suite(runs) -> None:
    outputs, base, rerun, changed = runs
    folder = {r["run_id"]: Path(r["folder"]) for r in RunStore(outputs).list_runs()}
    assert_results_close(folder[rerun] / "results.nc", folder[base] / "results.nc")
    with pytest.raises(AssertionError, match=r"(?s)✗ max_contact_stress \[MPa\].*FAILED"):
        assert_results_close(folder[changed] / "results.nc", folder[base] / "results.nc")
    assert_results_close(
        folder[changed] / "results.nc", folder[base] / "results.nc", {"max_contact_stress": 0.03}
    )


def test_assert_results_close_matches_points_by_factor_values(tmp_path: Path) -> None:
    baseline = xr.Dataset(
        {"y": ("run", [1.0, 2.0, 3.0], {"units": "mm"})},
        coords={"a": ("run", [10.0, 20.0, 30.0])},
        attrs={"factors": '["a"]', "responses": '["y"]'},
    )
    shuffled = baseline.isel(run=[2, 0, 1])
    assert_results_close(shuffled, baseline, rtol=0)
    moved = shuffled.copy(deep=True)
    moved["y"].values[0] *= 1 + 1e-6  # the point a = 30
    with pytest.raises(AssertionError, match=r"a=30: 3 → 3\.000003"):
        assert_results_close(moved, baseline)
    assert_results_close(moved, baseline, {"y": {"atol": 1e-5}})
    other_units = shuffled.copy()
    other_units["y"].attrs["units"] = "m"
    with pytest.raises(AssertionError, match="units 'm'"):
        assert_results_close(other_units, baseline)


def test_equal_infinities_and_nans_are_unchanged(tmp_path: Path) -> None:
    # A concave cam has an infinite contact stress, a point that never separates a NaN jump
    # start: the same inf or NaN in both runs has not moved (was: inf − inf = NaN, a failure).
    baseline = xr.Dataset(
        {"y": ("run", [1.0, math.inf, math.nan], {"units": "MPa"})},
        coords={"a": ("run", [10.0, 20.0, 30.0])},
        attrs={"factors": '["a"]', "responses": '["y"]'},
    )
    assert_results_close(baseline.copy(deep=True), baseline, rtol=0)
    flipped = baseline.copy(deep=True)
    flipped["y"].values[1] = -math.inf
    with pytest.raises(AssertionError, match="a=20"):
        assert_results_close(flipped, baseline)


@pytest.mark.slow
def test_regress_takes_a_results_file_and_compare_names_the_changed_engine_source(
    runs, capsys: pytest.CaptureFixture[str]
) -> None:
    outputs, base, rerun, changed = runs
    reviewed = next(outputs.glob(f"isac_l9/{base}/results.nc"))  # a baseline file, by path
    assert main(["regress", str(reviewed), rerun, "--outputs", str(outputs)]) == 0
    assert f"run {rerun} against baseline {reviewed}" in capsys.readouterr().out
    assert main(["regress", str(reviewed), changed, "--outputs", str(outputs)]) == 1
    capsys.readouterr()
    # the scratch copy's kernel edit is uncommitted code outside any repository: its source
    # hash, not a commit, tells the runs apart
    assert main(["compare", base, changed, "--outputs", str(outputs), "--rtol", "1e-3"]) == 0
    out = capsys.readouterr().out
    assert re.search(r"code engine\s+engine-studies \S+ → engine-studies \S+, source changed", out)
    assert "code scene" not in out  # a built-in scene's code is the engine's: said once
    assert "moved: max_contact_stress" in out
    (line,) = [x for x in out.splitlines() if x.strip().startswith("max_contact_stress [MPa]")]
    assert "9/9" in line  # one line for the moved response, every point beyond 1e-3


NOISE_STUDY = """
name = "cam_noise"
scene = "cam"
responses = ["max_contact_stress"]
design = "full_factorial"
[factors.base_radius]
levels = [30.0, 35.0, 40.0]
units = "mm"
[noise]
type = "L4"
[noise.spring_rate]
distribution = "uniform"
half_width = {half_width}
relative = true
"""


def noise_results(stress: np.ndarray, order: list[int], half_width: int = 5) -> xr.Dataset:
    """Results laid out as a [noise] study writes them (run × noise), design points in
    ``order``: ``stress[i, k]`` is the value at base radius 30 + 5 i mm, noise case k."""
    radius = np.array([30.0, 35.0, 40.0])[order]
    return xr.Dataset(
        {"max_contact_stress": (("run", "noise"), stress[order], {"units": "MPa"})},
        coords={
            "run": np.arange(3),
            "noise": np.arange(4),
            "spring_rate_noise": (("run", "noise"), np.tile([0.95, 0.95, 1.05, 1.05], (3, 1))),
            "base_radius": ("run", radius, {"units": "mm"}),
            "base_radius_level": ("run", np.array(order, dtype=np.int32)),
        },
        attrs={
            "factors": '["base_radius"]',
            "responses": '["max_contact_stress"]',
            "noise_factors": '["spring_rate"]',
            "noise_design": "L4 over 'spring_rate'",
            "study_toml": NOISE_STUDY.format(half_width=half_width),
            "run_id": f"noise-{half_width}-{''.join(map(str, order))}",
        },
    )


def test_regress_under_noise_checks_every_noise_case_of_every_design_point(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # was: "the run has none of the baseline's responses ()", exit 2 (only responses on
    # ("run",) were compared)
    rng = np.random.default_rng(7)
    before = rng.uniform(200.0, 300.0, (3, 4))
    after = before * (1 + rng.uniform(-0.01, 0.01, (3, 4)))
    after[2, 3] = before[2, 3] * 1.03  # the largest change: base radius 40 mm, noise case 3
    rel = np.abs(after - before) / np.abs(before)
    baseline, run = tmp_path / "baseline.nc", tmp_path / "run.nc"
    noise_results(before, [0, 1, 2]).to_netcdf(baseline)
    noise_results(after, [2, 0, 1]).to_netcdf(run)  # the same points, in another order

    def regress(rtol: float) -> int:
        argv = ["regress", str(baseline), str(run), "--rtol", repr(float(rtol))]
        return main([*argv, "--outputs", str(tmp_path / "out")])

    assert regress(rel.max() * (1 - 1e-6)) == 1
    out = capsys.readouterr().out
    line = next(x for x in out.splitlines() if x.startswith("✗ max_contact_stress [MPa]"))
    beyond, max_abs, max_rel = line.split()[-3:]
    assert beyond == "1/12"  # 3 design points × 4 noise cases
    assert float(max_abs) == pytest.approx(np.abs(after - before).max(), rel=5e-3)
    assert float(max_rel) == pytest.approx(rel.max(), rel=5e-3)
    assert "base_radius=0.04, noise=3:" in out
    assert regress(rel.max() * (1 + 1e-6)) == 0
    assert "all within tolerance" in capsys.readouterr().out


def test_regress_refuses_unlike_noise_cases_in_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    stress = np.full((3, 4), 250.0)
    files = {"5": tmp_path / "5.nc", "8": tmp_path / "8.nc", "none": tmp_path / "none.nc"}
    noise_results(stress, [0, 1, 2], 5).to_netcdf(files["5"])
    noise_results(stress, [0, 1, 2], 8).to_netcdf(files["8"])
    plain = noise_results(stress, [0, 1, 2]).isel(noise=0, drop=True)
    plain = plain.drop_vars("spring_rate_noise").assign_attrs(noise_design="", run_id="plain")
    plain.to_netcdf(files["none"])
    for other, words in (
        ("8", "spring_rate.half_width = 5 in noise-5-012, 8 in noise-8-012"),
        ("none", "L4 over 'spring_rate' in noise-5-012; no [noise] in plain"),
    ):
        argv = ["regress", str(files["5"]), str(files[other]), "--outputs", str(tmp_path)]
        assert main(argv) == 2
        (err,) = capsys.readouterr().err.strip().splitlines()
        assert f"the runs' [noise] tables differ ({words}): their noise cases" in err
