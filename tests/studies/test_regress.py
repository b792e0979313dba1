"""regress and studies.compare.testing.assert_results_close: a changed kernel fails, a rerun passes."""

from __future__ import annotations

import math
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

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
