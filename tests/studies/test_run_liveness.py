"""Liveness that is true, and kills that lose nothing: the heartbeat thread through long
phases, the run folder's lock against a second resume, SIGKILL at each phase boundary of a
run and of an rm, a copied outputs tree, and tags that cannot pose as run ids."""

from __future__ import annotations

import json
import shutil
import sqlite3
import subprocess
import sys
import time
from contextlib import closing
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from run_faults import fail_on_call

from studies import pipeline
from studies.cli import main
from studies.define.plan import plan_text
from studies.pipeline import run_plan
from studies.run.results import open_results
from studies.tracking import liveness as live
from studies.tracking import registry
from studies.tracking.liveness import current_status, liveness, lock_folder
from studies.tracking.store import RunStore

STUDY = """
name = "alive"
scene = "cam"
responses = ["max_jerk", "min_radius_of_curvature"]
design = "full_factorial"
[factors.base_radius]
levels = [16.0, 18.0, 20.0]
[factors.cam_speed]
levels = [1000.0, 1300.0]
"""
KILLS = Path(__file__).resolve().parents[1] / "run_kills.py"


def another_host_sees(outputs: Path) -> str:
    """The run's status as read from run.json on another machine (heartbeat only)."""
    (path,) = outputs.glob("alive/*/run.json")
    record = json.loads(path.read_text(encoding="utf-8"))
    record["host"] = {"node": "another-host"}
    return liveness(record)


@pytest.mark.parametrize("phase", ["compile", "chunk", "analysis"])
def test_another_host_sees_a_run_alive_through_a_long_phase(
    phase: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(live, "HEARTBEAT_S", 0.05)
    monkeypatch.setattr(live, "STALE_S", 1.0)
    seen: list[str] = []

    def long_phase() -> None:  # 2.5 heartbeat ages of silence, were it not for the thread
        time.sleep(2.5)
        seen.append(another_host_sees(tmp_path))

    plan = plan_text(STUDY)
    if phase == "analysis":
        original = pipeline.write_analysis

        def slow_analysis(*args: Any, **kwargs: Any) -> Any:
            long_phase()
            return original(*args, **kwargs)

        monkeypatch.setattr(pipeline, "write_analysis", slow_analysis)
    else:  # the first call of a stage is the warm-up (compile), the second the first chunk
        call = 1 if phase == "compile" else 2
        original_stage = plan.scene.stages["geometry"]
        calls = {"n": 0}

        def stage(*args: Any, **kwargs: Any) -> Any:
            calls["n"] += 1
            if calls["n"] == call:
                long_phase()
            return original_stage(*args, **kwargs)

        monkeypatch.setitem(plan.scene.stages, "geometry", stage)
    result = run_plan(plan, tmp_path, chunk_size=3, progress=False)
    assert seen == ["running"]
    assert result.record.status == "finished"
    assert another_host_sees(tmp_path) == "finished"


def failed_run(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> tuple[str, Path]:
    """A run that failed in its second chunk (its id and folder)."""
    plan = plan_text(STUDY)
    fail_on_call(monkeypatch, plan, 3, RuntimeError("simulated crash"))
    with pytest.raises(RuntimeError):
        run_plan(plan, tmp_path, chunk_size=2, progress=False)
    (folder,) = (tmp_path / "alive").iterdir()
    return folder.name, folder


def one_line(err: str) -> str:
    assert "Traceback" not in err
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    return lines[0]


def test_a_resume_is_refused_while_another_holds_the_run_folder(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    run_id, folder = failed_run(tmp_path, monkeypatch)
    lock = lock_folder(folder)  # as a resume in another process holds it
    assert lock is not None
    with lock:
        command = ["run", "--resume", run_id, "--outputs", str(tmp_path), "--no-progress"]
        assert main(command) == 2
        assert "is being run or resumed by another process" in one_line(capsys.readouterr().err)
        assert main(["rm", run_id, "--outputs", str(tmp_path)]) == 2
        assert "is still running" in one_line(capsys.readouterr().err)
        assert current_status(RunStore(tmp_path).find_run(run_id))[0] == "running"
    assert main(command) == 0


def kill_at(phase: str, *command: str) -> None:
    done = subprocess.run(
        [sys.executable, str(KILLS), phase, *command],
        check=False,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert done.returncode == -9, done.stderr  # SIGKILL


@pytest.fixture(scope="module")
def fresh(tmp_path_factory: pytest.TempPathFactory) -> dict[str, np.ndarray]:
    """The responses of an uninterrupted run, to compare the resumed ones with."""
    ds = run_plan(plan_text(STUDY), tmp_path_factory.mktemp("fresh"), progress=False).dataset
    return {name: ds[name].values for name in ("max_jerk", "min_radius_of_curvature")}


@pytest.mark.slow
@pytest.mark.parametrize("phase", ["before-registration", "after-first-chunk", "before-analysis"])
def test_a_run_killed_at_a_phase_boundary_is_listed_and_resumes_bit_identical(
    phase: str, tmp_path: Path, fresh: dict[str, np.ndarray], capsys: pytest.CaptureFixture[str]
) -> None:
    study = tmp_path / "alive.toml"
    study.write_text(STUDY, encoding="utf-8")
    outputs = tmp_path / "out"
    kill_at(phase, "run", str(study), "--outputs", str(outputs), "--no-progress",
            "--chunk-size", "2")  # fmt: skip
    assert main(["runs", "--outputs", str(outputs)]) == 0  # registered on sight
    listed = capsys.readouterr().out
    (row,) = RunStore(outputs).list_runs()
    assert " interrupted " in listed
    assert f"run --resume {row['run_id']}" in listed
    command = ["run", "--resume", row["run_id"], "--outputs", str(outputs), "--no-progress"]
    assert main(command) == 0
    (row,) = RunStore(outputs).list_runs()
    assert row["status"] == "finished"
    with open_results(Path(row["folder"]) / "results.nc") as ds:
        for name, values in fresh.items():
            np.testing.assert_array_equal(ds[name].values, values)


@pytest.mark.slow
def test_a_run_killed_after_finishing_is_finished_everywhere(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    study = tmp_path / "alive.toml"
    study.write_text(STUDY, encoding="utf-8")
    outputs = tmp_path / "out"
    kill_at("after-finished", "run", str(study), "--outputs", str(outputs), "--no-progress")
    with closing(sqlite3.connect(outputs / registry.REGISTRY)) as con:
        assert con.execute("SELECT status FROM runs").fetchall() == [("running",)]
    (row,) = RunStore(outputs).list_runs()  # seeing it mends the registry row
    with closing(sqlite3.connect(outputs / registry.REGISTRY)) as con:
        assert con.execute("SELECT status FROM runs").fetchall() == [("finished",)]
    assert main(["runs", "--where", "max_jerk.max>0", "--outputs", str(outputs)]) == 0
    assert row["run_id"] in capsys.readouterr().out  # its responses are indexed too
    assert main(["run", "--resume", row["run_id"], "--outputs", str(outputs)]) == 2
    assert "already finished" in one_line(capsys.readouterr().err)


@pytest.mark.slow
def test_an_rm_killed_between_the_trash_and_the_registry_loses_nothing(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    run_id = run_plan(plan_text(STUDY), tmp_path, progress=False).record.run_id
    kill_at("rm-before-registry", "rm", run_id, "--outputs", str(tmp_path))
    assert [e.run_id for e in RunStore(tmp_path).trash_entries()] == [run_id]
    assert RunStore(tmp_path).list_runs() == []  # its rows are deleted on sight
    assert main(["restore", run_id, "--outputs", str(tmp_path)]) == 0
    assert [r["run_id"] for r in RunStore(tmp_path).list_runs()] == [run_id]


@pytest.mark.slow
def test_two_resumes_started_together_one_runs_the_other_is_refused(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    run_id, _ = failed_run(tmp_path, monkeypatch)
    command = [sys.executable, str(KILLS), "slow-chunks", "run", "--resume", run_id,
               "--outputs", str(tmp_path), "--no-progress"]  # fmt: skip
    both = [subprocess.Popen(command, stderr=subprocess.PIPE, text=True) for _ in range(2)]
    answers = sorted((p.wait(timeout=600), p.communicate()[1]) for p in both)
    assert [code for code, _ in answers] == [0, 2]
    refused = one_line(answers[1][1])
    assert "not resumed" in refused or "nothing to resume" in refused
    assert RunStore(tmp_path).list_runs()[0]["status"] == "finished"


def fingerprint(folder: Path) -> dict[str, bytes]:
    return {str(p.relative_to(folder)): p.read_bytes() for p in folder.rglob("*") if p.is_file()}


@pytest.mark.parametrize("legacy", [False, True], ids=["relative rows", "absolute rows"])
def test_gc_of_a_copied_outputs_tree_removes_the_copys_runs_never_the_originals(
    legacy: bool, tmp_path: Path
) -> None:
    a, b = tmp_path / "A", tmp_path / "B"
    run_id = run_plan(plan_text(STUDY), a, progress=False).record.run_id
    shutil.copytree(a, b, symlinks=True)  # cp -a A B
    if legacy:  # rows as an earlier version wrote them: absolute folders, under A
        with closing(sqlite3.connect(b / registry.REGISTRY)) as con, con:
            con.execute("UPDATE runs SET folder = ?", (str(a / "alive" / run_id),))
    before = fingerprint(a)
    assert main(["gc", "--older-than", "0s", "--outputs", str(b)]) == 0
    assert [e.run_id for e in RunStore(b).trash_entries()] == [run_id]
    assert main(["gc", "--older-than", "0s", "--outputs", str(b)]) == 0  # empties B's trash
    assert RunStore(b).trash_entries() == []
    assert not (b / "alive" / run_id).exists()
    assert RunStore(b).list_runs() == []
    assert fingerprint(a) == before
    assert [r["run_id"] for r in RunStore(a).list_runs()] == [run_id]


def test_a_tag_cannot_take_the_form_of_a_run_id_nor_hijack_one(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    a, b = (run_plan(plan_text(STUDY), tmp_path, progress=False).record.run_id for _ in range(2))
    out = ["--outputs", str(tmp_path)]
    for tag in (a, a[:8], "2026-review", "with space"):
        assert main(["tag", b, tag, *out]) == 2
        assert "can never be mistaken for a run id" in one_line(capsys.readouterr().err)
    assert RunStore(tmp_path).tags_and_notes()[0] == {}
    # a registry written before tags were checked may hold one: the id still names its run
    with closing(sqlite3.connect(tmp_path / registry.REGISTRY)) as con, con:
        con.execute("INSERT INTO tags (tag, run_id) VALUES (?, ?)", (a, b))
    assert RunStore(tmp_path).find_run(a)["run_id"] == a
    assert main(["rm", a, *out]) == 0
    assert [e.run_id for e in RunStore(tmp_path).trash_entries()] == [a]
    assert [r["run_id"] for r in RunStore(tmp_path).list_runs()] == [b]
