"""The run registry ``outputs/registry.sqlite``: its schema, versions and queryable values.

Tables (schema version 3, in ``PRAGMA user_version``):

    runs        one row per run: id, study, scene, design, status, commit, timings, folder,
                the cache key (definition_sha256 and code_sha256)
    run_values  per run, one row per fixed parameter, parameter at its default, setting,
                factor level and response summary (``<response>.min|mean|max``): kind, name,
                value as text and as number in SI, its SI unit and the unit the scene declares
                (:mod:`studies.tracking.run_values`); what ``runs --where`` filters on
    tags        tag → run id (a tag names one run; tagging another run moves it)
    notes       free-text notes on a run, timestamped

The registry is an index, never the truth: each run's folder holds its record (``run.json``),
definition, results and labels (:mod:`studies.common.labels`), and ``studies reindex`` rebuilds the
registry from them. A run's folder is stored relative to the outputs root (``<study>/<run-id>``)
and resolved against the root the registry was found in, so a copied outputs tree addresses
its own folders. Older registries are migrated in place the first time they are opened:
version 1 (the ``runs`` table alone, user_version 0) gets the new tables, version 2 the new
columns, and both are indexed again from each run's folder (version 2 held values in the
file's units). Every write is one transaction; connections wait up to :data:`BUSY_TIMEOUT_S`
for a lock, so several processes may register runs into one registry at once. Any failure of
the file (damaged, locked, read-only, full) is :class:`RegistryUnusable`, in one line
(:mod:`studies.tracking.registry_file`).
"""

from __future__ import annotations

import datetime as dt
import sqlite3
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from studies.common import labels
from studies.common.errors import EngineError, RunStateError
from studies.tracking.registry_file import (
    BUSY_TIMEOUT_S,
    REGISTRY,
    RegistryUnusable,
    damaged,
    open_file,
    unusable,
    writing,
)
from studies.tracking.run_values import SUMMARIES, Value, values_of

__all__ = ["BUSY_TIMEOUT_S", "REGISTRY", "SUMMARIES", "RegistryUnusable", "Value", "values_of"]
SCHEMA_VERSION = 3
COLUMNS = (
    "run_id",
    "study",
    "scene",
    "design",
    "runs",
    "status",
    "started",
    "finished",
    "git_commit",
    "git_dirty",
    "compile_s",
    "run_s",
    "folder",
    "definition_sha256",
    "code_sha256",
)
_TABLES = (
    (
        "CREATE TABLE IF NOT EXISTS runs (run_id TEXT PRIMARY KEY, study TEXT, scene TEXT, "
        "design TEXT, runs INTEGER, status TEXT, started TEXT, finished TEXT, git_commit TEXT, "
        "git_dirty INTEGER, compile_s REAL, run_s REAL, folder TEXT, definition_sha256 TEXT, "
        "code_sha256 TEXT)"
    ),
    (
        "CREATE TABLE IF NOT EXISTS run_values (run_id TEXT NOT NULL, kind TEXT NOT NULL, "
        "name TEXT NOT NULL, text TEXT, num REAL, units TEXT, declared_units TEXT)"
    ),
    "CREATE INDEX IF NOT EXISTS run_values_by_run ON run_values (run_id)",
    "CREATE INDEX IF NOT EXISTS run_values_by_name ON run_values (name, num)",
    "CREATE TABLE IF NOT EXISTS tags (tag TEXT PRIMARY KEY, run_id TEXT NOT NULL)",
    "CREATE TABLE IF NOT EXISTS notes (run_id TEXT NOT NULL, written TEXT, text TEXT)",
)
TABLES = ("runs", "run_values", "tags", "notes")


class RegistryError(EngineError, ValueError):
    """A registry this version cannot use: written by a newer version of the package."""


def connect(outputs: Path) -> sqlite3.Connection:
    """A connection to the registry under ``outputs``, created whole or migrated to
    :data:`SCHEMA_VERSION` first (under the write lock, so concurrent openers agree); its
    tables checked. Raises :class:`RegistryUnusable` (or :class:`RegistryError`)."""
    con = open_file(outputs, _create)
    try:
        if _version(con) != SCHEMA_VERSION:
            with writing(con):
                _migrate(con, outputs)
        present = {r[0] for r in con.execute("SELECT name FROM sqlite_master WHERE type='table'")}
        missing = [t for t in TABLES if t not in present]
        if missing:
            raise damaged(outputs, f"table {', '.join(missing)} is missing")
    except sqlite3.Error as exc:
        con.close()
        raise unusable(exc, outputs) from None
    except BaseException:
        con.close()
        raise
    con.isolation_level = "DEFERRED"  # from here on: `with con:` is one transaction
    return con


@contextmanager
def connection(outputs: Path) -> Iterator[sqlite3.Connection]:
    """:func:`connect`, closed after the block; any SQLite error in the block becomes
    :class:`RegistryUnusable`."""
    con = connect(outputs)
    try:
        yield con
    except sqlite3.Error as exc:
        raise unusable(exc, outputs) from None
    finally:
        con.close()


def _create(con: sqlite3.Connection) -> None:
    with writing(con):
        for statement in _TABLES:
            con.execute(statement)
        con.execute(f"PRAGMA user_version = {SCHEMA_VERSION}")


def _version(con: sqlite3.Connection) -> int:
    return int(con.execute("PRAGMA user_version").fetchone()[0])


def _migrate(con: sqlite3.Connection, outputs: Path) -> None:
    version = _version(con)  # read again under the lock: another process may have migrated
    if version > SCHEMA_VERSION:
        msg = (
            f"the registry has schema version {version}, newer than this version of the "
            f"package understands ({SCHEMA_VERSION}): upgrade engine-studies"
        )
        raise RegistryError(msg)
    if version == SCHEMA_VERSION:
        return
    had_runs = bool(
        con.execute("SELECT 1 FROM sqlite_master WHERE type='table' AND name='runs'").fetchone()
    )
    for statement in _TABLES:
        con.execute(statement)
    for table, column in (("runs", "code_sha256"), ("run_values", "declared_units")):
        present = {r["name"] for r in con.execute(f"PRAGMA table_info({table})")}
        if column not in present:  # versions 1 and 2
            con.execute(f"ALTER TABLE {table} ADD COLUMN {column} TEXT")
    if had_runs:  # versions 1 and 2: index what each run's folder holds, in SI
        for row in con.execute("SELECT * FROM runs").fetchall():
            values = values_of(folder_of(outputs, dict(row)), row["status"])
            store_values(con, row["run_id"], values)
    con.execute(f"PRAGMA user_version = {SCHEMA_VERSION}")


def row_of(record: Mapping[str, Any], folder: str) -> dict[str, Any]:
    """The registry row of a run record (what ``run.json`` holds); ``folder`` relative to the
    outputs root (``<study>/<run-id>``)."""
    timings = record.get("timings") or {}
    row = {c: record.get(c) for c in COLUMNS}
    row |= {
        "git_dirty": int(bool(record.get("git_dirty"))),
        "compile_s": timings.get("compile_s"),
        "run_s": timings.get("run_s"),
        "folder": folder,
    }
    return row


def folder_of(outputs: Path, row: Mapping[str, Any]) -> Path:
    """A row's run folder under the outputs root it was found in (rows written before folders
    were stored relative hold an absolute path, which is not followed: it may be another root's)."""
    stored = Path(row.get("folder") or "")
    if stored.parts and not stored.is_absolute():
        return outputs / stored
    return outputs / str(row["study"]) / str(row["run_id"])


def upsert_run(con: sqlite3.Connection, row: dict[str, Any], outputs: Path) -> None:
    """Insert or replace a run's row and re-index its values, in one transaction (the values
    are read from the run folder before the registry is locked)."""
    values = values_of(folder_of(outputs, row), row["status"])
    with writing(con):
        _upsert(con, row, values)


def _upsert(con: sqlite3.Connection, row: dict[str, Any], values: list[Value]) -> None:
    placeholders = ", ".join("?" for _ in COLUMNS)
    con.execute(
        f"INSERT OR REPLACE INTO runs ({', '.join(COLUMNS)}) VALUES ({placeholders})",
        [row.get(c) for c in COLUMNS],
    )
    store_values(con, row["run_id"], values)


def index_folder(
    con: sqlite3.Connection, outputs: Path, record: Mapping[str, Any], folder: Path
) -> list[str]:
    """Register the run in ``folder`` (``record``: its run.json) with its values, tags and
    notes (:mod:`studies.common.labels`), in one transaction. A tag that names another run already
    stays there; those tags are returned."""
    row = row_of(record, folder.relative_to(outputs).as_posix())
    values = values_of(folder, row["status"])
    found = labels.read_labels(folder)
    run_id = row["run_id"]
    with writing(con):
        _upsert(con, row, values)
        held = {
            tag: r[0]
            for tag in found.tags
            if (r := con.execute("SELECT run_id FROM tags WHERE tag = ?", (tag,)).fetchone())
        }
        lost = [t for t in found.tags if held.get(t, run_id) != run_id]
        con.executemany(
            "INSERT OR REPLACE INTO tags (tag, run_id) VALUES (?, ?)",
            [(t, run_id) for t in found.tags if t not in lost],
        )
        if not con.execute("SELECT 1 FROM notes WHERE run_id = ?", (run_id,)).fetchone():
            con.executemany(
                "INSERT INTO notes VALUES (?, ?, ?)",
                [(run_id, n["written"], n["text"]) for n in found.notes],
            )
    return lost


def store_values(con: sqlite3.Connection, run_id: str, rows: list[Value]) -> None:
    """Replace the run's indexed values by ``rows``."""
    con.execute("DELETE FROM run_values WHERE run_id = ?", (run_id,))
    con.executemany(
        "INSERT INTO run_values (run_id, kind, name, text, num, units, declared_units) "
        "VALUES (?, ?, ?, ?, ?, ?, ?)",
        [(run_id, *r) for r in rows],
    )


def run_values(outputs: Path, run_id: str) -> list[dict[str, Any]]:
    """The indexed values of one run (kind, name, text, num in SI, units: the SI unit,
    declared_units: the scene's)."""
    with connection(outputs) as con:
        rows = con.execute(
            "SELECT kind, name, text, num, units, declared_units FROM run_values WHERE run_id = ? "
            "ORDER BY kind, name, num",
            (run_id,),
        )
        return [dict(r) for r in rows]


def _folder(con: sqlite3.Connection, outputs: Path, run_id: str) -> Path:
    """The folder of a registered run (FileNotFoundError when it is gone)."""
    row = con.execute("SELECT * FROM runs WHERE run_id = ?", (run_id,)).fetchone()
    folder = folder_of(outputs, dict(row)) if row else None
    if folder is None or not folder.is_dir():
        raise RunStateError(f"run {run_id} has no folder under {outputs}: nothing to label")
    return folder


def set_tag(outputs: Path, run_id: str, tag: str) -> str | None:
    """Tag a run, in its folder and the registry; return the run the tag named before (it
    moves), if another. ValueError for a tag that could be taken for a run id."""
    labels.check_tag(tag)
    when = dt.datetime.now(dt.UTC).isoformat(timespec="milliseconds")
    with connection(outputs) as con, labels.Undo() as undo, writing(con):
        folder = _folder(con, outputs, run_id)
        before = con.execute("SELECT run_id FROM tags WHERE tag = ?", (tag,)).fetchone()
        moved = before["run_id"] if before and before["run_id"] != run_id else None
        undo.save(folder)
        labels.add_tag(folder, tag, when)
        if moved is not None:
            try:
                previous = _folder(con, outputs, moved)
            except FileNotFoundError:
                previous = None  # the other run's folder is gone: only its row names the tag
            if previous is not None:
                undo.save(previous)
                labels.drop_tag(previous, tag)
        con.execute("INSERT OR REPLACE INTO tags (tag, run_id) VALUES (?, ?)", (tag, run_id))
    return moved


def remove_tag(outputs: Path, tag: str) -> bool:
    with connection(outputs) as con, labels.Undo() as undo, writing(con):
        before = con.execute("SELECT run_id FROM tags WHERE tag = ?", (tag,)).fetchone()
        if before is None:
            return False
        try:
            folder = _folder(con, outputs, before["run_id"])
        except FileNotFoundError:
            folder = None
        if folder is not None:
            undo.save(folder)
            labels.drop_tag(folder, tag)
        con.execute("DELETE FROM tags WHERE tag = ?", (tag,))
        return True


def add_note(outputs: Path, run_id: str, written: str, text: str) -> None:
    with connection(outputs) as con, labels.Undo() as undo, writing(con):
        folder = _folder(con, outputs, run_id)
        undo.save(folder)
        labels.add_note(folder, written, text)
        con.execute("INSERT INTO notes VALUES (?, ?, ?)", (run_id, written, text))


def tags_and_notes(outputs: Path) -> tuple[dict[str, list[str]], dict[str, list[str]]]:
    """Run id → its tags, and run id → its notes ("<time> <text>"), oldest first."""
    tags: dict[str, list[str]] = {}
    notes: dict[str, list[str]] = {}
    with connection(outputs) as con:
        for r in con.execute("SELECT tag, run_id FROM tags ORDER BY tag"):
            tags.setdefault(r["run_id"], []).append(r["tag"])
        for r in con.execute("SELECT run_id, written, text FROM notes ORDER BY written"):
            notes.setdefault(r["run_id"], []).append(f"{r['written']} {r['text']}")
    return tags, notes


def tagged_run(outputs: Path, tag: str) -> str | None:
    with connection(outputs) as con:
        row = con.execute("SELECT run_id FROM tags WHERE tag = ?", (tag,)).fetchone()
    return row["run_id"] if row else None


def delete_run(con: sqlite3.Connection, run_id: str) -> None:
    """Remove every row of a run (its tags and notes too), inside the caller's transaction."""
    for table in TABLES:
        con.execute(f"DELETE FROM {table} WHERE run_id = ?", (run_id,))
