"""The run store: one outputs root, its run folders and the registry that indexes them.

:class:`RunStore` is the one way into a tracked outputs root: it opens the registry
(``registry.sqlite``, :mod:`studies.tracking.registry`), brings it to the current schema once
per object, and offers every operation on the runs as a method: register and list them, look one
up by id, tag or prefix, tag and note them, read their indexed values, move them to the trash and
back, collect garbage, and re-index. The folders are the truth and the registry their index:
listing or looking up runs first registers what the registry misses (:meth:`RunStore.reconcile`),
and rows address folders relative to the outputs root.
"""

from __future__ import annotations

import datetime as dt
import sqlite3
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from dataclasses import asdict
from pathlib import Path
from typing import Any

from studies.common import labels
from studies.common.errors import RunNotFound, RunStateError
from studies.tracking import housekeeping, registry, reindex, trash
from studies.tracking.records import RunRecord
from studies.tracking.registry_file import REGISTRY, open_file, unusable, writing

RUN_ID_ATTEMPTS = 1000  # runs of one definition started in the same millisecond


class RunStore:
    """The runs recorded under one outputs root [folder] and their registry.

    A connection is opened per operation and closed after it, not held by the object: SQLite
    connections belong to the thread that made them (the run's heartbeat thread must not share
    one), and a closed connection holds no lock or file handle while a long run computes, so
    other processes register, tag and list runs in the same registry meanwhile. Opening costs
    one ``open`` of the file; the schema migration and the table check are done once per
    object, by its first connection.
    """

    def __init__(self, outputs: Path) -> None:
        self.outputs = outputs
        self.registry = outputs / REGISTRY
        self.trash = outputs / trash.TRASH
        self._up_to_date = False

    def __repr__(self) -> str:
        return f"RunStore({str(self.outputs)!r})"

    def connect(self) -> sqlite3.Connection:
        """A connection to the registry, created whole or migrated to
        :data:`registry.SCHEMA_VERSION` first (by this object's first connection); in
        ``DEFERRED`` mode (``with con:`` is one transaction). Raises
        :class:`~studies.tracking.registry_file.RegistryUnusable` (or
        :class:`~studies.tracking.registry.RegistryError`)."""
        con = open_file(self.registry, registry.create)
        try:
            if not self._up_to_date:
                registry.bring_up_to_date(con, self.registry, self.folder)
                self._up_to_date = True
        except sqlite3.Error as exc:
            con.close()
            raise unusable(exc, self.registry) from None
        except BaseException:
            con.close()
            raise
        con.isolation_level = "DEFERRED"
        return con

    @contextmanager
    def connection(self) -> Iterator[sqlite3.Connection]:
        """:meth:`connect`, closed after the block; any SQLite error in the block becomes
        :class:`~studies.tracking.registry_file.RegistryUnusable`."""
        con = self.connect()
        try:
            yield con
        except sqlite3.Error as exc:
            raise unusable(exc, self.registry) from None
        finally:
            con.close()

    def folder(self, row: Mapping[str, Any]) -> Path:
        """A row's run folder under this outputs root (rows written before folders were stored
        relative hold an absolute path, which is not followed: it may be another root's)."""
        stored = Path(row.get("folder") or "")
        if stored.parts and not stored.is_absolute():
            return self.outputs / stored
        return self.outputs / str(row["study"]) / str(row["run_id"])

    def relative(self, folder: Path) -> str:
        """How the registry stores a run folder of this root: ``<study>/<run-id>``."""
        return folder.relative_to(self.outputs).as_posix()

    def run_folder(self, study: str, run_id: str) -> tuple[str, Path]:
        """Create a run's folder; the id gets a suffix ``-1``, ``-2``, … when another run of
        the same definition took it in the same millisecond. Returns the id used and the
        folder."""
        (self.outputs / study).mkdir(parents=True, exist_ok=True)
        taken = run_id
        for attempt in range(1, RUN_ID_ATTEMPTS + 1):
            folder = self.outputs / study / taken
            try:
                folder.mkdir()
            except FileExistsError:
                taken = f"{run_id}-{attempt}"
                continue
            return taken, folder
        msg = (
            f"{RUN_ID_ATTEMPTS} runs of {study!r} took the id {run_id} at once: "
            "start fewer together"
        )
        raise FileExistsError(msg)

    def resume_command(self, run_id: str) -> str:
        """The command that finishes an interrupted or failed run."""
        return f"python -m studies run --resume {run_id} --outputs {self.outputs}"

    def register(self, record: RunRecord) -> None:
        """Insert or update the registry row of ``record`` (and its queryable values)."""
        row = registry.row_of(asdict(record), f"{record.study}/{record.run_id}")
        with self.connection() as con:
            registry.upsert_run(con, row, self.folder(row))

    def list_runs(self, study: str | None = None) -> list[dict[str, Any]]:
        """Registry rows, newest first (optionally of one study), each with its ``folder``
        under the outputs root; what the registry missed is registered first."""
        self.reconcile()
        if not self.registry.exists():
            return []
        with self.connection() as con:
            query = "SELECT * FROM runs"
            args: tuple[str, ...] = ()
            if study:
                query += " WHERE study = ?"
                args = (study,)
            order = " ORDER BY started DESC, run_id DESC"
            rows = [dict(r) for r in con.execute(query + order, args)]
        return [r | {"folder": str(self.folder(r))} for r in rows]

    def finished_identical(self, definition_sha256: str, code_sha256: str) -> dict[str, Any] | None:
        """The newest finished run of the same definition (study text and input files)
        computed by the same code (engine and scene sources, library versions:
        :func:`studies.run.provenance.code_hash`)."""
        for row in self.list_runs():
            same = row["definition_sha256"] == definition_sha256
            same = same and row["code_sha256"] == code_sha256
            if (
                same
                and row["status"] == "finished"
                and (Path(row["folder"]) / "results.nc").exists()
            ):
                return row
        return None

    def find_run(self, ref: str) -> dict[str, Any] | None:
        """The registry row named by ``ref``: the id, else a tag, else a unique prefix of the
        id (a tag never hides a run's own id)."""
        rows = self.list_runs()
        exact = [r for r in rows if r["run_id"] == ref]
        if not exact and rows:
            tagged = self.tagged_run(ref)
            exact = [r for r in rows if r["run_id"] == tagged]
        chosen = exact or [r for r in rows if r["run_id"].startswith(ref)]
        return chosen[0] if len(chosen) == 1 else None

    def resolve_run(self, ref: str) -> dict[str, Any]:
        """:meth:`find_run`, or :class:`RunNotFound` with one sentence on what was wrong."""
        row = self.find_run(ref)
        if row is not None:
            return row
        matches = [r["run_id"] for r in self.list_runs() if r["run_id"].startswith(ref)]
        if matches:
            msg = (
                f"{ref!r} matches {len(matches)} runs ({', '.join(matches[:4])}…): "
                "give more of the id"
            )
        elif trash.holds(self.trash, ref):
            msg = (
                f"run {ref} is in the trash: bring it back with "
                f"python -m studies restore {ref} --outputs {self.outputs}"
            )
        else:
            msg = (
                f"no run or tag {ref!r} under {self.outputs} "
                "(`python -m studies runs` lists the runs and their tags)"
            )
        raise RunNotFound(msg)

    def run_values(self, run_id: str) -> list[dict[str, Any]]:
        """The indexed values of one run (kind, name, text, num in SI, units: the SI unit,
        declared_units: the scene's)."""
        with self.connection() as con:
            rows = con.execute(
                "SELECT kind, name, text, num, units, declared_units FROM run_values "
                "WHERE run_id = ? ORDER BY kind, name, num",
                (run_id,),
            )
            return [dict(r) for r in rows]

    def _labelled(self, con: sqlite3.Connection, run_id: str) -> Path:
        """The folder of a registered run, to write its labels into (RunStateError when it is
        gone)."""
        row = con.execute("SELECT * FROM runs WHERE run_id = ?", (run_id,)).fetchone()
        folder = self.folder(dict(row)) if row else None
        if folder is None or not folder.is_dir():
            msg = f"run {run_id} has no folder under {self.outputs}: nothing to label"
            raise RunStateError(msg)
        return folder

    def set_tag(self, run_id: str, tag: str) -> str | None:
        """Tag a run, in its folder and the registry; return the run the tag named before (it
        moves), if another. StudyError for a tag that could be taken for a run id."""
        labels.check_tag(tag)
        when = dt.datetime.now(dt.UTC).isoformat(timespec="milliseconds")
        with self.connection() as con, labels.Undo() as undo, writing(con):
            folder = self._labelled(con, run_id)
            before = con.execute("SELECT run_id FROM tags WHERE tag = ?", (tag,)).fetchone()
            moved = before["run_id"] if before and before["run_id"] != run_id else None
            undo.save(folder)
            labels.add_tag(folder, tag, when)
            if moved is not None:
                try:
                    previous = self._labelled(con, moved)
                except RunStateError:
                    previous = None  # the other run's folder is gone: only its row names the tag
                if previous is not None:
                    undo.save(previous)
                    labels.drop_tag(previous, tag)
            con.execute("INSERT OR REPLACE INTO tags (tag, run_id) VALUES (?, ?)", (tag, run_id))
        return moved

    def remove_tag(self, tag: str) -> bool:
        """Remove a tag from its run and the registry (False when no run has it)."""
        with self.connection() as con, labels.Undo() as undo, writing(con):
            before = con.execute("SELECT run_id FROM tags WHERE tag = ?", (tag,)).fetchone()
            if before is None:
                return False
            try:
                folder = self._labelled(con, before["run_id"])
            except RunStateError:
                folder = None  # its folder is gone: only the registry names the tag
            if folder is not None:
                undo.save(folder)
                labels.drop_tag(folder, tag)
            con.execute("DELETE FROM tags WHERE tag = ?", (tag,))
            return True

    def add_note(self, run_id: str, written: str, text: str) -> None:
        """Add a note (``written``: its UTC time) to a run, in its folder and the registry."""
        with self.connection() as con, labels.Undo() as undo, writing(con):
            folder = self._labelled(con, run_id)
            undo.save(folder)
            labels.add_note(folder, written, text)
            con.execute("INSERT INTO notes VALUES (?, ?, ?)", (run_id, written, text))

    def tags_and_notes(self) -> tuple[dict[str, list[str]], dict[str, list[str]]]:
        """Run id → its tags, and run id → its notes ("<time> <text>"), oldest first."""
        tags: dict[str, list[str]] = {}
        notes: dict[str, list[str]] = {}
        with self.connection() as con:
            for r in con.execute("SELECT tag, run_id FROM tags ORDER BY tag"):
                tags.setdefault(r["run_id"], []).append(r["tag"])
            for r in con.execute("SELECT run_id, written, text FROM notes ORDER BY written"):
                notes.setdefault(r["run_id"], []).append(f"{r['written']} {r['text']}")
        return tags, notes

    def tagged_run(self, tag: str) -> str | None:
        """The id of the run that ``tag`` names, if any."""
        with self.connection() as con:
            row = con.execute("SELECT run_id FROM tags WHERE tag = ?", (tag,)).fetchone()
        return row["run_id"] if row else None

    def reconcile(self) -> None:
        """Register what the registry missed (:func:`studies.tracking.reindex.reconcile`)."""
        reindex.reconcile(self)

    def reindex(self) -> reindex.Reindexed:
        """Move the registry aside and build a new one from the run folders
        (:func:`studies.tracking.reindex.rebuild`)."""
        return reindex.rebuild(self)

    def remove(self, row: dict[str, Any], force: bool = False) -> Path | None:
        """Move a run to the trash and delete its registry rows; where it went (None when its
        folder was gone already). See :func:`studies.tracking.housekeeping.remove_run`."""
        return housekeeping.remove_run(self, row, force)

    def restore(self, ref: str) -> tuple[trash.Trashed, Path, list[str]]:
        """Bring a run back from the trash and register it: (the entry, its folder, the tags it
        could not take back). See :func:`studies.tracking.housekeeping.restore_run`."""
        return housekeeping.restore_run(self, ref)

    def collect_garbage(
        self, older_than: dt.timedelta, keep_tagged: bool, dry_run: bool = False
    ) -> housekeeping.Collected:
        """``gc``: see :func:`studies.tracking.housekeeping.collect_garbage`."""
        return housekeeping.collect_garbage(self, older_than, keep_tagged, dry_run)

    def trash_entries(self) -> list[trash.Trashed]:
        """Every run in the trash, most recently removed first."""
        return trash.entries(self.trash)
