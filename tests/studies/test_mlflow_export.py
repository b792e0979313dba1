"""MLflow export as the README writes it: ``run isac_l9 --mlflow sqlite:///mlflow.db`` with the
MLflow the ``[mlflow]`` extra installs and no environment override (MLflow 3 refuses its file
store unless ``MLFLOW_ALLOW_FILE_STORE`` is set; SQLite is the local store it recommends).
Everything logged is read back with ``mlflow.search_runs`` and compared with the run folder."""

from __future__ import annotations

import os
from pathlib import Path

import pytest
import xarray as xr

from studies.cli import main
from studies.tracking.store import RunStore

mlflow = pytest.importorskip("mlflow")
URI = "sqlite:///mlflow.db"  # as the README writes it: a file in the current folder

TINY = """
name = "tiny_cam"
scene = "cam"
responses = ["max_jerk"]
[factors.base_radius]
levels = [16.0, 18.0]
"""


@pytest.fixture(scope="module")
def logged(tmp_path_factory: pytest.TempPathFactory):
    """isac_l9 run with --mlflow, --tag and --note in a fresh folder, then run again."""
    assert "MLFLOW_ALLOW_FILE_STORE" not in os.environ
    here = tmp_path_factory.mktemp("mlflow")
    outputs = here / "out"
    with pytest.MonkeyPatch.context() as patch:
        patch.chdir(here)
        argv = ["run", "isac_l9", "--outputs", str(outputs), "--no-progress", "--mlflow", URI]
        first = main([*argv, "--tag", "review", "--note", "first look"])
        again = main(argv)  # an identical definition: reused, and not logged twice
        mlflow.set_tracking_uri(f"sqlite:///{(here / 'mlflow.db').resolve()}")
        yield here, outputs, first, again


def test_run_with_mlflow_logs_params_metrics_tags_and_artifacts(logged) -> None:
    here, outputs, first, again = logged
    assert (first, again) == (0, 0)
    (row,) = mlflow.search_runs(experiment_names=["isac_l9"]).to_dict("records")  # logged once
    (run,) = RunStore(outputs).list_runs()
    folder = Path(run["folder"])
    assert row["tags.engine_studies.run_id"] == run["run_id"]
    assert row["tags.tag.review"] == "1"
    assert row["tags.mlflow.note.content"].endswith("first look")
    # parameters in SI whatever the study wrote: base_radius = 20.5 mm is 0.0205 m
    assert row["params.base_radius"] == "0.0205 m"
    assert row["params.factor.seg2_width"].endswith(" rad")
    with xr.open_dataset(folder / "results.nc") as ds:
        assert ds["max_jerk"].attrs["units"] == "mm/rad^3"
        # metrics in SI: mm/rad^3 → m/rad^3 divides by 1000
        assert row["metrics.max_jerk.max"] == pytest.approx(float(ds["max_jerk"].max()) / 1000)
        assert row["metrics.max_contact_stress.min"] == pytest.approx(
            float(ds["max_contact_stress"].min()) * 1e6  # MPa → Pa
        )
    assert row["tags.units.max_jerk"] == "m/rad^3"
    artifacts = {Path(a.path).name for a in mlflow.artifacts.list_artifacts(run_id=row["run_id"])}
    figures = {p.name for p in folder.glob("*.png")}
    assert figures
    assert {"results.nc", "analysis.nc", "report.html", "run.json", *figures} <= artifacts
    assert (here / "mlartifacts").is_dir()  # beside the database, not wherever MLflow likes


def test_studies_mlflow_logs_an_existing_run_once(
    logged, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    here, outputs, _, _ = logged
    study = tmp_path / "tiny_cam.toml"
    study.write_text(TINY, encoding="utf-8")
    assert main(["run", str(study), "--outputs", str(outputs), "--no-progress"]) == 0
    (tiny,) = RunStore(outputs).list_runs("tiny_cam")
    uri = f"sqlite:///{here / 'mlflow.db'}"
    argv = ["mlflow", tiny["run_id"], "--to", uri, "--outputs", str(outputs)]
    assert main(argv) == 0
    assert main(argv) == 0
    out = capsys.readouterr().out
    assert "logged as MLflow run" in out
    assert "already logged as MLflow run" in out
    (row,) = mlflow.search_runs(experiment_names=["tiny_cam"]).to_dict("records")
    assert row["tags.engine_studies.run_id"] == tiny["run_id"]


def test_a_store_mlflow_refuses_is_one_line_before_anything_runs(
    logged, capsys: pytest.CaptureFixture[str]
) -> None:
    _, outputs, _, _ = logged
    before = len(RunStore(outputs).list_runs())
    argv = ["run", "isac_l9", "--outputs", str(outputs), "--force", "--mlflow", "file:./mlruns"]
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1
    assert "MLflow cannot use this store" in err
    assert "sqlite:///mlflow.db" in err
    assert len(RunStore(outputs).list_runs()) == before  # no run recorded for a failed export


def test_an_export_that_fails_part_way_leaves_no_mlflow_run_behind(
    logged, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from studies.tracking.mlflow_export import log_run

    here, outputs, _, _ = logged
    study = tmp_path / "tiny_fail.toml"
    study.write_text(TINY.replace("tiny_cam", "tiny_fail"), encoding="utf-8")
    assert main(["run", str(study), "--outputs", str(outputs), "--no-progress"]) == 0
    (run,) = RunStore(outputs).list_runs("tiny_fail")
    uri = f"sqlite:///{here / 'mlflow.db'}"

    def broken(*args, **kwargs):
        raise OSError("disk full while copying artifacts")

    with monkeypatch.context() as patch:
        patch.setattr(mlflow, "log_artifacts", broken)
        with pytest.raises(ValueError, match="disk full while copying artifacts"):
            log_run(uri, Path(run["folder"]), [], [])
    assert mlflow.search_runs(experiment_names=["tiny_fail"]).empty  # the partial run is gone
    mlflow_id, new = log_run(uri, Path(run["folder"]), [], [])
    assert new
    (row,) = mlflow.search_runs(experiment_names=["tiny_fail"]).to_dict("records")
    assert row["run_id"] == mlflow_id
