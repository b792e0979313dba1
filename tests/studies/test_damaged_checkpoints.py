"""Every checkpoint and run.json is validated before ``--resume`` uses it (issue 25, item 4):
a chunk missing a response (before: that response silently NaN for the chunk), a copy under
another number, arrays cut short, an extra curve or response, a chunk of an older format or
beyond the plan; a run.json that is a list, has an extra or a missing key or a mistyped value.
Each is refused in one line naming the file (exit 4 for a chunk, 2 for run.json), nothing is
lost, and once the bad file is removed (or restored) the run resumes to the numbers of a run
that was never interrupted."""

from __future__ import annotations

import errno
import json
import os
import shutil
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest
from run_faults import failing_on_call

from studies import pipeline
from studies.cli import EXIT_OUTPUT_ERROR, EXIT_STUDY_ERROR, main
from studies.run.results import open_results
from studies.tracking.store import RunStore

STUDY = """
name = "chunks"
scene = "cam"
responses = ["max_jerk", "min_radius_of_curvature"]
[factors.base_radius]
levels = [16.0, 18.0, 20.0, 22.0]
[factors.cam_speed]
levels = [1000.0, 1300.0, 1600.0]
"""
RESPONSES = ("max_jerk", "min_radius_of_curvature")


def run(study: Path, outputs: Path, *extra: str) -> int:
    return main(["run", str(study), "--outputs", str(outputs), "--no-progress", *extra])


def resume(run_id: str, outputs: Path) -> int:
    return main(["run", "--resume", run_id, "--outputs", str(outputs), "--no-progress"])


@pytest.fixture(scope="module")
def expected(tmp_path_factory: pytest.TempPathFactory) -> dict[str, np.ndarray]:
    """The results of an uninterrupted run (the reference every resume must reproduce)."""
    tmp = tmp_path_factory.mktemp("fresh")
    study = tmp / "chunks.toml"
    study.write_text(STUDY)
    assert run(study, tmp / "out") == 0
    (row,) = RunStore(tmp / "out").list_runs()
    ds = open_results(Path(row["folder"]) / "results.nc")
    return {name: ds[name].values for name in RESPONSES}


@pytest.fixture
def failed(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> tuple[Path, Path]:
    """A run whose disk filled at chunk 2 of 4 (chunks of 3 points): (outputs, run folder)."""
    study = tmp_path / "chunks.toml"
    study.write_text(STUDY)
    outputs = tmp_path / "out"
    full = OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
    with monkeypatch.context() as patch:
        patch.setattr(pipeline, "_save_chunk", failing_on_call(pipeline._save_chunk, 3, full))
        assert run(study, outputs, "--chunk-size", "3") == EXIT_OUTPUT_ERROR
    (row,) = RunStore(outputs).list_runs()
    return outputs, Path(row["folder"])


def rewrite(path: Path, change: Callable[[dict[str, np.ndarray]], None]) -> None:
    with np.load(path) as data:
        arrays = {k: data[k] for k in data.files}
    change(arrays)
    path.unlink()
    np.savez(path, **arrays)


def drop(key: str) -> Callable[[dict[str, np.ndarray]], None]:
    return lambda arrays: arrays.pop(key)


def cut(key: str) -> Callable[[dict[str, np.ndarray]], None]:
    return lambda arrays: arrays.update({key: arrays[key][:2]})


def add(key: str, shape: tuple[int, ...]) -> Callable[[dict[str, np.ndarray]], None]:
    return lambda arrays: arrays.update({key: np.zeros(shape)})


def one_line(capsys: pytest.CaptureFixture[str]) -> str:
    err = capsys.readouterr().err.strip()
    assert "Traceback" not in err
    (line,) = err.splitlines()
    return line


def assert_resumes_to_the_uninterrupted_numbers(
    outputs: Path, folder: Path, expected: dict[str, np.ndarray]
) -> None:
    assert resume(folder.name, outputs) == 0
    ds = open_results(folder / "results.nc")
    for name, values in expected.items():
        np.testing.assert_array_equal(ds[name].values, values, err_msg=name)


@pytest.mark.parametrize(
    ("damage", "reason"),
    [
        (drop("scalar:max_jerk"), "missing scalar:max_jerk"),
        (cut("scalar:min_radius_of_curvature"), "scalar:min_radius_of_curvature has shape (2,)"),
        (add("curve:velocity", (3, 5)), "unexpected curve:velocity"),
        (add("scalar:max_lift", (3,)), "unexpected scalar:max_lift"),
        (drop("meta:version"), "checkpoint version none, expected 2"),
        (lambda a: a.update({"meta:runs": np.array([0, 3])}), "design points [0, 3], expected"),
    ],
    ids=["missing-response", "cut-short", "extra-curve", "extra-response", "old", "runs"],
)
def test_a_damaged_chunk_is_refused_in_one_line_and_nothing_is_lost(
    failed: tuple[Path, Path],
    expected: dict[str, np.ndarray],
    capsys: pytest.CaptureFixture[str],
    damage: Callable[[dict[str, np.ndarray]], None],
    reason: str,
) -> None:
    outputs, folder = failed
    capsys.readouterr()
    bad = folder / "chunks" / "000001.npz"
    rewrite(bad, damage)
    kept = {p.name: p.read_bytes() for p in (folder / "chunks").iterdir()}
    assert resume(folder.name, outputs) == EXIT_OUTPUT_ERROR
    line = one_line(capsys)
    assert line.startswith(f"error: checkpoint {bad} does not belong to this run ({reason}")
    assert "delete it and resume: its design points are computed again" in line
    assert {p.name: p.read_bytes() for p in (folder / "chunks").iterdir()} == kept
    assert not (folder / "results.nc").exists()
    bad.unlink()
    assert_resumes_to_the_uninterrupted_numbers(outputs, folder, expected)


def test_a_chunk_copied_under_another_number_is_refused(
    failed: tuple[Path, Path], expected: dict[str, np.ndarray], capsys: pytest.CaptureFixture[str]
) -> None:
    """Before: the copy's values were written into chunk 2's design points (or IndexError)."""
    outputs, folder = failed
    capsys.readouterr()
    copy = folder / "chunks" / "000002.npz"
    shutil.copy(folder / "chunks" / "000000.npz", copy)
    assert resume(folder.name, outputs) == EXIT_OUTPUT_ERROR
    assert one_line(capsys).startswith(
        f"error: checkpoint {copy} does not belong to this run (design points [0, 3], "
        "expected [6, 9])"
    )
    copy.unlink()
    assert_resumes_to_the_uninterrupted_numbers(outputs, folder, expected)


def test_a_chunk_beyond_the_plan_is_refused(
    failed: tuple[Path, Path], capsys: pytest.CaptureFixture[str]
) -> None:
    outputs, folder = failed
    capsys.readouterr()
    stray = folder / "chunks" / "000099.npz"
    shutil.copy(folder / "chunks" / "000000.npz", stray)
    assert resume(folder.name, outputs) == EXIT_STUDY_ERROR
    assert one_line(capsys) == (
        f"error: run {folder.name}: chunk size 3 gives 4 chunks, but {stray} lie beyond them: "
        "delete those and resume"
    )


@pytest.mark.parametrize(
    ("record", "reason"),
    [
        (lambda r: [r], "a JSON list, expected an object"),
        (lambda r: r | {"owner": "mallory"}, "unknown key 'owner'"),
        (lambda r: {k: v for k, v in r.items() if k != "study"}, "missing key 'study'"),
        (lambda r: r | {"runs": "12"}, 'runs = "12" should be of type int'),
        (lambda r: r | {"git_dirty": "no"}, 'git_dirty = "no" should be of type bool'),
        (lambda r: r | {"settings": [1]}, "settings = [1] should be of type dict"),
    ],
    ids=["list", "extra-key", "missing-key", "runs-text", "dirty-text", "settings-list"],
)
def test_a_run_json_that_is_not_a_run_record_is_refused(
    failed: tuple[Path, Path],
    capsys: pytest.CaptureFixture[str],
    record: Callable[[dict], object],
    reason: str,
) -> None:
    outputs, folder = failed
    capsys.readouterr()
    path = folder / "run.json"
    original = path.read_text()
    path.write_text(json.dumps(record(json.loads(original))))
    damaged = path.read_text()
    assert resume(folder.name, outputs) == EXIT_STUDY_ERROR
    assert one_line(capsys) == (f"error: {path} is not a run record ({reason}): it was not resumed")
    assert path.read_text() == damaged  # nothing rewritten
    assert len(list((folder / "chunks").glob("*.npz"))) == 2


def test_a_run_json_that_is_not_json_is_refused(
    failed: tuple[Path, Path], capsys: pytest.CaptureFixture[str]
) -> None:
    outputs, folder = failed
    capsys.readouterr()
    (folder / "run.json").write_bytes(b'{"run_id": "x", \xff')
    assert resume(folder.name, outputs) == EXIT_STUDY_ERROR
    assert one_line(capsys).startswith(f"error: {folder / 'run.json'} is not a run record: ")
