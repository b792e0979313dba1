"""A disk that fills at any write of results, analysis or reports (issue 25, item 4): exit 4,
one line, the run marked failed with the reason, no file of the attempt left behind (results.nc,
analysis.nc, report.md, report.html, figures: any may be cut short), no second exception from
the clean-up; once space is back the run resumes. The writes fail as a full disk makes them
fail: ``OSError(ENOSPC)`` from Python and matplotlib, the netCDF library's ``RuntimeError``
("NetCDF: HDF error") from netCDF4 — and, in a process of its own, a real file-size limit
(``ulimit -f``)."""

from __future__ import annotations

import errno
import json
import os
import re
import resource
import shutil
import subprocess
import sys
from pathlib import Path
from typing import Any

import matplotlib.figure
import netCDF4
import pytest
import xarray as xr
from run_faults import failing_on_call

from studies import pipeline
from studies.cli import EXIT_OUTPUT_ERROR, main
from studies.define.plan import plan_text
from studies.run import results_writer
from studies.run.runner import evaluate
from studies.tracking.checkpoints import checkpoint_bytes
from studies.tracking.records import RunRecord
from studies.tracking.store import RunStore

STUDY = """
name = "full"
scene = "cam"
responses = ["max_jerk", "min_radius_of_curvature"]
[factors.base_radius]
levels = [16.0, 18.0, 20.0]
[factors.cam_speed]
levels = [1000.0, 1300.0]
"""


def enospc() -> OSError:  # a fresh exception each time: the run adds notes to the one it sees
    return OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))


def hdf() -> RuntimeError:
    return RuntimeError("NetCDF: HDF error")


KEPT = {"study.toml", "run.json", "chunks"}


def _cut_short(original, *names: str):  # type: ignore[no-untyped-def]
    """``Path.write_text`` (``original``), except that files called one of ``names`` get a
    prefix of the text and then ENOSPC, as on a disk that fills."""

    def write_text(self: Path, *args: object, **kwargs: object) -> int:
        if self.name in names:
            with self.open("w") as cut:
                cut.write("# cut sh")  # what a full disk leaves: a prefix
            raise enospc()
        return original(self, *args, **kwargs)

    return write_text


FAULTS = {
    # results.nc: a chunk written into it, its closing, its creation
    "results-chunk": (results_writer.ResultsWriter, "_write", hdf, 2),
    "results-close": (netCDF4.Dataset, "close", hdf, 1),
    "analysis-nc": (xr.Dataset, "dump_to_store", hdf, 2),  # 1: the results layout, 2: analysis.nc
    "figure": (matplotlib.figure.Figure, "savefig", enospc, 2),
}


def full_study(folder: Path) -> tuple[Path, Path]:
    """The study file ``STUDY`` written in ``folder``, and the outputs folder beside it."""
    study = folder / "full.toml"
    study.write_text(STUDY, encoding="utf-8")
    return study, folder / "out"


def run(study: Path, outputs: Path, *extra: str) -> int:
    return main(["run", str(study), "--outputs", str(outputs), "--no-progress", *extra])


def check_failed_run(outputs: Path, capsys: pytest.CaptureFixture[str], reason: str) -> Path:
    err = capsys.readouterr().err.strip()
    assert "Traceback" not in err
    (line,) = err.splitlines()
    assert line.startswith("error: ")
    assert reason in line
    (row,) = RunStore(outputs).list_runs()
    folder = Path(row["folder"])
    record = json.loads((folder / "run.json").read_text())
    assert record["status"] == "failed"
    assert "No space left" in record["error"] or "HDF error" in record["error"]
    assert {p.name for p in folder.iterdir()} == KEPT  # nothing of the attempt left
    assert line.endswith(RunStore(outputs).resume_command(row["run_id"]))
    return folder


@pytest.mark.parametrize("fault", FAULTS)
def test_a_full_disk_at_each_write_is_one_line_and_resumable(
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
    fault: str,
) -> None:
    owner, name, error, call = FAULTS[fault]
    study, outputs = full_study(tmp_path)
    with monkeypatch.context() as patch:
        patch.setattr(owner, name, failing_on_call(getattr(owner, name), call, error()))
        assert run(study, outputs, "--chunk-size", "2") == EXIT_OUTPUT_ERROR
    reason = "is the disk full?" if error is hdf else os.strerror(errno.ENOSPC)
    folder = check_failed_run(outputs, capsys, reason)
    assert main(["run", "--resume", folder.name, "--outputs", str(outputs), "--no-progress"]) == 0
    assert (folder / "report.html").exists()


def test_a_full_disk_while_writing_the_report_leaves_no_cut_report(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    study, outputs = full_study(tmp_path)
    with monkeypatch.context() as patch:
        patch.setattr(Path, "write_text", _cut_short(Path.write_text, "report.md", "report.html"))
        assert run(study, outputs) == EXIT_OUTPUT_ERROR
    check_failed_run(outputs, capsys, os.strerror(errno.ENOSPC))


def test_a_full_disk_before_run_json_is_written_leaves_no_run_folder(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    # An audit's case: the run folder was left holding run.json.writing, which `runs` does
    # not list, and the error named no file.
    study, outputs = full_study(tmp_path)
    with monkeypatch.context() as patch:
        patch.setattr(Path, "write_text", _cut_short(Path.write_text, "run.json.writing"))
        assert run(study, outputs) == EXIT_OUTPUT_ERROR
    assert list((outputs / "full").iterdir()) == []
    assert RunStore(outputs).list_runs() == []
    (line,) = capsys.readouterr().err.strip().splitlines()
    folder = re.escape(str(outputs / "full")) + r"/[\w-]+"
    assert re.fullmatch(
        f"error: No space left on device: ({folder})/run.json; nothing was run: the run "
        r"folder \1 was removed again",
        line,
    ), line


def test_a_run_json_that_cannot_be_rewritten_stays_as_it_was(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    record = RunRecord(
        run_id="r", study="full", scene="cam", design="sweep", runs=1, status="running",
        started="2026-12-07T00:00:00+00:00", git_commit="c", git_dirty=False,
        definition_sha256="d", folder=str(tmp_path),
    )  # fmt: skip
    record.write()
    before = (tmp_path / "run.json").read_bytes()
    record.status = "failed"
    monkeypatch.setattr(Path, "write_text", _cut_short(Path.write_text, "run.json.writing"))
    with pytest.raises(OSError, match="No space left on device") as failed:
        record.write()
    assert [p.name for p in tmp_path.iterdir()] == ["run.json"]
    assert (tmp_path / "run.json").read_bytes() == before
    assert str(failed.value) == f"[Errno 28] No space left on device: '{tmp_path / 'run.json'}'"


def test_the_clean_up_never_raises_again(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """Before: closing the half-written netCDF file raised a second HDF error inside the
    handler, and run.json still said "running"."""
    study, outputs = full_study(tmp_path)
    with monkeypatch.context() as patch:
        patch.setattr(netCDF4.Dataset, "close", failing_on_call(netCDF4.Dataset.close, 1, hdf()))
        patch.setattr(
            results_writer.ResultsWriter,
            "_write",
            failing_on_call(results_writer.ResultsWriter._write, 1, hdf()),
        )
        assert run(study, outputs) == EXIT_OUTPUT_ERROR
    check_failed_run(outputs, capsys, "is the disk full?")


def test_analyze_onto_a_full_disk_leaves_nothing_behind(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    study, outputs = full_study(tmp_path)
    assert run(study, outputs) == 0
    (row,) = RunStore(outputs).list_runs()
    target = tmp_path / "again"
    capsys.readouterr()
    with monkeypatch.context() as patch:
        savefig = matplotlib.figure.Figure.savefig
        patch.setattr(matplotlib.figure.Figure, "savefig", failing_on_call(savefig, 2, enospc()))
        code = main(["analyze", str(Path(row["folder"]) / "results.nc"), "--to", str(target)])
    assert code == EXIT_OUTPUT_ERROR
    (line,) = capsys.readouterr().err.strip().splitlines()
    assert line == f"error: {enospc()}; nothing was recorded"
    assert not target.exists()


def test_analyze_to_another_runs_folder_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    study, outputs = full_study(tmp_path)
    assert run(study, outputs) == 0
    assert run(study, outputs, "--force") == 0
    first, second = (Path(r["folder"]) for r in RunStore(outputs).list_runs())
    report = (second / "report.md").read_bytes()
    capsys.readouterr()
    assert main(["analyze", str(first / "results.nc"), "--to", str(second)]) == 2
    assert capsys.readouterr().err.strip() == (
        f"error: --to {second} holds a run's results: its recorded analysis would be overwritten"
    )
    assert (second / "report.md").read_bytes() == report


@pytest.mark.slow
def test_a_real_file_size_limit_is_one_line(tmp_path: Path) -> None:
    """``ulimit -f``: the kernel refuses the write that would pass the limit (EFBIG; Python
    ignores SIGXFSZ). The limit lets the checkpoints through, not results.nc with its curves."""
    study = tmp_path / "full.toml"
    study.write_text(
        STUDY.replace('responses = ["max_jerk"', 'curves = ["lift"]\nresponses = ["max_jerk"')
    )
    outputs = tmp_path / "out"
    limit = 60_000  # bytes; a chunk of 2 points of lift (3601 angles) is ~58 kB uncompressed
    # compiled and cached once without the limit, so that it falls on the run's files and not
    # on Numba's cache (a cold cache writes larger files first)
    assert main(["run", str(study), "--outputs", str(tmp_path / "warm"), "--no-progress"]) == 0

    def small_files() -> None:
        resource.setrlimit(resource.RLIMIT_FSIZE, (limit, limit))

    done = subprocess.run(
        [sys.executable, "-m", "studies", "run", str(study), "--outputs", str(outputs),
         "--no-progress", "--chunk-size", "2"],
        preexec_fn=small_files,
        capture_output=True, text=True, check=False,
    )  # fmt: skip
    assert done.returncode == EXIT_OUTPUT_ERROR, done.stderr
    assert "Traceback" not in done.stderr
    (line,) = done.stderr.strip().splitlines()
    assert line.startswith("error: ")
    (row,) = RunStore(outputs).list_runs()
    folder = Path(row["folder"])
    assert json.loads((folder / "run.json").read_text())["status"] == "failed"
    assert {p.name for p in folder.iterdir()} == KEPT
    assert main(["run", "--resume", row["run_id"], "--outputs", str(outputs), "--no-progress"]) == 0


def test_what_the_checkpoints_take_is_what_a_run_computes() -> None:
    # reference: the bytes of the chunk outputs an evaluation actually returns
    plan = plan_text(
        STUDY.replace(
            'min_radius_of_curvature"]', 'min_radius_of_curvature"]\ncurves = ["lift", "velocity"]'
        )
    )
    ev = evaluate(plan, progress=False)
    made = sum(v.nbytes for v in ev.scalars.values()) + sum(v.nbytes for v in ev.curves.values())
    assert checkpoint_bytes(plan) == made > 0


def test_a_run_that_cannot_fit_on_the_disk_is_refused_before_it_starts(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    study, outputs = full_study(tmp_path)
    real = shutil.disk_usage

    def small(path: str | Path) -> Any:
        return real(path)._replace(free=50)  # 6 points × 2 responses × 8 bytes do not fit

    monkeypatch.setattr(pipeline.shutil, "disk_usage", small)
    assert main(["run", str(study), "--outputs", str(outputs)]) == EXIT_OUTPUT_ERROR
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1
    assert "Traceback" not in err
    assert "full needs at least 9.6e-08 GB of disk for its 6 points' checkpoints" in err
    assert "5e-08 GB are free" in err
    assert not any(p.is_dir() and p.name == "full" for p in outputs.glob("*"))
