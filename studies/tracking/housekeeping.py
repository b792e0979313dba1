"""Remove and restore runs: the folder moves to the trash and back, the registry follows.

``rm`` takes the run folder's lock (a live run or resume holds it: refused), moves the folder
into the trash (:mod:`studies.tracking.trash`, one rename) and deletes the run's registry rows in one
transaction; if the registry refuses, the folder is moved back. A tagged run needs ``force``.
``restore`` moves the folder back and registers it with its tags and notes (from its
``labels.json``). ``gc`` moves runs older than an age to the trash and deletes for good what
has been in the trash longer than that age, plus what killed processes left behind. These are
the operations behind :meth:`RunStore.remove`, :meth:`RunStore.restore` and
:meth:`RunStore.collect_garbage` (:mod:`studies.tracking.store`), which callers use.
"""

from __future__ import annotations

import datetime as dt
import re
import shutil
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from studies.common import labels
from studies.common.errors import OutputsError, RunNotFound, RunStateError, StudyError
from studies.tracking import registry, trash
from studies.tracking.liveness import current_status, is_locked, liveness, lock_folder
from studies.tracking.registry_file import writing
from studies.tracking.reindex import read_record, run_folders

if TYPE_CHECKING:
    from studies.tracking.store import RunStore

REMOVING = ".removing"  # left by versions that deleted runs at once
AGE = re.compile(r"^\s*(\d+(?:\.\d+)?)\s*([smhdw])\s*$")
UNIT_S = {"s": 1, "m": 60, "h": 3600, "d": 86400, "w": 7 * 86400}
MAX_AGE = dt.timedelta(days=1000 * 365)  # older runs than this cannot exist; datetime ends at 9999
LOCK_WAIT_S = 0.5  # a listing may hold a run folder's lock for an instant
STILLBORN_S = 60.0  # a run folder without run.json this old was left by a killed start


def parse_age(text: str) -> dt.timedelta:
    """``30d``, ``12h``, ``2w``, ``90m``, ``45s`` → a timedelta (ValueError otherwise); ages
    beyond a century are a century."""
    match = AGE.match(text)
    if not match:
        raise StudyError(f"--older-than {text!r}: write a number and s, m, h, d or w, e.g. 30d")
    seconds = float(match[1]) * UNIT_S[match[2]]
    if seconds > MAX_AGE.total_seconds():
        msg = f"--older-than {text.strip()} is more than {MAX_AGE.days // 365} years: give a shorter age"
        raise StudyError(msg)
    return dt.timedelta(seconds=seconds)


def remove_run(store: RunStore, row: dict[str, Any], force: bool = False) -> Path | None:
    """Move a run of ``store`` to the trash and delete its registry rows; return where it went
    (None when its folder was gone already). RunStateError while it runs, or if tagged and not
    ``force``; RunNotFound if another process moved it meanwhile; OutputsError if its folder
    cannot move (read-only): then nothing changed."""
    run_id = row["run_id"]
    tags = store.tags_and_notes()[0].get(run_id, [])
    if tags and not force:
        msg = (
            f"run {run_id} is tagged ({', '.join(tags)}): not removed; `rm --force` moves it "
            "to the trash all the same (`restore` brings it back)"
        )
        raise RunStateError(msg)
    folder = Path(row["folder"])
    try:
        lock = lock_folder(folder, LOCK_WAIT_S)
    except FileNotFoundError:
        with store.connection() as con, writing(con):
            registry.delete_run(con, run_id)
        return None
    if lock is None:
        raise RunStateError(f"run {run_id} is still running (its folder is locked): not removed")
    with lock:
        if not lock.holds(folder):
            raise RunNotFound(f"run {run_id} was moved by another process meanwhile: not removed")
        record = read_record(folder)
        if record is not None and liveness(record) == "running":
            raise RunStateError(f"run {run_id} is still running: not removed")
        try:
            target = trash.move_in(store.trash, folder, str(row["study"]))
        except OSError as exc:
            refused = OutputsError(
                f"run {run_id}: {folder} cannot move into the trash ({exc.strerror or exc}); "
                f"the folder and {folder.parent} must be writable"
            )
            refused.add_note("nothing was removed")
            raise refused from None
        try:
            with store.connection() as con, writing(con):
                registry.delete_run(con, run_id)
        except BaseException:
            target.rename(folder)
            raise
    return target


def restore_run(store: RunStore, ref: str) -> tuple[trash.Trashed, Path, list[str]]:
    """Bring a run back from the trash of ``store``, bit-identical, and register it; return the
    entry, its folder and the tags it could not take back (they name another run now)."""
    entry = trash.find(store.trash, ref)
    folder = store.outputs / entry.study / entry.run_id
    if folder.exists():
        raise RunStateError(f"{folder} exists: run {entry.run_id} is not restored over it")
    try:
        lock = lock_folder(entry.folder, LOCK_WAIT_S)  # held across the rename: same inode
    except FileNotFoundError:
        lock = None
    if lock is None or not lock.holds(entry.folder):
        raise RunNotFound(f"run {entry.run_id} left the trash meanwhile: not restored")
    with lock:
        record = read_record(entry.folder)
        if record is None:
            raise RunStateError(f"{entry.folder} holds no readable run.json: not restored")
        folder.parent.mkdir(parents=True, exist_ok=True)
        try:
            entry.folder.rename(folder)
        except FileNotFoundError:
            raise RunNotFound(
                f"run {entry.run_id} left the trash meanwhile: not restored"
            ) from None
        try:
            with store.connection() as con:
                lost = registry.index_folder(con, record, folder, store.relative(folder))
        except BaseException:
            entry.folder.parent.mkdir(parents=True, exist_ok=True)
            folder.rename(entry.folder)
            raise
    for tag in lost:
        labels.drop_tag(folder, tag)
    return entry, folder, lost


@dataclass
class Collected:
    """What ``gc`` moved to the trash, what it deleted from it, and why the runs it could not
    move stayed where they are (one line each)."""

    trashed: list[dict[str, Any]] = field(default_factory=list)
    purged: list[trash.Trashed] = field(default_factory=list)
    refused: list[str] = field(default_factory=list)


def collect_garbage(
    store: RunStore, older_than: dt.timedelta, keep_tagged: bool, dry_run: bool = False
) -> Collected:
    """Move the runs of ``store`` that started more than ``older_than`` ago to the trash (not
    running ones; not tagged ones with ``keep_tagged``), delete for good the runs removed more
    than ``older_than`` ago (with ``keep_tagged``, not a tagged one: it stays in the trash), and
    what killed processes left behind. A run whose folder cannot move (read-only) stays,
    registered and whole, with its reason in ``refused``; the others are collected all the same."""
    cutoff = dt.datetime.now(dt.UTC) - older_than
    tags, _ = store.tags_and_notes()
    chosen = []
    for row in store.list_runs():
        started = dt.datetime.fromisoformat(row["started"]) if row["started"] else cutoff
        if started >= cutoff or (keep_tagged and row["run_id"] in tags):
            continue
        if current_status(row)[0] == "running":
            continue
        chosen.append(row)
    expired = [
        e for e in store.trash_entries() if e.removed < cutoff and not (keep_tagged and e.tags())
    ]
    if dry_run:
        return Collected(chosen, expired)
    done = Collected()
    for row in chosen:
        try:
            remove_run(store, row, force=True)
        except (ValueError, KeyError):
            continue  # started again (a resume), or removed by another process, since listed
        except OutputsError as exc:
            done.refused.append("; ".join([str(exc), *getattr(exc, "__notes__", [])]))
            continue
        done.trashed.append(row)
    done.purged = [e for e in expired if trash.purge(e)]
    trash.sweep(store.trash)
    _sweep_leftovers(store.outputs)
    return done


def _sweep_leftovers(root: Path) -> None:
    """Delete ``.removing`` folders of older versions under the outputs root ``root``, and run
    folders that a start killed before writing ``run.json`` left (unlocked and older than
    :data:`STILLBORN_S`)."""
    for leftover in root.glob(f"*/*{REMOVING}"):
        shutil.rmtree(leftover, ignore_errors=True)
    settled = dt.datetime.now(dt.UTC).timestamp() - STILLBORN_S
    for folder in run_folders(root):
        if (folder / "run.json").exists() or is_locked(folder):
            continue
        try:
            if folder.stat().st_mtime < settled:
                shutil.rmtree(folder, ignore_errors=True)
        except OSError:
            continue
