"""The registry: schema version and migration, concurrent writers, tags, notes, rm and gc."""

from __future__ import annotations

import datetime as dt
import json
import math
import multiprocessing
import shutil
import sqlite3
from contextlib import closing
from pathlib import Path

import pytest
from registry_writers import RUNS_EACH, register_many

from studies import registry, tracking
from studies.cli import main
from studies.study_run import run_study

STUDY = """
name = "tiny"
scene = "cam"
responses = ["max_jerk", "min_radius_of_curvature"]
design = "full_factorial"
[parameters]
cam_speed = {cam_speed}
[factors.base_radius]
levels = [16.0, 18.0]
"""
V1_SCHEMA = (
    "CREATE TABLE runs (run_id TEXT PRIMARY KEY, study TEXT, scene TEXT, design TEXT, "
    "runs INTEGER, status TEXT, started TEXT, finished TEXT, git_commit TEXT, git_dirty INTEGER, "
    "compile_s REAL, run_s REAL, folder TEXT, definition_sha256 TEXT)"
)
WRITERS = 4


def tiny_run(tmp_path: Path, outputs: Path, cam_speed: float = 1000.0) -> str:
    path = tmp_path / f"tiny_{cam_speed:g}.toml"
    path.write_text(STUDY.format(cam_speed=cam_speed), encoding="utf-8")
    return run_study(path, outputs=outputs, progress=False).record.run_id


def test_a_version_1_registry_is_migrated_in_place(tmp_path: Path) -> None:
    outputs = tmp_path / "out"
    run_id = tiny_run(tmp_path, outputs)
    (outputs / registry.REGISTRY).unlink()
    with closing(sqlite3.connect(outputs / registry.REGISTRY)) as con, con:  # as version 1 wrote
        con.execute(V1_SCHEMA)
        folder = next((outputs / "tiny").iterdir())
        record = json.loads((folder / "run.json").read_text(encoding="utf-8"))
        skipped = ("compile_s", "run_s", "code_sha256")
        row = [record.get(c) for c in registry.COLUMNS if c not in skipped]
        con.execute(
            "INSERT INTO runs (run_id, study, scene, design, runs, status, started, finished, "
            "git_commit, git_dirty, folder, definition_sha256) VALUES "
            "(?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)",
            row,
        )
    values = {v["name"]: v for v in registry.run_values(outputs, run_id)}
    with closing(sqlite3.connect(outputs / registry.REGISTRY)) as con:
        assert con.execute("PRAGMA user_version").fetchone()[0] == registry.SCHEMA_VERSION
    # indexed in SI: 1000 rpm = 1000 · 2π/60 rad/s; the scene's units kept beside
    assert values["cam_speed"]["num"] == pytest.approx(1000.0 * 2 * math.pi / 60, rel=1e-15)
    assert (values["cam_speed"]["units"], values["cam_speed"]["declared_units"]) == (
        "rad/s",
        "rpm",
    )
    assert values["max_jerk.max"]["units"] == "m/rad^3"
    assert [r["run_id"] for r in tracking.list_runs(outputs)] == [run_id]


def test_a_version_2_registry_is_indexed_again_in_si(tmp_path: Path) -> None:
    outputs = tmp_path / "out"
    run_id = tiny_run(tmp_path, outputs)
    (outputs / registry.REGISTRY).unlink()
    with closing(sqlite3.connect(outputs / registry.REGISTRY)) as con, con:  # as version 2 wrote
        con.execute(V1_SCHEMA)
        con.execute(
            "CREATE TABLE run_values (run_id TEXT NOT NULL, kind TEXT NOT NULL, "
            "name TEXT NOT NULL, text TEXT, num REAL, units TEXT)"
        )
        con.execute("CREATE TABLE tags (tag TEXT PRIMARY KEY, run_id TEXT NOT NULL)")
        con.execute("CREATE TABLE notes (run_id TEXT NOT NULL, written TEXT, text TEXT)")
        folder = next((outputs / "tiny").iterdir())
        con.execute(
            "INSERT INTO runs (run_id, study, status, folder) VALUES (?, 'tiny', 'finished', ?)",
            (run_id, str(folder)),
        )
        con.execute(  # version 2 held the file's units
            "INSERT INTO run_values VALUES (?, 'parameter', 'cam_speed', '1000.0', 1000.0, 'rpm')",
            (run_id,),
        )
        con.execute("INSERT INTO tags VALUES ('kept', ?)", (run_id,))
        con.execute("PRAGMA user_version = 2")
    values = [v for v in registry.run_values(outputs, run_id) if v["name"] == "cam_speed"]
    (value,) = values  # 1000 rpm = 1000 · 2π/60 rad/s
    assert value["num"] == pytest.approx(1000.0 * 2 * math.pi / 60, rel=1e-15)
    assert value["units"] == "rad/s"
    assert registry.tagged_run(outputs, "kept") == run_id
    with closing(sqlite3.connect(outputs / registry.REGISTRY)) as con:
        assert con.execute("PRAGMA user_version").fetchone()[0] == 3


def test_a_newer_registry_is_refused_with_exit_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    outputs = tmp_path / "out"
    outputs.mkdir()
    with closing(sqlite3.connect(outputs / registry.REGISTRY)) as con:
        con.execute(f"PRAGMA user_version = {registry.SCHEMA_VERSION + 1}")
    assert main(["runs", "--outputs", str(outputs)]) == 2
    assert "upgrade engine-studies" in capsys.readouterr().err


def test_four_processes_registering_at_once_leave_the_registry_intact(tmp_path: Path) -> None:
    context = multiprocessing.get_context("spawn")
    workers = [
        context.Process(target=register_many, args=(str(tmp_path), w)) for w in range(WRITERS)
    ]
    for w in workers:
        w.start()
    for w in workers:
        w.join(timeout=300)
    assert [w.exitcode for w in workers] == [0] * WRITERS
    with closing(sqlite3.connect(tmp_path / registry.REGISTRY)) as con:
        assert con.execute("PRAGMA integrity_check").fetchone()[0] == "ok"
        ids = {r[0] for r in con.execute("SELECT run_id FROM runs WHERE status = 'finished'")}
    assert ids == {f"{w}-{i}" for w in range(WRITERS) for i in range(RUNS_EACH)}


def test_tags_and_notes_work_wherever_a_run_id_does(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    outputs = tmp_path / "out"
    first = tiny_run(tmp_path, outputs, 1000.0)
    second = tiny_run(tmp_path, outputs, 1200.0)
    out = ["--outputs", str(outputs)]
    assert main(["tag", first, "baseline", *out]) == 0
    assert main(["note", "baseline", "the design review's run", *out]) == 0
    assert main(["show", "baseline", *out]) == 0
    shown = json.loads(capsys.readouterr().out.split("\n", 2)[2])
    assert shown["run_id"] == first
    assert shown["tags"] == ["baseline"]
    assert shown["notes"][0].endswith("the design review's run")
    assert main(["compare", "baseline", second, *out]) == 0
    assert "fixed parameter cam_speed  1000 rpm → 1200 rpm" in capsys.readouterr().out
    assert main(["tag", second, "baseline", *out]) == 0  # a tag names one run: it moves
    assert f"moved from {first}" in capsys.readouterr().out
    assert tracking.find_run(outputs, "baseline")["run_id"] == second
    assert main(["export", "baseline", *out]) == 0
    assert main(["tag", first, "nothing", "--remove", *out]) == 2
    assert "no tag 'nothing'" in capsys.readouterr().err


def test_rm_removes_folder_and_rows_together(tmp_path: Path) -> None:
    outputs = tmp_path / "out"
    run_id = tiny_run(tmp_path, outputs)
    folder = Path(tracking.find_run(outputs, run_id)["folder"])
    registry.set_tag(outputs, run_id, "keep")
    assert main(["rm", "keep", "--outputs", str(outputs)]) == 0
    assert not folder.exists()
    assert not list(folder.parent.iterdir())
    assert tracking.list_runs(outputs) == []
    assert registry.run_values(outputs, run_id) == []
    assert registry.tagged_run(outputs, "keep") is None


def test_rm_keeps_the_folder_when_the_registry_cannot_change(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from studies.housekeeping import remove_run

    outputs = tmp_path / "out"
    row = tracking.find_run(outputs, tiny_run(tmp_path, outputs))

    def locked(*_: object) -> None:
        raise sqlite3.OperationalError("database is locked")

    monkeypatch.setattr(registry, "delete_run", locked)
    with pytest.raises(sqlite3.OperationalError):
        remove_run(outputs, row)
    assert (Path(row["folder"]) / "results.nc").exists()
    assert tracking.find_run(outputs, row["run_id"]) is not None


def test_gc_removes_old_untagged_runs(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    outputs = tmp_path / "out"
    old, tagged, new = (tiny_run(tmp_path, outputs, s) for s in (1000.0, 1100.0, 1200.0))
    registry.set_tag(outputs, tagged, "baseline")
    long_ago = (dt.datetime.now(dt.UTC) - dt.timedelta(days=40)).isoformat(timespec="seconds")
    with closing(registry.connect(outputs)) as con, con:
        con.execute("UPDATE runs SET started = ? WHERE run_id IN (?, ?)", (long_ago, old, tagged))
    out = ["--outputs", str(outputs)]
    assert main(["gc", "--older-than", "30d", "--keep-tagged", "--dry-run", *out]) == 0
    assert f"would remove {old}" in capsys.readouterr().out
    assert len(tracking.list_runs(outputs)) == 3
    assert main(["gc", "--older-than", "30d", "--keep-tagged", *out]) == 0
    assert {r["run_id"] for r in tracking.list_runs(outputs)} == {tagged, new}
    assert sorted(p.name for p in (outputs / "tiny").iterdir()) == sorted([tagged, new])
    assert main(["gc", "--older-than", "30d", *out]) == 0
    assert [r["run_id"] for r in tracking.list_runs(outputs)] == [new]
    assert main(["gc", "--older-than", "thirty days", *out]) == 2
    assert "--older-than 'thirty days'" in capsys.readouterr().err


def test_a_leftover_removing_folder_is_collected(tmp_path: Path) -> None:
    outputs = tmp_path / "out"
    tiny_run(tmp_path, outputs)
    stray = outputs / "tiny" / "20200101T000000000-abcdef.removing"
    shutil.copytree(next((outputs / "tiny").iterdir()), stray)
    assert main(["gc", "--older-than", "1000d", "--outputs", str(outputs)]) == 0
    assert not stray.exists()
    assert len(tracking.list_runs(outputs)) == 1
