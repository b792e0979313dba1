"""The run registry ``outputs/registry.sqlite``: its schema, versions and queryable values.

Tables (schema version 2, in ``PRAGMA user_version``):

    runs        one row per run: id, study, scene, design, status, commit, timings, folder
    run_values  per run, one row per fixed parameter, setting, factor level and response
                summary (``<response>.min|mean|max``): kind, name, value as text and as number,
                units; what ``runs --where`` filters on
    tags        tag → run id (a tag names one run; tagging another run moves it)
    notes       free-text notes on a run, timestamped

Version 1 registries (the ``runs`` table alone, user_version 0) are migrated in place the first
time they are opened: the new tables are created and filled from each run's folder. Every
write is one transaction; connections wait up to :data:`BUSY_TIMEOUT_S` for a lock, so several
processes may register runs into one registry at once.
"""

from __future__ import annotations

import json
import math
import sqlite3
import tomllib
from contextlib import closing
from pathlib import Path
from typing import Any

import numpy as np

from studies.definition import parse_study
from studies.results import open_results

REGISTRY = "registry.sqlite"
SCHEMA_VERSION = 2
BUSY_TIMEOUT_S = 60.0
SUMMARIES = ("min", "mean", "max")
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
)
_TABLES = (
    (
        "CREATE TABLE IF NOT EXISTS runs (run_id TEXT PRIMARY KEY, study TEXT, scene TEXT, "
        "design TEXT, runs INTEGER, status TEXT, started TEXT, finished TEXT, git_commit TEXT, "
        "git_dirty INTEGER, compile_s REAL, run_s REAL, folder TEXT, definition_sha256 TEXT)"
    ),
    (
        "CREATE TABLE IF NOT EXISTS run_values (run_id TEXT NOT NULL, kind TEXT NOT NULL, "
        "name TEXT NOT NULL, text TEXT, num REAL, units TEXT)"
    ),
    "CREATE INDEX IF NOT EXISTS run_values_by_run ON run_values (run_id)",
    "CREATE INDEX IF NOT EXISTS run_values_by_name ON run_values (name, num)",
    "CREATE TABLE IF NOT EXISTS tags (tag TEXT PRIMARY KEY, run_id TEXT NOT NULL)",
    "CREATE TABLE IF NOT EXISTS notes (run_id TEXT NOT NULL, written TEXT, text TEXT)",
)


Value = tuple[str, str, str, float | None, str]  # kind, name, text, number, units


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
    if had_runs:  # version 1: index what each run's folder holds
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


def values_of(folder: Path, status: str) -> list[Value]:
    """A run's queryable values: parameters, settings and factor levels from its
    ``study.toml``; response min/mean/max from its ``results.nc`` once it is finished."""
    rows = _definition_values(folder / "study.toml")
    if status == "finished":
        rows += _response_values(folder / "results.nc")
    return rows


def store_values(con: sqlite3.Connection, run_id: str, rows: list[Value]) -> None:
    """Replace the run's indexed values by ``rows``."""
    con.execute("DELETE FROM run_values WHERE run_id = ?", (run_id,))
    con.executemany(
        "INSERT INTO run_values (run_id, kind, name, text, num, units) VALUES (?, ?, ?, ?, ?, ?)",
        [(run_id, *r) for r in rows],
    )


def _value(kind: str, name: str, value: Any, units: str = "") -> Value:
    number = (
        float(value) if isinstance(value, int | float) and not isinstance(value, bool) else None
    )
    text = value if isinstance(value, str) else json.dumps(value)
    return kind, name, text, number, units


def _definition_values(study: Path) -> list[Value]:
    try:
        text = study.read_text(encoding="utf-8")
    except OSError:
        return []
    definition, _ = parse_study(text, str(study))
    if definition is None:  # recorded text that no longer validates: keep what TOML gives
        try:
            raw = tomllib.loads(text)
        except tomllib.TOMLDecodeError:
            return []
        return [_value("setting", k, v) for k, v in raw.get("settings", {}).items()]
    rows = [_value("parameter", k, v, u) for k, (v, u) in definition.parameters.items()]
    rows += [_value("setting", k, v) for k, v in definition.settings.items()]
    rows += [_value("factor", f.name, v, f.units) for f in definition.factors for v in f.levels]
    return rows


def _response_values(results: Path) -> list[Value]:
    try:
        ds = open_results(results)  # lazily, one response at a time: flat memory
    except (OSError, ValueError):
        return []
    with ds:
        names = json.loads(ds.attrs.get("responses", "[]"))
        rows = []
        for name in names:
            if name not in ds or ds[name].dims != ("run",) or ds[name].dtype.kind != "f":
                continue
            stored = ds[name].values
            values = stored[np.isfinite(stored)]
            units = str(ds[name].attrs.get("units", ""))
            summaries = (
                (values.min(), values.mean(), values.max()) if values.size else (math.nan,) * 3
            )
            for summary, x in zip(SUMMARIES, summaries, strict=True):
                rows.append(_value("response", f"{name}.{summary}", float(x), units))
        return rows


def run_values(outputs: Path, run_id: str) -> list[dict[str, Any]]:
    """The indexed values of one run (kind, name, text, num, units)."""
    with closing(connect(outputs)) as con:
        rows = con.execute(
            "SELECT kind, name, text, num, units FROM run_values WHERE run_id = ? "
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
