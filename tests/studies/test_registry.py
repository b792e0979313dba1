"""The registry: schema version and migration, concurrent writers (registering, removing,
restoring and collecting at once), tags, notes, rm and gc."""

from __future__ import annotations

import datetime as dt
import errno
import json
import math
import multiprocessing
import os
import shutil
import sqlite3
import time
from contextlib import closing
from pathlib import Path

import pytest
from registry_writers import RUNS_EACH, register_many, run_id

from studies.cli import EXIT_OUTPUT_ERROR, main
from studies.common import labels
from studies.pipeline import run_study
from studies.tracking import registry, trash
from studies.tracking.store import RunStore

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
    values = {v["name"]: v for v in RunStore(outputs).run_values(run_id)}
    with closing(sqlite3.connect(outputs / registry.REGISTRY)) as con:
        assert con.execute("PRAGMA user_version").fetchone()[0] == registry.SCHEMA_VERSION
    # indexed in SI: 1000 rpm = 1000 · 2π/60 rad/s; the scene's units kept beside
    assert values["cam_speed"]["num"] == pytest.approx(1000.0 * 2 * math.pi / 60, rel=1e-15)
    assert (values["cam_speed"]["units"], values["cam_speed"]["declared_units"]) == (
        "rad/s",
        "rpm",
    )
    assert values["max_jerk.max"]["units"] == "m/rad^3"
    assert [r["run_id"] for r in RunStore(outputs).list_runs()] == [run_id]


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
    values = [v for v in RunStore(outputs).run_values(run_id) if v["name"] == "cam_speed"]
    (value,) = values  # 1000 rpm = 1000 · 2π/60 rad/s
    assert value["num"] == pytest.approx(1000.0 * 2 * math.pi / 60, rel=1e-15)
    assert value["units"] == "rad/s"
    assert RunStore(outputs).tagged_run("kept") == run_id
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


def test_a_run_store_brings_its_registry_up_to_date_once_and_closes_each_connection(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    # What RunStore's docstring promises: the migration and table check on the first
    # connection of an object only; every operation's connection closed after it (brute force:
    # count the calls and close every connection handed out, then look for one still open).
    checks: list[Path] = []
    check = registry.bring_up_to_date
    monkeypatch.setattr(registry, "bring_up_to_date", lambda *a: checks.append(a[1]) or check(*a))
    opened: list[sqlite3.Connection] = []
    connect = RunStore.connect
    monkeypatch.setattr(
        RunStore, "connect", lambda self: opened.append(connect(self)) or opened[-1]
    )
    store = RunStore(tmp_path)
    assert store.tags_and_notes() == ({}, {})
    assert store.tagged_run("nothing") is None
    assert store.run_values("20260101T000000000-abcdef") == []
    assert checks == [tmp_path / registry.REGISTRY]
    assert len(opened) == 3
    for con in opened:
        with pytest.raises(sqlite3.ProgrammingError, match="closed"):
            con.execute("SELECT 1")
    RunStore(tmp_path).tagged_run("nothing")  # a new object checks again
    assert len(checks) == 2


def test_four_processes_registering_removing_restoring_at_once_leave_it_consistent(
    tmp_path: Path,
) -> None:
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
        rows = dict(con.execute("SELECT run_id, status FROM runs").fetchall())
        tags = dict(con.execute("SELECT tag, run_id FROM tags").fetchall())
        indexed = {r[0] for r in con.execute("SELECT run_id FROM run_values")}
        noted = {r[0] for r in con.execute("SELECT run_id FROM notes")}
    folders = {p.parent.name for p in (tmp_path / "many").glob("*/run.json")}
    trashed = {e.run_id for e in RunStore(tmp_path).trash_entries()}
    # the registry indexes exactly the folders in place, none in the trash
    assert set(rows) == folders
    assert not folders & trashed
    assert set(rows.values()) == {"finished"}
    assert indexed <= folders
    every = [(w, i) for w in range(WRITERS) for i in range(RUNS_EACH)]
    assert {run_id(w, i) for w, i in every if i % 5 in (0, 3)} <= folders  # kept
    assert {run_id(w, i) for w, i in every if i % 5 == 1} <= trashed  # removed
    assert not {run_id(w, i) for w, i in every if i % 5 in (2, 4)} & trashed  # purge passes
    assert tags == {f"w{w}-{i}": run_id(w, i) for w, i in every if i % 5 == 3}
    assert noted == set(tags.values())
    for tag, run in tags.items():  # each folder holds its own tags and notes
        found = labels.read_labels(tmp_path / "many" / run)
        assert list(found.tags) == [tag]
        assert found.notes[0]["text"] == f"note of {tag}"


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
    assert RunStore(outputs).find_run("baseline")["run_id"] == second
    assert main(["export", "baseline", *out]) == 0
    assert main(["tag", first, "nothing", "--remove", *out]) == 2
    assert "no tag 'nothing'" in capsys.readouterr().err


def test_a_tag_moves_off_or_comes_off_a_run_whose_folder_was_deleted_by_hand(
    tmp_path: Path,
) -> None:
    """The tag of a run whose folder is gone moves to another run, or is removed, instead of
    refusing with "nothing to label" (the registry row alone still names it)."""
    outputs = tmp_path / "out"
    first = tiny_run(tmp_path, outputs, 1000.0)
    second = tiny_run(tmp_path, outputs, 1200.0)
    store = RunStore(outputs)
    store.set_tag(first, "baseline")
    store.set_tag(first, "old")
    folder = store.folder(store.find_run(first))
    shutil.rmtree(folder)
    assert store.set_tag(second, "baseline") == first
    assert store.tagged_run("baseline") == second
    assert store.remove_tag("old")
    assert store.tagged_run("old") is None


def tree(folder: Path) -> dict[str, bytes]:
    """Every file under ``folder`` and its bytes (with the modes, to compare bit for bit)."""
    return {
        f"{p.relative_to(folder)} {p.stat().st_mode:o}": p.read_bytes()
        for p in sorted(folder.rglob("*"))
        if p.is_file()
    }


def test_rm_of_a_tagged_run_needs_force_and_restore_brings_it_back_bit_identical(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    outputs = tmp_path / "out"
    run_id = tiny_run(tmp_path, outputs)
    folder = Path(RunStore(outputs).find_run(run_id)["folder"])
    out = ["--outputs", str(outputs)]
    assert main(["tag", run_id, "keepme", *out]) == 0
    assert main(["note", "keepme", "the review's run", *out]) == 0
    before = tree(folder)
    values = RunStore(outputs).run_values(run_id)
    assert main(["rm", "keepme", *out]) == 2
    assert "is tagged (keepme)" in capsys.readouterr().err
    assert tree(folder) == before
    assert main(["rm", "keepme", "--force", *out]) == 0
    assert "restore" in capsys.readouterr().out
    assert not folder.exists()
    assert RunStore(outputs).list_runs() == []
    assert RunStore(outputs).run_values(run_id) == []
    assert RunStore(outputs).tagged_run("keepme") is None
    assert main(["trash", *out]) == 0
    assert f"{run_id}" in capsys.readouterr().out
    assert main(["restore", "keepme", *out]) == 0  # a tag it had finds it in the trash
    assert tree(folder) == before
    assert RunStore(outputs).run_values(run_id) == values
    assert RunStore(outputs).tagged_run("keepme") == run_id
    _, notes = RunStore(outputs).tags_and_notes()
    assert notes[run_id][0].endswith("the review's run")
    assert RunStore(outputs).trash_entries() == []


def test_rm_keeps_the_folder_when_the_registry_cannot_change(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    outputs = tmp_path / "out"
    row = RunStore(outputs).find_run(tiny_run(tmp_path, outputs))
    monkeypatch.setattr("studies.tracking.registry_file.BUSY_TIMEOUT_S", 0.2)
    with closing(sqlite3.connect(outputs / registry.REGISTRY, isolation_level=None)) as other:
        other.execute("BEGIN IMMEDIATE")  # another writer holds the write lock; reads go on
        with pytest.raises(registry.RegistryUnusable, match="is locked by another process"):
            RunStore(outputs).remove(row)
        other.execute("ROLLBACK")
    assert (Path(row["folder"]) / "results.nc").exists()
    assert RunStore(outputs).find_run(row["run_id"]) is not None
    assert RunStore(outputs).trash_entries() == []


def refuse_to_move(monkeypatch: pytest.MonkeyPatch, folder: Path) -> None:
    """Make ``folder`` refuse to move, as a read-only folder does (the kernel refuses as it
    would a user; root is not refused)."""
    rename = Path.rename

    def read_only(self: Path, target: Path) -> Path:
        if self == folder:
            raise PermissionError(errno.EACCES, os.strerror(errno.EACCES), str(self))
        return rename(self, target)

    monkeypatch.setattr(Path, "rename", read_only)


def test_rm_of_a_run_whose_folder_cannot_move_is_one_line_and_leaves_nothing_in_the_trash(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    # An audit's case: a read-only run folder refused the move, but the trash folder made for
    # it was left behind, empty.
    outputs = tmp_path / "out"
    run_id = tiny_run(tmp_path, outputs)
    folder = Path(RunStore(outputs).find_run(run_id)["folder"])
    before = tree(folder)
    refuse_to_move(monkeypatch, folder)
    assert main(["rm", run_id, "--outputs", str(outputs)]) == EXIT_OUTPUT_ERROR
    err = capsys.readouterr().err
    assert err == (
        f"error: run {run_id}: {folder} cannot move into the trash (Permission denied); the "
        f"folder and {folder.parent} must be writable; nothing was removed\n"
    )
    assert tree(folder) == before
    assert RunStore(outputs).find_run(run_id) is not None
    assert [p.name for p in (outputs / trash.TRASH).rglob("*")] == []


def test_gc_moves_old_runs_to_the_trash_and_empties_it_by_age(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    outputs = tmp_path / "out"
    old, tagged, new = (tiny_run(tmp_path, outputs, s) for s in (1000.0, 1100.0, 1200.0))
    RunStore(outputs).set_tag(tagged, "baseline")
    long_ago = (dt.datetime.now(dt.UTC) - dt.timedelta(days=40)).isoformat(timespec="seconds")
    with closing(RunStore(outputs).connect()) as con, con:
        con.execute("UPDATE runs SET started = ? WHERE run_id IN (?, ?)", (long_ago, old, tagged))
    out = ["--outputs", str(outputs)]
    assert main(["gc", "--older-than", "30d", "--keep-tagged", "--dry-run", *out]) == 0
    assert f"would move {old}" in capsys.readouterr().out
    assert len(RunStore(outputs).list_runs()) == 3
    assert main(["gc", "--older-than", "30d", "--keep-tagged", *out]) == 0
    assert {r["run_id"] for r in RunStore(outputs).list_runs()} == {tagged, new}
    assert sorted(p.name for p in (outputs / "tiny").iterdir()) == sorted([tagged, new])
    assert [e.run_id for e in RunStore(outputs).trash_entries()] == [old]
    assert main(["gc", "--older-than", "30d", *out]) == 0  # trashed just now: kept 30 days
    assert [r["run_id"] for r in RunStore(outputs).list_runs()] == [new]
    assert {e.run_id for e in RunStore(outputs).trash_entries()} == {old, tagged}
    assert main(["gc", "--older-than", "0s", "--dry-run", *out]) == 0
    assert "would delete 2 from it" in capsys.readouterr().out
    assert main(["gc", "--older-than", "0s", *out]) == 0
    assert {e.run_id for e in RunStore(outputs).trash_entries()} == {new}  # the last one moved in
    assert main(["gc", "--older-than", "thirty days", *out]) == 2
    assert "--older-than 'thirty days'" in capsys.readouterr().err
    assert main(["gc", "--older-than", "99999999999w", "--dry-run", *out]) == 2  # > 1000 years


def test_gc_moves_every_run_it_can_and_names_the_one_it_cannot(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    # gc stopped at the first run whose folder could not move (read-only): the runs after it
    # stayed, the trash was not emptied, and the runs it had moved were not listed.
    outputs = tmp_path / "out"
    first, stuck, last = (tiny_run(tmp_path, outputs, s) for s in (1000.0, 1100.0, 1200.0))
    out = ["--outputs", str(outputs)]
    expired = tiny_run(tmp_path, outputs, 1300.0)
    assert main(["rm", expired, *out]) == 0
    folder = Path(RunStore(outputs).find_run(stuck)["folder"])
    before = tree(folder)
    refuse_to_move(monkeypatch, folder)
    capsys.readouterr()
    assert main(["gc", "--older-than", "0s", *out]) == EXIT_OUTPUT_ERROR
    said = capsys.readouterr()
    assert f"moved {first}" in said.out
    assert f"moved {last}" in said.out
    assert "moved 2 run(s) to the trash, deleted 1 from it" in said.out
    assert said.err == (
        f"error: run {stuck}: {folder} cannot move into the trash (Permission denied); the "
        f"folder and {folder.parent} must be writable; nothing was removed\n"
    )
    assert [r["run_id"] for r in RunStore(outputs).list_runs()] == [stuck]
    assert tree(folder) == before
    assert {e.run_id for e in RunStore(outputs).trash_entries()} == {first, last}


def test_gc_keep_tagged_never_deletes_a_tagged_run_from_the_trash(tmp_path: Path) -> None:
    # An audit's case: a tagged run removed with rm (tags travel into the trash) was deleted
    # for good by `gc --keep-tagged`, whose help says it never removes a tagged run.
    outputs = tmp_path / "out"
    tagged, plain = (tiny_run(tmp_path, outputs, s) for s in (1000.0, 1100.0))
    RunStore(outputs).set_tag(tagged, "baseline")
    out = ["--outputs", str(outputs)]
    assert main(["rm", tagged, "--force", *out]) == 0
    assert main(["rm", plain, "--force", *out]) == 0
    assert main(["gc", "--older-than", "0s", "--keep-tagged", *out]) == 0
    assert [e.run_id for e in RunStore(outputs).trash_entries()] == [tagged]
    assert main(["restore", "baseline", *out]) == 0
    assert RunStore(outputs).find_run(tagged) is not None


def test_gc_collects_what_killed_processes_left_and_nothing_else(tmp_path: Path) -> None:
    outputs = tmp_path / "out"
    tiny_run(tmp_path, outputs)
    stray = outputs / "tiny" / "20200101T000000000-abcdef.removing"  # an older version's rm
    shutil.copytree(next((outputs / "tiny").iterdir()), stray)
    stillborn = outputs / "tiny" / "20200101T000000001-abcdef"  # killed before its run.json
    starting = outputs / "tiny" / "20200101T000000002-abcdef"  # a run starting right now
    for folder in (stillborn, starting):
        folder.mkdir()
        (folder / "study.toml").write_text(STUDY, encoding="utf-8")
    hour_ago = time.time() - 3600
    os.utime(stillborn, (hour_ago, hour_ago))
    purging = outputs / trash.TRASH / "20200101T000000000000" / "tiny" / f"x{trash.PURGING}"
    purging.mkdir(parents=True)  # a purge that was killed
    assert main(["gc", "--older-than", "1000d", "--outputs", str(outputs)]) == 0
    assert not stray.exists()
    assert not stillborn.exists()
    assert starting.exists()
    assert not (outputs / trash.TRASH / "20200101T000000000000").exists()
    assert len(RunStore(outputs).list_runs()) == 1
