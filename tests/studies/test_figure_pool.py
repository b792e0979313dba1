"""Figures drawn by worker processes beside this one (studies/report/figure_pool.py).

Expected values: the figures drawn in one process (the path every test elsewhere takes, with
ENGINE_STUDIES_FIGURE_WORKERS=0 from tests/conftest.py), byte for byte; which process drew a job is
read from its own process id.
"""

from __future__ import annotations

import os
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest
from figure_jobs import dies_in_a_worker, drawn_by, fails, writes_after

from results_datasets import CATALOG, study_dataset
from studies.common.errors import StudyError
from studies.report import figure_pool
from studies.report.figure_pool import Drawing
from studies.report.write import write_analysis


@pytest.fixture
def pool(monkeypatch: pytest.MonkeyPatch) -> Iterator[None]:
    monkeypatch.setenv(figure_pool.ENVIRONMENT, "1")
    figure_pool.start()
    assert figure_pool._ready.wait(120)  # figures go to the worker once it runs
    yield
    figure_pool.stop()


def test_figures_drawn_by_a_worker_are_the_files_drawn_in_one_process(
    pool: None, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    ds = study_dataset(CATALOG / "isac_l9.toml")
    timings: dict[str, float] = {}
    shared = write_analysis(ds, tmp_path / "pool", timings=timings)
    figure_pool.stop()
    alone = write_analysis(ds, tmp_path / "alone")
    assert [p.name for p in shared] == [p.name for p in alone]
    pictures = [(a, b) for a, b in zip(shared, alone, strict=True) if a.suffix == ".png"]
    assert len(pictures) >= 6
    for a, b in pictures:
        assert a.read_bytes() == b.read_bytes(), a.name


def test_the_worker_takes_jobs_from_the_front_this_process_from_the_back(pool: None) -> None:
    problems: list[str] = []
    drawing = Drawing({}, problems)
    tags = [f"job{i}" for i in range(6)]
    for tag in tags:
        drawing.add(drawn_by, tag)
    paths = drawing.paths()
    assert [p.name.split("-")[0] for p in paths] == tags  # in the order asked for
    pids = [int(p.name.split("-")[1]) for p in paths]
    assert pids[0] != os.getpid()  # the first job went to the worker
    assert pids[-1] == os.getpid()  # the last was drawn here meanwhile
    assert problems == []


def test_a_figure_whose_worker_died_is_drawn_here(pool: None) -> None:
    problems: list[str] = []
    drawing = Drawing({}, problems)
    drawing.add(dies_in_a_worker, os.getpid())
    drawing.add(drawn_by, "last")
    paths = drawing.paths()
    assert paths[0] == Path("drawn here")
    assert paths[1].name == f"last-{os.getpid()}"
    assert problems == []


def test_a_figure_that_fails_in_a_worker_is_one_line_and_a_full_disk_fails_the_run(
    pool: None,
) -> None:
    problems: list[str] = []
    drawing = Drawing({}, problems)
    for _ in range(3):
        drawing.add(fails, RuntimeError)
    drawing.add(drawn_by, "last")
    paths = drawing.paths()
    assert [p.name.split("-")[0] for p in paths] == ["last"]
    assert problems == ["fails drew nothing: RuntimeError: no display"]  # once, not per job
    drawing.add(fails, OSError)
    drawing.add(drawn_by, "last")
    with pytest.raises(OSError, match="no display"):
        drawing.paths()


def test_a_run_that_fails_here_waits_for_the_worker_first(pool: None, tmp_path: Path) -> None:
    """A failed run removes the files it wrote: none may appear after that."""
    late = tmp_path / "late.png"
    drawing = Drawing({}, [])
    drawing.add(writes_after, late, 0.5)
    drawing.add(fails, OSError)
    with pytest.raises(OSError, match="no display"):
        drawing.paths()
    assert late.read_bytes() == b"late"


def test_a_job_that_cannot_be_sent_is_drawn_here(pool: None) -> None:
    def local(tag: str) -> list[Path]:  # a local function cannot be pickled
        return drawn_by(tag)

    drawing = Drawing({}, [])
    drawing.add(local, "a")
    drawing.add(local, "b")
    assert [p.name for p in drawing.paths()] == [f"a-{os.getpid()}", f"b-{os.getpid()}"]


def test_a_job_whose_arguments_do_not_pickle_is_drawn_here(pool: None) -> None:
    drawing = Drawing({}, [])
    drawing.add(drawn_by, Unpicklable())
    assert [p.name for p in drawing.paths()] == [f"unpicklable-{os.getpid()}"]


class Unpicklable:
    def __reduce__(self) -> tuple[object, ...]:
        raise ValueError("ctypes objects containing pointers cannot be pickled")

    def __str__(self) -> str:
        return "unpicklable"


@pytest.mark.parametrize("text", ["two", "-1", "1.5", "²"])
def test_a_malformed_worker_count_is_an_error_naming_it(
    text: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv(figure_pool.ENVIRONMENT, text)
    with pytest.raises(StudyError, match=f"ENGINE_STUDIES_FIGURE_WORKERS = '{text}'"):
        figure_pool.start()


UNGUARDED = """
import sys
from studies.cli import main
main(["run", "isac_l9", "--outputs", sys.argv[1], "--no-progress"])
"""


def test_a_script_calling_the_command_line_without_a_guard_runs_its_study_once(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A worker process imports the main module: this script's would run the study again
    (and register a second run). Workers start only under ``python -m studies``."""
    monkeypatch.setenv(figure_pool.ENVIRONMENT, "1")
    script = tmp_path / "script.py"
    script.write_text(UNGUARDED, encoding="utf-8")
    outputs = tmp_path / "outputs"
    subprocess.run([sys.executable, str(script), str(outputs)], check=True, timeout=600)
    assert len(list(outputs.glob("isac_l9/*/run.json"))) == 1


def test_the_command_line_draws_with_a_worker_and_without_one_where_none_can_start(
    tmp_path: Path,
) -> None:
    """``python -m studies run`` with a figure worker (through its exit without teardown), and
    with a temporary folder too deep for the forkserver's socket (AF_UNIX paths end at 107
    bytes): the run finishes with every figure either way."""
    deep = tmp_path / ("d" * 60) / ("e" * 60)
    deep.mkdir(parents=True)
    counts = []
    for name, temp in (("worker", tmp_path), ("no-socket", deep)):
        env = {**os.environ, figure_pool.ENVIRONMENT: "1", "TMPDIR": str(temp)}
        outputs = tmp_path / name
        command = [sys.executable, "-m", "studies", "run", "isac_l9", "--outputs", str(outputs)]
        done = subprocess.run(
            [*command, "--no-progress"],
            check=False,
            env=env,
            capture_output=True,
            text=True,
            timeout=600,
        )
        assert done.returncode == 0, done.stderr
        (folder,) = outputs.glob("isac_l9/*/")
        counts.append(len(list(folder.glob("*.png"))))
    assert counts[0] == counts[1] >= 6
