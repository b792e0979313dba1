"""A damaged, locked, read-only or full registry: every command answers in one line with exit
code 4 and the way out, writes no unregistered run folder, and loses nothing — ``reindex``
rebuilds the registry from the run folders with every run, tag and note."""

from __future__ import annotations

import hashlib
import os
import shutil
import sqlite3
import subprocess
import sys
from collections.abc import Callable, Iterator
from contextlib import closing
from pathlib import Path

import pytest

from studies.cli import main
from studies.pipeline import run_study
from studies.tracking import records, registry, registry_file
from studies.tracking.store import RunStore

STUDY = """
name = "tiny"
scene = "cam"
responses = ["max_jerk"]
design = "full_factorial"
[parameters]
cam_speed = 1000.0
[factors.base_radius]
levels = [16.0, 18.0]
"""
PAGE = 4096  # SQLite's default page size
HOLD_LOCK = """
import sqlite3, sys, time
con = sqlite3.connect(sys.argv[1], isolation_level=None)
con.execute("BEGIN EXCLUSIVE")
print("locked", flush=True)
time.sleep(120)
"""


@pytest.fixture(scope="module")
def recorded(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path, list[str]]:
    """An outputs tree with two finished runs, the first tagged ``baseline`` and noted."""
    base = tmp_path_factory.mktemp("recorded")
    study = base / "tiny.toml"
    study.write_text(STUDY, encoding="utf-8")
    outputs = base / "out"
    ids = [run_study(study, outputs=outputs, progress=False).record.run_id for _ in range(2)]
    RunStore(outputs).set_tag(ids[0], "baseline")
    RunStore(outputs).add_note(ids[0], records.now(), "the design review's run")
    return study, outputs, ids


def fingerprint(outputs: Path) -> dict[str, str]:
    """Every file of every run folder and its SHA-256 (what must never be lost)."""
    return {
        str(p.relative_to(outputs)): hashlib.sha256(p.read_bytes()).hexdigest()
        for p in sorted((outputs / "tiny").rglob("*"))
        if p.is_file()
    }


def rewrite(path: Path, change: Callable[[bytes], bytes]) -> None:
    path.write_bytes(change(path.read_bytes()))


def drop_tags_table(path: Path) -> None:
    with closing(sqlite3.connect(path)) as con, con:
        con.execute("DROP TABLE tags")


def become_directory(path: Path) -> None:
    path.unlink()
    path.mkdir()
    (path / "what.txt").write_text("a directory where the registry was")


# each: how the registry file is damaged (the reproductions of issue 25)
DAMAGE: dict[str, Callable[[Path], None]] = {
    "truncated": lambda p: rewrite(p, lambda b: b[: len(b) // 2]),
    "random bytes": lambda p: rewrite(p, lambda b: os.urandom(len(b))),
    "header then garbage": lambda p: rewrite(p, lambda b: b[:100] + os.urandom(len(b) - 100)),
    "corrupt page": lambda p: rewrite(p, lambda b: b[:PAGE] + os.urandom(PAGE) + b[2 * PAGE :]),
    "a directory": become_directory,
    "dropped table": drop_tags_table,
    "0 bytes": lambda p: p.write_bytes(b""),
}


def one_line(err: str) -> str:
    assert "Traceback" not in err
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    return lines[0]


def commands(study: Path, ids: list[str]) -> list[list[str]]:
    return [
        ["runs"],
        ["show", "baseline"],
        ["tag", ids[1], "candidate"],
        ["note", ids[1], "a note"],
        ["rm", ids[1]],
        ["run", str(study), "--force", "--no-progress"],
    ]


@pytest.fixture
def outputs(recorded: tuple[Path, Path, list[str]], tmp_path: Path) -> Path:
    copy = tmp_path / "out"
    shutil.copytree(recorded[1], copy)
    return copy


@pytest.mark.parametrize("kind", list(DAMAGE))
def test_a_damaged_registry_gives_one_line_and_reindex_loses_nothing(
    kind: str,
    recorded: tuple[Path, Path, list[str]],
    outputs: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    study, _, ids = recorded
    before = fingerprint(outputs)
    DAMAGE[kind](outputs / registry.REGISTRY)
    out = ["--outputs", str(outputs)]
    for command in commands(study, ids):
        assert main([*command, *out]) == 4, command
        line = one_line(capsys.readouterr().err)
        assert "is damaged" in line
        assert f"python -m studies reindex --outputs {outputs}" in line
    assert fingerprint(outputs) == before  # no run folder changed, none added
    assert main(["reindex", *out]) == 0
    said = capsys.readouterr().out
    assert "reindexed 2 run(s), 1 tag(s) and 1 note(s)" in said
    assert "the old registry is kept as" in said  # moved aside, never deleted
    rows = {r["run_id"]: r for r in RunStore(outputs).list_runs()}
    assert set(rows) == set(ids)
    assert {r["status"] for r in rows.values()} == {"finished"}
    assert RunStore(outputs).find_run("baseline")["run_id"] == ids[0]
    _, notes = RunStore(outputs).tags_and_notes()
    assert notes[ids[0]][0].endswith("the design review's run")
    assert {v["name"] for v in RunStore(outputs).run_values(ids[1])} >= {"max_jerk.max"}
    assert fingerprint(outputs) == before


@pytest.fixture
def locked(outputs: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[None]:
    """Another process holds the registry's exclusive lock; commands wait 0.3 s for it."""
    monkeypatch.setattr(registry_file, "BUSY_TIMEOUT_S", 0.3)
    holder = subprocess.Popen(
        [sys.executable, "-c", HOLD_LOCK, str(outputs / registry.REGISTRY)],
        stdout=subprocess.PIPE, text=True,
    )  # fmt: skip
    assert holder.stdout is not None
    assert holder.stdout.readline().strip() == "locked"
    yield
    holder.kill()
    holder.wait()
    holder.stdout.close()


def read_only(path: Path) -> sqlite3.Connection:
    """A connection as SQLite opens a file it may not write (tests run as root, whom file
    modes do not stop, so the file is opened read-only the way SQLite does for such a file)."""
    con = sqlite3.connect(f"{path.as_uri()}?mode=ro", uri=True, isolation_level=None)
    con.row_factory = sqlite3.Row
    return con


@pytest.mark.usefixtures("locked")
def test_a_locked_registry_waits_a_bounded_time_then_says_so(
    recorded: tuple[Path, Path, list[str]], outputs: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    study, _, ids = recorded
    before = fingerprint(outputs)
    for command in commands(study, ids):
        assert main([*command, "--outputs", str(outputs)]) == 4, command
        line = one_line(capsys.readouterr().err)
        assert "is locked by another process (waited 0.3 s)" in line
    assert fingerprint(outputs) == before
    # reindex too (an audit: it moved the locked file and its journal aside after 7 s, under
    # the other process's open transaction, and said it had reindexed)
    assert main(["reindex", "--outputs", str(outputs)]) == 4
    assert "is locked by another process (waited 0.3 s)" in one_line(capsys.readouterr().err)
    assert sorted(p.name for p in outputs.glob(f"{registry.REGISTRY}*")) == [registry.REGISTRY]


def test_a_read_only_registry_is_read_and_refuses_writes_in_one_line(
    recorded: tuple[Path, Path, list[str]],
    outputs: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    study, _, ids = recorded
    before = fingerprint(outputs)
    monkeypatch.setattr(registry_file, "_open", read_only)
    out = ["--outputs", str(outputs)]
    assert main(["runs", *out]) == 0
    listed = capsys.readouterr().out
    assert all(i in listed for i in ids)
    for command in commands(study, ids)[2:]:
        assert main([*command, *out]) == 4, command
        assert "is read-only" in one_line(capsys.readouterr().err)
    assert fingerprint(outputs) == before  # labels.json put back, no run folder left


def test_a_full_disk_under_the_registry_gives_one_line(
    recorded: tuple[Path, Path, list[str]], outputs: Path
) -> None:
    """A process that may write no file beyond 4 KiB (RLIMIT_FSIZE, as a full disk refuses to
    grow any file) cannot write the registry's journal: each write command fails cleanly."""
    study, _, ids = recorded
    before = fingerprint(outputs)
    limit = "import resource; resource.setrlimit(resource.RLIMIT_FSIZE, (4096, 4096))"
    for command in commands(study, ids)[2:5]:
        done = subprocess.run(
            [sys.executable, "-c",
             f"{limit}\nfrom studies.cli import main\nraise SystemExit(main())",
             *command, "--outputs", str(outputs)],
            check=False, capture_output=True, text=True, timeout=300,
        )  # fmt: skip
        assert done.returncode == 4, (command, done.stderr)
        line = one_line(done.stderr)
        assert "could not be written" in line
    assert fingerprint(outputs) == before
    assert {r["run_id"] for r in RunStore(outputs).list_runs()} == set(ids)


def test_sqlite_full_is_said_as_a_full_disk(tmp_path: Path) -> None:
    with closing(sqlite3.connect(tmp_path / "r.sqlite", isolation_level=None)) as con:
        con.execute("CREATE TABLE t (x TEXT)")
        pages = con.execute("PRAGMA page_count").fetchone()[0]
        con.execute(f"PRAGMA max_page_count = {pages}")  # SQLite's own full-disk answer
        with pytest.raises(sqlite3.OperationalError) as full:
            con.executemany("INSERT INTO t VALUES (?)", [("x" * 1000,)] * 100)
    said = str(registry_file.unusable(full.value, tmp_path / registry_file.REGISTRY))
    assert "is full; nothing was changed: free some space" in said


def test_a_deleted_registry_is_rebuilt_on_sight(
    recorded: tuple[Path, Path, list[str]], outputs: Path
) -> None:
    _, _, ids = recorded
    (outputs / registry.REGISTRY).unlink()
    assert {r["run_id"] for r in RunStore(outputs).list_runs()} == set(ids)
    assert RunStore(outputs).find_run("baseline")["run_id"] == ids[0]  # from labels.json
