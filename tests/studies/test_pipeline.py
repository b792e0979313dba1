"""End to end: study → plan → stages → Dataset → netCDF → analysis → run record."""

from __future__ import annotations

import json
import sqlite3
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from studies.define.plan import plan_text
from studies.pipeline import run_plan, run_study
from studies.run.results import as_grid
from study_text import recorded_stages

SMALL = """
name = "small"
scene = "cam"
responses = {responses}
curves = {curves}
[design]
type = "{design}"
[factors.base_radius]
levels = [18.0, 20.5]
units = "mm"
[factors.cam_speed]
levels = [1000.0, 1300.0, 1600.0]
"""


def small(responses=("max_jerk",), curves=(), design="full_factorial") -> str:
    return SMALL.format(
        responses=json.dumps(list(responses)), curves=json.dumps(list(curves)), design=design
    )


@pytest.fixture(scope="module")
def isac(tmp_path_factory: pytest.TempPathFactory):
    outputs = tmp_path_factory.mktemp("outputs")
    return outputs, run_study("isac_l9", outputs=outputs, progress=False)


def test_isac_results_layout(isac) -> None:
    _, result = isac
    with xr.open_dataset(result.folder / "results.nc") as ds:
        assert ds.sizes["run"] == 9
        for f, units in [
            ("seg2_width", "degree"),
            ("seg6_amplitude", "mm/rad^2"),
            ("seg2_amplitude", "mm/rad^2"),
        ]:
            assert ds[f].attrs["units"] == units
            assert sorted(set(ds[f"{f}_level"].values)) == [0, 1, 2]
        assert "D_level" in ds.coords
        assert "D" not in ds.coords
        expected_units = {
            "max_contact_stress": "MPa",
            "max_lubrication_coefficient_nose": "1",
            "max_jerk": "mm/rad^3",
        }
        assert set(ds.data_vars) == set(expected_units)
        for name, units in expected_units.items():
            assert ds[name].attrs["units"] == units
            assert ds[name].attrs["long_name"]
            assert np.isfinite(ds[name]).all()
        assert ds.attrs["design"].startswith("L9")
        assert "seg2_width" in ds.attrs["study_toml"]
        assert json.loads(ds.attrs["timings"])["run_s"] >= 0
        assert ds.attrs["git_dirty"] in (0, 1)


def test_isac_run_record(isac) -> None:
    outputs, result = isac
    names = {p.name for p in result.folder.iterdir()}
    assert {"results.nc", "study.toml", "run.json", "analysis.txt"} <= names
    assert {f"main_effects_{r}.png" for r in ["max_contact_stress", "max_jerk"]} <= names
    record = json.loads((result.folder / "run.json").read_text())
    assert record["status"] == "finished"
    assert {"git_commit", "git_dirty", "versions", "host", "started", "finished", "timings"} <= set(
        record
    )
    assert set(record["timings"]) >= {
        "compile_s",
        "run_s",
        "results_s",
        "analysis_s",
        "figures_s",
        "report_s",
    }
    text = (result.folder / "analysis.txt").read_text()
    assert "ANOVA" in text or "anova" in text.lower()
    with sqlite3.connect(outputs / "registry.sqlite") as con:
        rows = con.execute("SELECT study, status FROM runs").fetchall()
    assert ("isac_l9", "finished") in rows


def test_kinematic_response_runs_only_the_kinematics_stage() -> None:
    plan = plan_text(small(responses=["max_jerk", "fullness"]))
    assert plan.stages == ("kinematics",)
    from studies.run.runner import evaluate

    with recorded_stages(plan.scene) as calls:
        evaluate(plan, progress=False)
    assert calls
    assert set(calls) == {"kinematics"}


def test_stress_response_needs_all_three_stages() -> None:
    plan = plan_text(small(responses=["max_contact_stress"]))
    assert plan.stages == ("kinematics", "geometry", "loads")


def test_curves_only_when_asked(tmp_path: Path) -> None:
    without = run_plan(plan_text(small()), tmp_path, progress=False).dataset
    assert "cam_angle" not in without.dims
    with_curves = run_plan(
        plan_text(small(curves=["lift", "radius_of_curvature"])), tmp_path, progress=False
    ).dataset
    assert with_curves["lift"].dims == ("run", "cam_angle")
    assert with_curves["lift"].attrs["units"] == "mm"
    assert with_curves["cam_angle"].attrs["units"] == "degree"


def test_full_factorial_as_grid(tmp_path: Path) -> None:
    ds = run_plan(plan_text(small()), tmp_path, progress=False).dataset
    grid = as_grid(ds)
    assert grid["max_jerk"].dims == ("base_radius", "cam_speed")
    assert grid["max_jerk"].shape == (2, 3)
    # every cell is the run at those factor values (brute-force lookup over the runs)
    for i, radius in enumerate(grid["base_radius"].values):
        for j, speed in enumerate(grid["cam_speed"].values):
            run = np.flatnonzero((ds["base_radius"] == radius) & (ds["cam_speed"] == speed))
            assert grid["max_jerk"].values[i, j] == ds["max_jerk"].values[run[0]]
    speed = float(grid["cam_speed"].values[1])
    assert grid.sel(cam_speed=speed)["max_jerk"].dims == ("base_radius",)
    # a shuffled run order gives the same grid
    shuffled = ds.isel(run=np.random.default_rng(1).permutation(ds.sizes["run"]))
    np.testing.assert_array_equal(as_grid(shuffled)["max_jerk"].values, grid["max_jerk"].values)


def test_runs_are_listed_by_cli(isac, capsys: pytest.CaptureFixture[str]) -> None:
    from studies.cli import main

    outputs, result = isac
    assert main(["runs", "--outputs", str(outputs)]) == 0
    assert result.record.run_id in capsys.readouterr().out


def test_analyze_cli_writes_tables_and_plots(isac, capsys: pytest.CaptureFixture[str]) -> None:
    from studies.cli import main

    _, result = isac
    recorded = (result.folder / "analysis.txt").read_text(encoding="utf-8")
    assert main(["analyze", str(result.folder / "results.nc"), "--response", "max_jerk"]) == 0
    out = capsys.readouterr().out
    assert "max_jerk" in out
    assert "max_contact_stress" not in out.split("wrote")[0]
    (folder,) = result.folder.glob("analysis-*")  # a new folder: the run's own is kept
    assert (folder / "main_effects_max_jerk.png").stat().st_size > 1000
    assert (result.folder / "analysis.txt").read_text(encoding="utf-8") == recorded
    assert main(["analyze", str(result.folder / "results.nc"), "--to", str(result.folder)]) == 2
    assert "would be overwritten" in capsys.readouterr().err


def test_pooling_from_the_study_and_from_the_cli(tmp_path: Path, capsys) -> None:
    # 2 × 3 full factorial: error dof 6 − 1 − 1 − 2 = 2; pooling cam_speed (dof 2) gives 4,
    # pooling base_radius (dof 1) gives 3 (counting from the design, not from the code).
    from studies.analysis.analyze import anova
    from studies.cli import main

    text = small(responses=("max_contact_stress",)).replace(
        'type = "full_factorial"', 'type = "full_factorial"\npool = ["cam_speed"]'
    )
    result = run_plan(plan_text(text), outputs=tmp_path, progress=False)
    path = result.folder / "results.nc"
    with xr.open_dataset(path) as ds:
        assert json.loads(ds.attrs["pool"]) == ["cam_speed"]
        table = anova(ds.load(), "max_contact_stress")
    assert table.attrs["pooled"] == ["cam_speed"]
    assert table.loc["error", "dof"] == 4
    assert "cam_speed (pooled)" in (result.folder / "analysis.txt").read_text(encoding="utf-8")
    assert "Pooled into error: cam_speed." in (result.folder / "report.md").read_text("utf-8")

    assert main(["analyze", str(path), "--pool", "base_radius", "--to", str(tmp_path / "a")]) == 0
    analysis = (tmp_path / "a" / "analysis.txt").read_text(encoding="utf-8")
    assert "base_radius (pooled)" in analysis
    assert "cam_speed (pooled)" not in analysis
    assert main(["analyze", str(path), "--no-pool", "--to", str(tmp_path / "b")]) == 0
    assert "(pooled)" not in (tmp_path / "b" / "analysis.txt").read_text(encoding="utf-8")
    capsys.readouterr()
    assert main(["analyze", str(path), "--pool", "cam_sped"]) == 2
    assert "cannot pool ['cam_sped']" in capsys.readouterr().err


def test_a_run_whose_figure_fails_finishes_with_its_numbers_and_says_which(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """Before, any failure while drawing marked the run failed and removed results.nc and
    analysis.nc (the chunks were kept for a resume). A figure is not a result: the run
    finishes, run.json and the command line say which figure is missing and why."""
    from studies.cli import main
    from studies.report import plots

    def broken(*args: object, **kwargs: object) -> list[Path]:
        raise RuntimeError("no display")

    monkeypatch.setattr(plots, "save_main_effects", broken)
    study = tmp_path / "small.toml"
    study.write_text(
        small(responses=("max_contact_stress",)), encoding="utf-8"
    )  # max_jerk [mm/rad³] does not vary here: no main effects drawn
    outputs = tmp_path / "out"
    assert main(["run", str(study), "--outputs", str(outputs), "--no-progress"]) == 0
    (record_path,) = outputs.glob("small/*/run.json")
    record = json.loads(record_path.read_text())
    assert record["status"] == "finished"
    assert record["warnings"] == ["broken drew nothing: RuntimeError: no display"]
    assert {"results.nc", "analysis.nc", "report.md"} <= {
        p.name for p in record_path.parent.iterdir()
    }
    err = capsys.readouterr().err
    assert "warning: small: broken drew nothing: RuntimeError: no display" in err
