"""The trash under the outputs root: where ``rm`` and ``gc`` move runs, and ``restore`` finds them.

    outputs/.trash/<UTC time removed>/<study>/<run-id>/    the run folder, moved whole

A folder is moved in and out by a single rename (atomic on one filesystem), so it is always in
exactly one place and comes back bit-identical. Emptying an entry renames it to
``<run-id>.purging`` first, so a ``restore`` and a purge racing for one entry cannot both have
it; leftovers of a purge that was killed are deleted by the next ``gc``. The functions here take
the trash folder ``outputs/.trash`` (:attr:`RunStore.trash <studies.tracking.store.RunStore>`).
"""

from __future__ import annotations

import contextlib
import datetime as dt
import glob
import shutil
from dataclasses import dataclass
from pathlib import Path

from studies.common import labels
from studies.common.errors import RunNotFound
from studies.tracking.liveness import lock_folder

TRASH = ".trash"
PURGING = ".purging"
STAMP = "%Y%m%dT%H%M%S%f"
SETTLE_S = 60.0  # an empty trash folder younger than this may be about to receive a run


@dataclass(frozen=True)
class Trashed:
    """A run in the trash."""

    run_id: str
    study: str
    folder: Path
    removed: dt.datetime

    def tags(self) -> list[str]:
        return sorted(labels.read_labels(self.folder).tags)


def _stamp_time(name: str) -> dt.datetime | None:
    try:
        return dt.datetime.strptime(name, STAMP).replace(tzinfo=dt.UTC)
    except ValueError:
        return None


def _folders(path: Path) -> list[Path]:
    """The sub-folders of ``path``, sorted (none if it went away meanwhile)."""
    try:
        return sorted(p for p in path.iterdir() if p.is_dir() and not p.is_symlink())
    except OSError:
        return []


def entries(root: Path) -> list[Trashed]:
    """Every run in the trash folder ``root``, most recently removed first."""
    found = []
    for stamp in reversed(_folders(root)):
        removed = _stamp_time(stamp.name)
        if removed is None:
            continue
        for study in _folders(stamp):
            found += [
                Trashed(run.name, study.name, run, removed)
                for run in _folders(study)
                if not run.name.endswith(PURGING)
            ]
    return found


def holds(root: Path, run_id: str) -> bool:
    """Whether the run ``run_id`` is in the trash folder ``root``."""
    return "/" not in run_id and any(root.glob(f"*/*/{glob.escape(run_id)}"))


def move_in(root: Path, folder: Path, study: str) -> Path:
    """Move a run folder into the trash folder ``root`` (one rename); return where it went.
    A folder that cannot move (read-only, say) leaves no empty folder in the trash."""
    stamp = dt.datetime.now(dt.UTC).strftime(STAMP)
    target = root / stamp / study / folder.name
    target.parent.mkdir(parents=True, exist_ok=True)
    try:
        folder.rename(target)
    except OSError:
        for made in (target.parent, target.parent.parent):
            with contextlib.suppress(OSError):
                made.rmdir()  # only when empty
        raise
    return target


def find(root: Path, ref: str) -> Trashed:
    """The run in the trash folder ``root`` named by ``ref``: its id, a tag it had, or a unique
    prefix of its id (RunNotFound with one sentence otherwise)."""
    found = entries(root)
    chosen = [e for e in found if e.run_id == ref] or [e for e in found if ref in e.tags()]
    chosen = chosen or [e for e in found if e.run_id.startswith(ref)]
    if len(chosen) == 1:
        return chosen[0]
    if chosen:
        names = ", ".join(e.run_id for e in chosen[:4])
        raise RunNotFound(f"{ref!r} matches {len(chosen)} runs in the trash ({names}…): say which")
    msg = f"no run {ref!r} in the trash under {root.parent} (`python -m studies trash` lists it)"
    raise RunNotFound(msg)


def purge(entry: Trashed) -> bool:
    """Delete a trashed run for good; False if it is leaving the trash (a restore holds it)
    or has left it."""
    doomed = entry.folder.with_name(entry.folder.name + PURGING)
    try:
        lock = lock_folder(entry.folder)
    except FileNotFoundError:
        return False
    if lock is None:
        return False
    with lock:
        try:
            entry.folder.rename(doomed)
        except FileNotFoundError:
            return False
    shutil.rmtree(doomed, ignore_errors=True)
    return True


def sweep(root: Path) -> None:
    """Delete what killed purges left in the trash folder ``root``, and its empty folders once
    they have settled."""
    for leftover in root.glob(f"*/*/*{PURGING}"):
        shutil.rmtree(leftover, ignore_errors=True)
    settled = dt.datetime.now(dt.UTC) - dt.timedelta(seconds=SETTLE_S)
    for stamp in _folders(root):
        removed = _stamp_time(stamp.name)
        if removed is None or removed > settled:
            continue
        for folder in [*_folders(stamp), stamp]:
            try:
                folder.rmdir()  # only when empty
            except OSError:
                continue
