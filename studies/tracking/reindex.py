"""Rebuild the registry from the run folders, and register on sight what it missed.

The run folders are the truth (``<study>/<run-id>/`` with ``run.json``, ``study.toml``, the
results and ``labels.json``); the registry indexes them.

:func:`reconcile` (:meth:`RunStore.reconcile <studies.tracking.store.RunStore.reconcile>`)
runs whenever runs are listed or looked up, and mends what a killed process
left: a folder with ``run.json`` but no registry row and no live process holding it (killed
between writing ``run.json`` and its first registration) is registered; a row that still says
"running" although ``run.json`` says otherwise (killed after "finished" and before the registry
update) is updated; a row whose folder went to the trash (``rm`` killed between moving the
folder and deleting the rows) is deleted. When the registry refuses the write (read-only,
locked) nothing is mended and the listing goes on: statuses are read from ``run.json`` anyway.

:func:`rebuild` (:meth:`RunStore.reindex <studies.tracking.store.RunStore.reindex>`,
``python -m studies reindex``) moves the registry aside, never deleting it,
and builds a new one from every run folder: rows, values, tags and notes; tags and notes that
only the old registry holds, if it can still be read, are carried over into the folders.
"""

from __future__ import annotations

import datetime as dt
import json
import os
import re
import sqlite3
from collections.abc import Iterator
from contextlib import closing, contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from studies.common import labels
from studies.tracking import registry, registry_file, trash
from studies.tracking.liveness import is_locked
from studies.tracking.registry_file import REGISTRY, RegistryUnusable, unusable, writing

if TYPE_CHECKING:
    from studies.tracking.store import RunStore

RUN_ID = re.compile(r"^\d{8}T\d{9}-[0-9a-f]{6}(-\d+)?$")
SIDE_FILES = ("-journal", "-wal", "-shm")  # SQLite's companions of a database file


def run_folders(root: Path) -> Iterator[Path]:
    """Every ``<study>/<run-id>/`` folder under the outputs root ``root`` (symbolic links not
    followed)."""
    try:
        studies = [e for e in os.scandir(root) if e.is_dir(follow_symlinks=False)]
    except OSError:
        return
    for study in sorted(studies, key=lambda e: e.name):
        if study.name.startswith("."):
            continue
        try:
            runs = sorted(os.scandir(study.path), key=lambda e: e.name)
        except OSError:
            continue
        for run in runs:
            if RUN_ID.match(run.name) and run.is_dir(follow_symlinks=False):
                yield Path(run.path)


def read_record(folder: Path) -> dict[str, Any] | None:
    """The ``run.json`` of ``folder`` when it is a record of that very run, else None."""
    try:
        record = json.loads((folder / "run.json").read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    if not isinstance(record, dict) or record.get("run_id") != folder.name:
        return None
    if not isinstance(record.get("study"), str) or not isinstance(record.get("status"), str):
        return None
    return record


def reconcile(store: RunStore) -> None:
    """Register what the registry of ``store`` missed (see the module's docstring)."""
    exists = store.registry.exists()
    folders = list(run_folders(store.outputs))
    if not exists and not folders:
        return  # nothing recorded here: do not create a registry
    with store.connection() as con:
        rows = {r["run_id"]: dict(r) for r in con.execute("SELECT * FROM runs")}
    adopt, update = [], []
    for folder in folders:
        row = rows.get(folder.name)
        if row is not None and row["status"] != "running":
            continue
        if is_locked(folder):
            continue  # a live run registers itself
        record = read_record(folder)
        if record is None:
            continue
        if row is None:
            adopt.append((record, folder))
        elif record["status"] != "running":
            update.append(registry.row_of(record, store.relative(folder)))
    gone = [
        run_id
        for run_id, row in rows.items()
        if not store.folder(row).exists() and trash.holds(store.trash, run_id)
    ]
    if not (adopt or update or gone):
        return
    try:
        with store.connection() as con:
            for record, folder in adopt:
                registry.index_folder(con, record, folder, store.relative(folder))
            for row in update:
                registry.upsert_run(con, row, store.folder(row))
            with writing(con):
                for run_id in gone:
                    registry.delete_run(con, run_id)
    except RegistryUnusable:
        return


@dataclass
class Reindexed:
    runs: int = 0
    tags: int = 0
    notes: int = 0
    kept_as: Path | None = None  # the old registry, moved aside
    skipped: list[str] = field(default_factory=list)  # folders without a readable run.json


def rebuild(store: RunStore) -> Reindexed:
    """Move the registry of ``store`` aside and build a new one from the run folders."""
    done = Reindexed()
    path = store.registry
    if path.exists() or path.is_symlink():
        stamp = dt.datetime.now(dt.UTC).strftime("%Y%m%dT%H%M%S%f")
        done.kept_as = path.with_name(f"{REGISTRY}.{stamp}.bak")
        with _no_writer(path):
            path.rename(done.kept_as)
            for side in SIDE_FILES:  # a hot journal must never be replayed onto the new file
                companion = path.with_name(REGISTRY + side)
                if companion.exists():
                    companion.rename(done.kept_as.with_name(done.kept_as.name + side))
    old_tags, old_notes = _salvage(done.kept_as)
    claims: dict[str, tuple[str, Path]] = {}  # tag → (when, folder): the latest claim wins
    with store.connection() as con:
        for folder in run_folders(store.outputs):
            record = read_record(folder)
            if record is None:
                done.skipped.append(f"{folder}: no readable run.json of run {folder.name}")
                continue
            found = labels.read_labels(folder)
            for tag, run_id in old_tags.items():
                if run_id == folder.name and tag not in claims and tag not in found.tags:
                    labels.add_tag(folder, tag, "")
                    found.tags[tag] = ""
            for tag, when in found.tags.items():
                earlier = claims.get(tag)
                if earlier is not None:
                    labels.drop_tag(min(earlier, (when, folder))[1], tag)
                claims[tag] = max(earlier or (when, folder), (when, folder))
            if not found.notes:
                for written, text in old_notes.get(folder.name, []):
                    labels.add_note(folder, written, text)
            registry.index_folder(con, record, folder, store.relative(folder))
            done.runs += 1
        with writing(con):
            con.executemany(
                "INSERT OR REPLACE INTO tags (tag, run_id) VALUES (?, ?)",
                [(tag, folder.name) for tag, (_, folder) in claims.items()],
            )
        done.tags = con.execute("SELECT COUNT(*) FROM tags").fetchone()[0]
        done.notes = con.execute("SELECT COUNT(*) FROM notes").fetchone()[0]
    return done


@contextmanager
def _no_writer(path: Path) -> Iterator[None]:
    """Hold the registry's write lock while it is moved aside, so that no other process is
    inside a transaction on it (waiting for one up to ``BUSY_TIMEOUT_S``, then
    :class:`RegistryUnusable`, nothing moved); a file SQLite cannot lock (damaged: what
    reindex is for) is moved as it is."""
    try:
        con = sqlite3.connect(path, timeout=registry_file.BUSY_TIMEOUT_S, isolation_level=None)
    except sqlite3.Error:
        yield
        return
    with closing(con):
        try:
            con.execute("BEGIN IMMEDIATE")
        except sqlite3.Error as exc:
            code = (getattr(exc, "sqlite_errorcode", None) or sqlite3.SQLITE_ERROR) & 0xFF
            if code in (sqlite3.SQLITE_BUSY, sqlite3.SQLITE_LOCKED):
                raise unusable(exc, path) from None
        yield


def _salvage(old: Path | None) -> tuple[dict[str, str], dict[str, list[tuple[str, str]]]]:
    """The tags and notes that a moved-aside registry still yields (none if it cannot be read)."""
    tags: dict[str, str] = {}
    notes: dict[str, list[tuple[str, str]]] = {}
    if old is None or not old.is_file():
        return tags, notes
    try:
        with closing(sqlite3.connect(f"{old.as_uri()}?mode=ro", uri=True)) as con:
            tags = {str(t): str(r) for t, r in con.execute("SELECT tag, run_id FROM tags")}
            for run_id, written, text in con.execute("SELECT run_id, written, text FROM notes"):
                notes.setdefault(str(run_id), []).append((str(written), str(text)))
    except sqlite3.Error:
        pass  # damaged beyond reading: the folders' labels are all there is
    return tags, notes
