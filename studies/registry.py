"""The run registry ``outputs/registry.sqlite``: its schema, versions and queryable values.

Tables (schema version 3, in ``PRAGMA user_version``):

    runs        one row per run: id, study, scene, design, status, commit, timings, folder,
                the cache key (definition_sha256 and code_sha256)
    run_values  per run, one row per fixed parameter, parameter at its default, setting,
                factor level and response summary (``<response>.min|mean|max``): kind, name,
                value as text and as number in SI, its SI unit and the unit the scene declares
                (:mod:`studies.run_values`); what ``runs --where`` filters on
    tags        tag → run id (a tag names one run; tagging another run moves it)
    notes       free-text notes on a run, timestamped

Older registries are migrated in place the first time they are opened: version 1 (the
``runs`` table alone, user_version 0) gets the new tables, version 2 the new columns, and both
are indexed again from each run's folder (version 2 held values in the file's units). Every
write is one transaction; connections wait up to :data:`BUSY_TIMEOUT_S` for a lock, so several
processes may register runs into one registry at once.
"""

from __future__ import annotations

import sqlite3
from contextlib import closing
from pathlib import Path
from typing import Any

from studies.run_values import SUMMARIES, Value, values_of

REGISTRY = "registry.sqlite"
SCHEMA_VERSION = 3
BUSY_TIMEOUT_S = 60.0
__all__ = ["SUMMARIES", "Value", "values_of"]
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


class RegistryError(ValueError):
    """A registry this version cannot use (written by a newer version, damaged)."""


def connect(outputs: Path) -> sqlite3.Connection:
    """A connection to the registry under ``outputs``, created or migrated to
    :data:`SCHEMA_VERSION` first (under an exclusive lock, so concurrent openers agree)."""
    outputs.mkdir(parents=True, exist_ok=True)
    con = sqlite3.connect(outputs / REGISTRY, timeout=BUSY_TIMEOUT_S, isolation_level=None)
    con.row_factory = sqlite3.Row
    try:
        if _version(con) != SCHEMA_VERSION:
            con.execute("BEGIN IMMEDIATE")
            try:
                _migrate(con)
            except BaseException:
                con.execute("ROLLBACK")
                raise
            con.execute("COMMIT")
    except BaseException:
        con.close()
        raise
    con.isolation_level = "DEFERRED"  # from here on: `with con:` is one transaction
    return con


def _version(con: sqlite3.Connection) -> int:
    return int(con.execute("PRAGMA user_version").fetchone()[0])


def _migrate(con: sqlite3.Connection) -> None:
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
        for row in con.execute("SELECT run_id, status, folder FROM runs").fetchall():
            store_values(con, row["run_id"], values_of(Path(row["folder"]), row["status"]))
    con.execute(f"PRAGMA user_version = {SCHEMA_VERSION}")


def upsert_run(con: sqlite3.Connection, row: dict[str, Any]) -> None:
    """Insert or replace a run's row and re-index its values, in one transaction (the values
    are read from the run folder before the registry is locked)."""
    values = values_of(Path(row["folder"]), row["status"])
    with con:
        placeholders = ", ".join("?" for _ in COLUMNS)
        con.execute(
            f"INSERT OR REPLACE INTO runs ({', '.join(COLUMNS)}) VALUES ({placeholders})",
            [row.get(c) for c in COLUMNS],
        )
        store_values(con, row["run_id"], values)


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
    with closing(connect(outputs)) as con:
        rows = con.execute(
            "SELECT kind, name, text, num, units, declared_units FROM run_values WHERE run_id = ? "
            "ORDER BY kind, name, num",
            (run_id,),
        )
        return [dict(r) for r in rows]


def set_tag(outputs: Path, run_id: str, tag: str) -> str | None:
    """Tag a run; return the run the tag named before (it moves), if another."""
    with closing(connect(outputs)) as con, con:
        before = con.execute("SELECT run_id FROM tags WHERE tag = ?", (tag,)).fetchone()
        con.execute("INSERT OR REPLACE INTO tags (tag, run_id) VALUES (?, ?)", (tag, run_id))
    return before["run_id"] if before and before["run_id"] != run_id else None


def remove_tag(outputs: Path, tag: str) -> bool:
    with closing(connect(outputs)) as con, con:
        return con.execute("DELETE FROM tags WHERE tag = ?", (tag,)).rowcount > 0


def add_note(outputs: Path, run_id: str, written: str, text: str) -> None:
    with closing(connect(outputs)) as con, con:
        con.execute("INSERT INTO notes VALUES (?, ?, ?)", (run_id, written, text))


def tags_and_notes(outputs: Path) -> tuple[dict[str, list[str]], dict[str, list[str]]]:
    """Run id → its tags, and run id → its notes ("<time> <text>"), oldest first."""
    tags: dict[str, list[str]] = {}
    notes: dict[str, list[str]] = {}
    with closing(connect(outputs)) as con:
        for r in con.execute("SELECT tag, run_id FROM tags ORDER BY tag"):
            tags.setdefault(r["run_id"], []).append(r["tag"])
        for r in con.execute("SELECT run_id, written, text FROM notes ORDER BY written"):
            notes.setdefault(r["run_id"], []).append(f"{r['written']} {r['text']}")
    return tags, notes


def tagged_run(outputs: Path, tag: str) -> str | None:
    with closing(connect(outputs)) as con:
        row = con.execute("SELECT run_id FROM tags WHERE tag = ?", (tag,)).fetchone()
    return row["run_id"] if row else None


def delete_run(con: sqlite3.Connection, run_id: str) -> None:
    """Remove every row of a run (its tags and notes too), inside the caller's transaction."""
    for table in ("runs", "run_values", "tags", "notes"):
        con.execute(f"DELETE FROM {table} WHERE run_id = ?", (run_id,))
