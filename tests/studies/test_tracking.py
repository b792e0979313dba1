"""Run records: checkpoints, resume after a failure, reuse of identical finished runs."""

from __future__ import annotations

import io
import json
import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from run_faults import fail_on_call

from studies.cli import main
from studies.define.plan import plan_text
from studies.pipeline import resume_run, run_plan
from studies.run.results import open_results
from studies.tracking import records, registry
from studies.tracking.liveness import liveness
from studies.tracking.store import RunStore

STUDY = """
name = "resumable"
scene = "cam"
responses = ["max_jerk", "min_radius_of_curvature"]
design = "full_factorial"
[factors.base_radius]
levels = [16.0, 18.0, 20.0, 22.0]
[factors.cam_speed]
levels = [1000.0, 1300.0, 1600.0]
"""


def test_failed_run_resumes_from_its_last_finished_chunk(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    plan = plan_text(STUDY)
    scene = plan.scene
    original = scene.stages["geometry"]
    # 1 warm-up call + chunks 0 and 1, then chunk 2 fails
    fail_on_call(monkeypatch, plan, 4, RuntimeError("simulated crash"))
    with pytest.raises(RuntimeError, match="simulated crash"):
        run_plan(plan, tmp_path, chunk_size=3, progress=False)
    (folder,) = (tmp_path / "resumable").iterdir()
    record = json.loads((folder / "run.json").read_text())
    assert record["status"] == "failed"
    assert "simulated crash" in record["error"]
    assert sorted(p.name for p in (folder / "chunks").glob("*.npz")) == ["000000.npz", "000001.npz"]

    monkeypatch.setitem(scene.stages, "geometry", original)
    resumed = resume_run(record["run_id"], tmp_path, progress=False)
    assert resumed.record.status == "finished"
    assert resumed.record.timings["points_computed"] == 6  # chunks 2 and 3 only
    assert not (folder / "chunks").exists()
    fresh = run_plan(plan_text(STUDY), tmp_path / "fresh", progress=False).dataset
    for name in ("max_jerk", "min_radius_of_curvature"):
        np.testing.assert_array_equal(resumed.dataset[name].values, fresh[name].values)


def test_identical_definition_on_clean_commit_is_reused(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.setattr("studies.run.provenance.git_state", lambda: ("c0ffee" * 6 + "cafe", False))
    study = tmp_path / "resumable.toml"
    study.write_text(STUDY)
    outputs = tmp_path / "outputs"
    args = ["run", str(study), "--outputs", str(outputs), "--no-progress"]
    assert main(args) == 0
    assert main(args) == 0
    assert "reusing run" in capsys.readouterr().out
    assert len(RunStore(outputs).list_runs()) == 1
    assert main([*args, "--force"]) == 0
    assert len(RunStore(outputs).list_runs()) == 2


def test_a_reused_run_answers_without_the_pipeline_or_a_figure_worker(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    # A reused run took 2.2 s to say so: the command imported the whole pipeline (xarray,
    # numba, scipy) and waited for a figure worker that had nothing to draw.
    study = tmp_path / "resumable.toml"
    study.write_text(STUDY)
    outputs = tmp_path / "outputs"
    args = ["run", str(study), "--outputs", str(outputs), "--no-progress"]
    warmed: list[int] = []
    monkeypatch.setattr("studies.report.figure_pool.warm", lambda: warmed.append(1))
    assert main(args) == 0
    assert warmed == [1]  # a computed run warms the workers
    assert main(args) == 0
    assert warmed == [1]
    heavy = ("studies.pipeline", "xarray", "numba", "scipy", "matplotlib")
    probe = (
        "import sys; from studies.cli import main; code = main(sys.argv[1:]); "
        f"print(code, [m for m in {heavy!r} if m in sys.modules])"
    )
    done = subprocess.run(
        [sys.executable, "-c", probe, *args], capture_output=True, text=True, check=True
    )
    assert "reusing run" in done.stdout
    assert done.stdout.splitlines()[-1] == "0 []"


class ClosedPipe:
    """Standard output after ``| head -1`` has exited: every write raises BrokenPipeError."""

    def write(self, text: str) -> int:
        raise BrokenPipeError

    def flush(self) -> None:
        raise BrokenPipeError


@pytest.mark.parametrize("reused", [False, True])
def test_tag_and_note_survive_an_output_pipe_closed_before_they_are_printed(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, reused: bool
) -> None:
    # An audit's case: `run STUDY --tag keep --note precious | head -1` exited 0 with no tag
    # and no note: the first print after the run raised BrokenPipeError, which ends the
    # command with 0, and the tag and note were only set after the printing.
    study = tmp_path / "resumable.toml"
    study.write_text(STUDY)
    outputs = tmp_path / "outputs"
    args = ["run", str(study), "--outputs", str(outputs), "--no-progress"]
    if reused:
        assert main(args) == 0
    monkeypatch.setattr("sys.stdout", ClosedPipe())
    monkeypatch.setattr("sys.stderr", io.StringIO())  # main closes it on a broken pipe
    assert main([*args, "--tag", "keep", "--note", "precious"]) == 0
    (row,) = RunStore(outputs).list_runs()
    tags, notes = RunStore(outputs).tags_and_notes()
    assert tags[row["run_id"]] == ["keep"]
    assert [n for n in notes[row["run_id"]] if "precious" in n]


def failed_run(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """A run that failed after its first two chunks (the folder)."""
    plan = plan_text(STUDY)
    fail_on_call(monkeypatch, plan, 4, RuntimeError("simulated crash"))
    with pytest.raises(RuntimeError):
        run_plan(plan, tmp_path, chunk_size=3, progress=False)
    (folder,) = (tmp_path / "resumable").iterdir()
    return folder


def test_resume_refuses_a_study_file_edited_after_the_run_started(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    folder = failed_run(tmp_path, monkeypatch)
    study = folder / "study.toml"
    study.write_text(study.read_text().replace("1600.0", "1700.0"))
    run_id = json.loads((folder / "run.json").read_text())["run_id"]
    with pytest.raises(ValueError, match="was edited after the run started") as error:
        resume_run(run_id, tmp_path, progress=False)
    assert "1600.0" in str(error.value)
    assert "1700.0" in str(error.value)
    assert not (folder / "results.nc").exists()
    assert main(["run", "--resume", run_id, "--outputs", str(tmp_path)]) == 2
    assert "edited after the run started" in capsys.readouterr().err


def test_a_checkpoint_left_mid_write_does_not_stop_a_resume(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    folder = failed_run(tmp_path, monkeypatch)
    (folder / "chunks" / "000002.tmp.npz").write_bytes(b"PK\x03\x04 cut short")
    run_id = json.loads((folder / "run.json").read_text())["run_id"]
    resumed = resume_run(run_id, tmp_path, progress=False)
    assert resumed.record.status == "finished"
    assert resumed.record.timings["points_computed"] == 6


def test_runs_of_one_definition_started_together_get_distinct_ids(tmp_path: Path) -> None:
    ids = [RunStore(tmp_path).run_folder("same", "20260101T000000000-abcdef")[0] for _ in range(3)]
    assert ids == [
        "20260101T000000000-abcdef",
        "20260101T000000000-abcdef-1",
        "20260101T000000000-abcdef-2",
    ]
    assert all((tmp_path / "same" / i).is_dir() for i in ids)


@pytest.mark.parametrize("size", ["0", "-5", "1.5", "many"])
def test_a_bad_chunk_size_is_refused_before_anything_is_written(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], size: str
) -> None:
    study = tmp_path / "resumable.toml"
    study.write_text(STUDY)
    with pytest.raises(SystemExit) as stop:
        main(["run", str(study), "--outputs", str(tmp_path / "out"), "--chunk-size", size])
    assert stop.value.code == 2
    assert "not a positive whole number of design points" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


def test_a_toml_error_names_the_file(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    study = tmp_path / "broken.toml"
    study.write_text('name = "broken"\nscene = cam\n')
    assert main(["check", str(study)]) == 2
    err = capsys.readouterr().err
    assert str(study) in err
    assert "<string>" not in err


def test_ctrl_c_ends_with_one_line_naming_the_run_and_the_resume_command(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    study = tmp_path / "resumable.toml"
    study.write_text(STUDY)
    plan = plan_text(STUDY)
    original = plan.scene.stages["geometry"]
    fail_on_call(monkeypatch, plan, 3, KeyboardInterrupt())
    monkeypatch.setattr("studies.define.plan.plan_study", lambda _: plan)
    outputs = tmp_path / "out"
    code = main(
        ["run", str(study), "--outputs", str(outputs), "--no-progress", "--chunk-size", "3"]
    )
    assert code == 130
    err = capsys.readouterr().err.strip()
    assert "Traceback" not in err
    assert len(err.splitlines()) == 1
    (row,) = RunStore(outputs).list_runs()
    assert f"python -m studies run --resume {row['run_id']} --outputs {outputs}" in err
    # recorded as what the console said (an audit: "failed", so --status interrupted missed it)
    assert row["status"] == "interrupted"
    assert main(["runs", "--status", "interrupted", "--outputs", str(outputs)]) == 0
    assert row["run_id"] in capsys.readouterr().out
    monkeypatch.setitem(plan.scene.stages, "geometry", original)
    assert main(["run", "--resume", row["run_id"], "--outputs", str(outputs), "--no-progress"]) == 0


def registered(outputs: Path) -> bool:
    try:
        return bool(RunStore(outputs).list_runs())
    except registry.RegistryUnusable:  # the other process held the registry past the wait
        return False


def test_after_kill_9_runs_shows_interrupted_and_the_resume_command(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    study = tmp_path / "resumable.toml"
    study.write_text(STUDY)
    outputs = tmp_path / "out"
    command = [sys.executable, "-m", "studies", "run", str(study), "--outputs", str(outputs),
               "--no-progress", "--chunk-size", "1"]  # fmt: skip
    process = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    deadline = time.monotonic() + 120
    while not registered(outputs) and time.monotonic() < deadline:
        time.sleep(0.002)  # the run is registered (and run.json written) before it computes
    process.kill()  # SIGKILL: no handler runs, run.json keeps "running"
    process.wait()
    (record,) = outputs.glob("resumable/*/run.json")
    assert json.loads(record.read_text())["status"] == "running"
    assert main(["runs", "--outputs", str(outputs)]) == 0
    out = capsys.readouterr().out
    (row,) = RunStore(outputs).list_runs()
    assert " interrupted " in out
    command = f"python -m studies run --resume {row['run_id']} --outputs {outputs}"
    assert command in out
    assert main(["show", row["run_id"], "--outputs", str(outputs)]) == 0
    shown = capsys.readouterr().out
    assert '"status": "interrupted"' in shown
    assert command in shown
    assert main(["run", "--resume", row["run_id"], "--outputs", str(outputs), "--no-progress"]) == 0
    assert RunStore(outputs).list_runs()[0]["status"] == "finished"


def test_a_live_run_is_not_resumed_and_a_deleted_folder_is_marked(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    result = run_plan(plan_text(STUDY), tmp_path, progress=False)
    record = json.loads((result.folder / "run.json").read_text())
    record["status"], record["pid"] = "running", os.getpid()  # this very process: alive
    (result.folder / "run.json").write_text(json.dumps(record))
    with pytest.raises(ValueError, match="is still running"):
        resume_run(record["run_id"], tmp_path, progress=False)
    shutil.rmtree(result.folder)
    assert main(["runs", "--outputs", str(tmp_path)]) == 0
    assert " missing " in capsys.readouterr().out
    assert main(["show", record["run_id"], "--outputs", str(tmp_path)]) == 2
    assert "its folder" in capsys.readouterr().err


def test_a_stale_heartbeat_from_another_host_reads_as_interrupted() -> None:
    old = "2020-01-01T00:00:00+00:00"
    record = {"status": "running", "host": {"node": "elsewhere"}, "pid": 1, "heartbeat": old}
    assert liveness(record) == "interrupted"
    record["heartbeat"] = records.now()
    assert liveness(record) == "running"


def test_the_outputs_root_is_the_same_from_any_folder(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    study = tmp_path / "resumable.toml"
    study.write_text(STUDY)
    root = tmp_path / "records"
    monkeypatch.setenv("ENGINE_STUDIES_OUTPUTS", str(root))
    (tmp_path / "here").mkdir()
    (tmp_path / "there").mkdir()
    monkeypatch.chdir(tmp_path / "here")
    assert main(["run", str(study), "--no-progress"]) == 0
    monkeypatch.chdir(tmp_path / "there")
    capsys.readouterr()
    assert main(["runs"]) == 0
    (row,) = RunStore(root).list_runs()
    assert row["run_id"] in capsys.readouterr().out
    assert Path(row["folder"]).is_absolute()
    assert not (tmp_path / "here" / "outputs").exists()
    # without the variable: this checkout's outputs/ folder, wherever the command runs
    monkeypatch.delenv("ENGINE_STUDIES_OUTPUTS")
    checkout = Path(__file__).resolve().parents[2] / "outputs"  # tests/studies/ -> the checkout
    assert records.default_outputs() == checkout


def test_a_relative_outputs_folder_is_recorded_absolute(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    study = tmp_path / "resumable.toml"
    study.write_text(STUDY)
    monkeypatch.chdir(tmp_path)
    assert main(["run", str(study), "--no-progress", "--outputs", "rel"]) == 0
    (row,) = RunStore(tmp_path / "rel").list_runs()
    assert Path(row["folder"]) == (tmp_path / "rel" / "resumable" / row["run_id"])


def lift_table(path: Path, peak_mm: float) -> Path:
    """A CSV lift table: a cosine bump of ``peak_mm`` over ±75 deg at 1 deg steps."""
    deg = np.arange(-75.0, 76.0)
    lift = peak_mm * (1 + np.cos(np.pi * deg / 75.0)) / 2
    np.savetxt(path, np.c_[deg, lift], delimiter=",", header="cam angle deg,lift mm")
    return path


def test_the_cache_key_covers_the_contents_of_a_lift_table(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.setattr("studies.run.provenance.git_state", lambda: ("c0ffee" * 6 + "cafe", False))
    table = lift_table(tmp_path / "lift.csv", peak_mm=10.0)
    study = tmp_path / "table.toml"
    study.write_text(
        f'name = "table"\nscene = "cam"\nresponses = ["max_lift"]\n[settings]\n'
        f'table_smoothing = 0.0\n[parameters]\nlaw = "table"\nlift_table = "{table}"\n'
        "rise_angle = 75.0\n[factors.base_radius]\nlevels = [15.0, 20.0]\n"
    )
    outputs = tmp_path / "outputs"
    args = ["run", str(study), "--outputs", str(outputs), "--no-progress"]
    assert main(args) == 0
    lift_table(table, peak_mm=5.0)  # the same file name, halved lifts
    assert main(args) == 0
    assert "reusing run" not in capsys.readouterr().out
    newest, first = RunStore(outputs).list_runs()
    assert newest["definition_sha256"] != first["definition_sha256"]
    for row, peak in ((first, 10.0), (newest, 5.0)):  # the spline interpolates the table peak
        result = open_results(Path(row["folder"]) / "results.nc")
        np.testing.assert_allclose(result["max_lift"].values, peak, rtol=1e-9)
    assert main(args) == 0  # unchanged since: reused
    assert "reusing run" in capsys.readouterr().out


def test_resume_from_any_folder_reads_a_relative_lift_table_and_refuses_it_changed(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    # An audit's case: lift_table = "lift.csv", resumed from another folder than the run's,
    # was refused as changed (a lift.csv there, or none, was read instead)
    started, elsewhere = tmp_path / "started", tmp_path / "elsewhere"
    started.mkdir()
    elsewhere.mkdir()
    table = lift_table(started / "lift.csv", peak_mm=10.0)
    lift_table(elsewhere / "lift.csv", peak_mm=5.0)  # the same name, another table
    text = (
        'name = "table"\nscene = "cam"\nresponses = ["max_lift", "min_radius_of_curvature"]\n'
        '[settings]\ntable_smoothing = 0.0\n[parameters]\nlaw = "table"\nlift_table = "lift.csv"\n'
        "rise_angle = 75.0\n"
        "[factors.base_radius]\n"
        "levels = [14.0, 15.0, 16.0, 17.0, 18.0, 19.0]\n"
    )
    monkeypatch.chdir(started)
    plan = plan_text(text)
    fail_on_call(monkeypatch, plan, 3, RuntimeError("simulated crash"))
    with pytest.raises(RuntimeError):
        run_plan(plan, tmp_path, chunk_size=2, progress=False)
    (folder,) = (tmp_path / "table").iterdir()
    monkeypatch.chdir(elsewhere)
    lift_table(table, peak_mm=5.0)
    run_id = json.loads((folder / "run.json").read_text())["run_id"]
    with pytest.raises(ValueError, match=f"a file that .* reads \\({table}\\) changed after"):
        resume_run(run_id, tmp_path, progress=False)
    table.unlink()  # a missing file is said to be gone, not changed
    with pytest.raises(ValueError, match=f"reads \\({table}\\) is gone: {table}\\. "):
        resume_run(run_id, tmp_path, progress=False)
    lift_table(table, peak_mm=10.0)  # the original contents: resumable again
    resumed = resume_run(run_id, tmp_path, progress=False)
    assert resumed.record.status == "finished"
    # the spline interpolates the table's peak: the run's table, not the one beside the resume
    np.testing.assert_allclose(resumed.dataset["max_lift"].values, 10.0, rtol=1e-9)


def test_resume_refuses_a_run_whose_code_changed_since_it_started(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    folder = failed_run(tmp_path, monkeypatch)
    record = json.loads((folder / "run.json").read_text())
    assert record["code"]["scene"]["scene"] == "cam"
    edited = record["code"]["engine"] | {"source_sha256": "0" * 64}  # e.g. a kernel edited since
    monkeypatch.setattr("studies.run.provenance.engine_code", lambda: edited)
    with pytest.raises(ValueError, match="the code changed since run"):
        resume_run(record["run_id"], tmp_path, progress=False)
    assert not (folder / "results.nc").exists()
    assert sorted(p.name for p in (folder / "chunks").glob("*.npz")) == ["000000.npz", "000001.npz"]
