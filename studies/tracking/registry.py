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
(:mod:`studies.tracking.registry_file`). The functions here take a connection and run folders;
:class:`studies.tracking.store.RunStore` opens the connections and knows the outputs root.
"""

from __future__ import annotations

import sqlite3
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

from studies.common import labels
from studies.common.errors import EngineError
from studies.tracking.registry_file import (
    BUSY_TIMEOUT_S,
    REGISTRY,
    RegistryUnusable,
    damaged,
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


def create(con: sqlite3.Connection) -> None:
    """Make the tables of a new, empty registry at :data:`SCHEMA_VERSION`."""
    with writing(con):
        for statement in _TABLES:
            con.execute(statement)
        con.execute(f"PRAGMA user_version = {SCHEMA_VERSION}")


def bring_up_to_date(
    con: sqlite3.Connection, path: Path, locate: Callable[[Mapping[str, Any]], Path]
) -> None:
    """Migrate the registry file ``path`` to :data:`SCHEMA_VERSION` if it is older (under the
    write lock, so concurrent openers agree; ``locate``: a row's run folder, re-indexed) and
    check its tables. Raises :class:`RegistryUnusable` (or :class:`RegistryError`)."""
    if _version(con) != SCHEMA_VERSION:
        with writing(con):
            _migrate(con, locate)
    present = {r[0] for r in con.execute("SELECT name FROM sqlite_master WHERE type='table'")}
    missing = [t for t in TABLES if t not in present]
    if missing:
        raise damaged(path, f"table {', '.join(missing)} is missing")


def _version(con: sqlite3.Connection) -> int:
    return int(con.execute("PRAGMA user_version").fetchone()[0])


def _migrate(con: sqlite3.Connection, locate: Callable[[Mapping[str, Any]], Path]) -> None:
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
            store_values(con, row["run_id"], values_of(locate(dict(row)), row["status"]))
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


def upsert_run(con: sqlite3.Connection, row: dict[str, Any], folder: Path) -> None:
    """Insert or replace a run's row and re-index its values, in one transaction (the values
    are read from its run ``folder`` before the registry is locked)."""
    values = values_of(folder, row["status"])
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
    con: sqlite3.Connection, record: Mapping[str, Any], folder: Path, relative: str
) -> list[str]:
    """Register the run in ``folder`` (``record``: its run.json; ``relative``: the folder
    under the outputs root, ``<study>/<run-id>``) with its values, tags and notes
    (:mod:`studies.common.labels`), in one transaction. A tag that names another run already
    stays there; those tags are returned."""
    row = row_of(record, relative)
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


def delete_run(con: sqlite3.Connection, run_id: str) -> None:
    """Remove every row of a run (its tags and notes too), inside the caller's transaction."""
    for table in TABLES:
        con.execute(f"DELETE FROM {table} WHERE run_id = ?", (run_id,))
