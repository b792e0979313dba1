"""Disk and permission failures (issue 18, item 5): a read-only outputs folder, a disk that fills
while chunks are written, an unreadable or damaged checkpoint. Each ends with one line on
stderr (what failed, on which file, how to go on), exit code 4 and no traceback; once the cause
is gone the run resumes to results identical to an uninterrupted run."""

from __future__ import annotations

import errno
import json
import os
from pathlib import Path

import numpy as np
import pytest
from run_faults import failing_on_call

from studies import pipeline
from studies.cli import EXIT_OUTPUT_ERROR, main
from studies.run.results import open_results
from studies.tracking.store import RunStore

STUDY = """
name = "disk"
scene = "cam"
responses = ["max_jerk", "min_radius_of_curvature"]
[factors.base_radius]
levels = [16.0, 18.0, 20.0, 22.0]
[factors.cam_speed]
levels = [1000.0, 1300.0, 1600.0]
"""
RESPONSES = ("max_jerk", "min_radius_of_curvature")


def enforce_modes(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Make permission bits bind: where they already do (a normal user) nothing changes; where
    they do not (root, CAP_DAC_OVERRIDE) creating in a folder without its write bit and
    opening a file without its read bit raise EACCES, as the kernel would for a user."""
    probe = tmp_path / "probe"
    probe.mkdir(mode=0o500)
    probe.chmod(0o500)
    try:
        (probe / "written").touch()
    except PermissionError:
        return
    finally:
        probe.chmod(0o700)
    mkdir, open_ = Path.mkdir, Path.open

    def denied(path: Path) -> PermissionError:
        return PermissionError(errno.EACCES, os.strerror(errno.EACCES), str(path))

    def checked_mkdir(self: Path, *args: object, **kwargs: object) -> None:
        if self.parent.exists() and not self.parent.stat().st_mode & 0o200 and not self.exists():
            raise denied(self)
        mkdir(self, *args, **kwargs)  # type: ignore[arg-type]

    def checked_open(self: Path, mode: str = "r", *args: object, **kwargs: object):
        if "r" in mode and self.exists() and not self.stat().st_mode & 0o400:
            raise denied(self)
        return open_(self, mode, *args, **kwargs)  # type: ignore[call-overload]

    monkeypatch.setattr(Path, "mkdir", checked_mkdir)
    monkeypatch.setattr(Path, "open", checked_open)


@pytest.fixture
def study(tmp_path: Path) -> Path:
    path = tmp_path / "disk.toml"
    path.write_text(STUDY)
    return path


def run(study: Path, outputs: Path, *extra: str) -> int:
    return main(["run", str(study), "--outputs", str(outputs), "--no-progress", *extra])


def resume(run_id: str, outputs: Path) -> int:
    return main(["run", "--resume", run_id, "--outputs", str(outputs), "--no-progress"])


def one_line_error(capsys: pytest.CaptureFixture[str]) -> str:
    err = capsys.readouterr().err.strip()
    assert "Traceback" not in err
    assert len(err.splitlines()) == 1
    return err


def assert_identical_to_an_uninterrupted_run(outputs: Path, study: Path, tmp_path: Path) -> None:
    (row,) = RunStore(outputs).list_runs()
    assert row["status"] == "finished"
    assert run(study, tmp_path / "fresh", "--force") == 0
    (fresh,) = RunStore(tmp_path / "fresh").list_runs()
    resumed = open_results(Path(row["folder"]) / "results.nc")
    expected = open_results(Path(fresh["folder"]) / "results.nc")
    for name in RESPONSES:
        np.testing.assert_array_equal(resumed[name].values, expected[name].values)


def test_a_read_only_outputs_folder_is_one_line_and_a_rerun_works(
    tmp_path: Path, study: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    enforce_modes(tmp_path, monkeypatch)
    outputs = tmp_path / "outputs"
    outputs.mkdir(mode=0o555)
    outputs.chmod(0o555)
    assert run(study, outputs) == EXIT_OUTPUT_ERROR
    err = one_line_error(capsys)
    assert err == f"error: Permission denied: {outputs / 'disk'}; nothing was recorded"
    assert list(outputs.iterdir()) == []
    outputs.chmod(0o755)
    assert run(study, outputs) == 0


@pytest.mark.parametrize("code", [errno.ENOSPC, errno.EROFS])
def test_a_disk_that_fills_during_chunk_writes_leaves_a_resumable_run(
    tmp_path: Path,
    study: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
    code: int,
) -> None:
    outputs = tmp_path / "outputs"
    save = pipeline._save_chunk
    full = OSError(code, os.strerror(code), "chunks/000002.npz")
    monkeypatch.setattr(pipeline, "_save_chunk", failing_on_call(save, 3, full))
    assert run(study, outputs, "--chunk-size", "3") == EXIT_OUTPUT_ERROR
    err = one_line_error(capsys)
    (row,) = RunStore(outputs).list_runs()
    assert err.startswith(f"error: {os.strerror(code)}: chunks/000002.npz; run {row['run_id']}")
    assert err.endswith(RunStore(outputs).resume_command(row["run_id"]))
    folder = Path(row["folder"])
    assert row["status"] == "failed"
    assert sorted(p.name for p in (folder / "chunks").glob("*.npz")) == [
        "000000.npz",
        "000001.npz",
    ]
    assert not (folder / "results.nc").exists()
    monkeypatch.setattr(pipeline, "_save_chunk", save)  # space freed
    assert resume(row["run_id"], outputs) == 0
    record = json.loads((folder / "run.json").read_text())
    assert record["timings"]["points_computed"] == 6  # chunks 2 and 3 only
    assert_identical_to_an_uninterrupted_run(outputs, study, tmp_path)


def failed_run(outputs: Path, study: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """A run that stopped after checkpointing chunks 0 and 1 of 4 (its folder)."""
    save = pipeline._save_chunk
    full = OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
    with monkeypatch.context() as patch:
        patch.setattr(pipeline, "_save_chunk", failing_on_call(save, 3, full))
        assert run(study, outputs, "--chunk-size", "3") == EXIT_OUTPUT_ERROR
    (row,) = RunStore(outputs).list_runs()
    return Path(row["folder"])


def test_a_damaged_checkpoint_is_named_and_the_run_resumes_once_it_is_deleted(
    tmp_path: Path,
    study: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    outputs = tmp_path / "outputs"
    folder = failed_run(outputs, study, monkeypatch)
    capsys.readouterr()
    damaged = folder / "chunks" / "000001.npz"
    damaged.write_bytes(damaged.read_bytes()[:100])  # cut short, as by a failing disk
    run_id = folder.name
    assert resume(run_id, outputs) == EXIT_OUTPUT_ERROR
    err = one_line_error(capsys)
    assert err.startswith(f"error: checkpoint {damaged} is damaged (BadZipFile: ")
    assert "delete it and resume: its design points are computed again" in err
    assert not (folder / "results.nc").exists()
    damaged.unlink()
    assert resume(run_id, outputs) == 0
    record = json.loads((folder / "run.json").read_text())
    assert record["timings"]["points_computed"] == 9  # chunks 1, 2 and 3
    assert_identical_to_an_uninterrupted_run(outputs, study, tmp_path)


def test_an_unreadable_checkpoint_is_named_and_the_run_resumes_once_readable(
    tmp_path: Path,
    study: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    enforce_modes(tmp_path, monkeypatch)
    outputs = tmp_path / "outputs"
    folder = failed_run(outputs, study, monkeypatch)
    capsys.readouterr()
    locked = folder / "chunks" / "000000.npz"
    locked.chmod(0)
    assert resume(folder.name, outputs) == EXIT_OUTPUT_ERROR
    assert one_line_error(capsys).startswith(f"error: Permission denied: {locked}; run ")
    locked.chmod(0o644)
    assert resume(folder.name, outputs) == 0
    assert_identical_to_an_uninterrupted_run(outputs, study, tmp_path)


@pytest.mark.parametrize("content", [b"", b"CDF\x01garbage"])
def test_a_results_file_that_is_none_is_one_line_for_every_command(
    tmp_path: Path, study: Path, content: bytes, capsys: pytest.CaptureFixture[str]
) -> None:
    # An audit's case: an empty file and one with a netCDF magic number but nothing else gave
    # a traceback and exit 1, the code by which regress says that a response moved.
    outputs = tmp_path / "outputs"
    assert run(study, outputs) == 0
    (row,) = RunStore(outputs).list_runs()
    good = Path(row["folder"]) / "results.nc"
    bad = tmp_path / "bad.nc"
    bad.write_bytes(content)
    capsys.readouterr()
    for argv in (["analyze", str(bad)], ["regress", str(good), str(bad)]):
        assert main(argv) == EXIT_OUTPUT_ERROR
        assert f"error: {bad} " in one_line_error(capsys)
    good.write_bytes(content)
    assert main(["export", row["run_id"], "--outputs", str(outputs)]) == EXIT_OUTPUT_ERROR
    assert f"error: {good} " in one_line_error(capsys)
