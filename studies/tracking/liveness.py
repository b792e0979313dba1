"""Whether a run lives: an exclusive lock on its folder, and a heartbeat thread.

A run, or a resume, holds an exclusive ``flock`` on its run folder from the moment the folder
exists until its last write. Another process on the machine (``rm``, ``gc``, a second
``--resume``, the registry's registration on sight) that cannot take the lock knows the run
lives, whatever its process id says; the kernel drops the lock when the process dies, even by
SIGKILL. Across machines, the heartbeat in ``run.json`` tells: :class:`Heartbeat` rewrites it
from a thread every few seconds while the run lives (compiling, computing chunks or analysing
alike: the kernels release the GIL), so a stale heartbeat means the process is gone.

Locks exist where ``fcntl.flock`` does (Linux, macOS, BSD); elsewhere a lock is always granted
and liveness falls back to the process id and the heartbeat. :func:`liveness` reads a run's
status as it is now from all three.
"""

from __future__ import annotations

import datetime as dt
import json
import os
import platform
import sys
import threading
import time
from collections.abc import Callable
from pathlib import Path
from types import TracebackType
from typing import Any, Self

POLL_S = 0.02  # between attempts to take a lock that is held
HEARTBEAT_S = 5.0  # a live run's heartbeat thread rewrites run.json this often
STALE_S = 120.0  # a heartbeat older than this marks a run on another host as interrupted


class FolderLock:
    """A held exclusive lock on a run folder; released by :meth:`release` or on exit."""

    def __init__(self, fd: int | None) -> None:
        self._fd = fd

    def holds(self, folder: Path) -> bool:
        """Whether ``folder`` is still the folder locked (another process may have moved it
        away while this one waited for the lock)."""
        if self._fd is None:
            return folder.is_dir()
        try:
            return os.path.samestat(os.fstat(self._fd), folder.stat())
        except OSError:
            return False

    def release(self) -> None:
        if self._fd is not None:
            os.close(self._fd)  # closing the descriptor drops the flock
            self._fd = None

    def __enter__(self) -> Self:
        return self

    def __exit__(
        self,
        kind: type[BaseException] | None,
        error: BaseException | None,
        trace: TracebackType | None,
    ) -> None:
        self.release()


def lock_folder(folder: Path, wait_s: float = 0.0) -> FolderLock | None:
    """Take the exclusive lock on ``folder``, waiting up to ``wait_s`` [s] for a holder to let
    go; None when another process holds it (FileNotFoundError when the folder is gone)."""
    if sys.platform == "win32":
        return FolderLock(None)
    import fcntl  # noqa: PLC0415  (POSIX only)

    fd = os.open(folder, os.O_RDONLY | os.O_DIRECTORY)
    deadline = time.monotonic() + wait_s
    while True:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            if time.monotonic() >= deadline:
                os.close(fd)
                return None
            time.sleep(POLL_S)
            continue
        return FolderLock(fd)


def is_locked(folder: Path) -> bool:
    """Whether a live process holds the lock on ``folder`` (False when it does not exist)."""
    if sys.platform == "win32":
        return False
    import fcntl  # noqa: PLC0415  (POSIX only)

    try:
        fd = os.open(folder, os.O_RDONLY | os.O_DIRECTORY)
    except OSError:
        return False
    try:
        fcntl.flock(fd, fcntl.LOCK_SH | fcntl.LOCK_NB)
    except BlockingIOError:
        return True
    finally:
        os.close(fd)
    return False


class Heartbeat:
    """Call ``beat()`` every ``every_s`` [s] from a daemon thread between :meth:`start` and
    :meth:`stop`. A beat that fails with OSError (a full disk) is skipped; the next one tries
    again."""

    def __init__(self, beat: Callable[[], None], every_s: float) -> None:
        self._beat = beat
        self._every_s = every_s
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="run-heartbeat", daemon=True)

    def _run(self) -> None:
        while not self._stop.wait(self._every_s):
            try:
                self._beat()
            except OSError:
                continue

    def start(self) -> None:
        self._thread.start()

    def stop(self) -> None:
        """Stop beating; when this returns, no beat is under way (safe to call twice)."""
        self._stop.set()
        if self._thread.is_alive():
            self._thread.join()


def liveness(record: dict[str, Any], folder: Path | None = None) -> str:
    """The status of a recorded run as it is now: an unfinished run is running while a
    process holds the lock on its ``folder`` (a resume, from its first instant); otherwise a
    "running" run is "interrupted" when its process is gone (same host) or its heartbeat is
    older than ``STALE_S`` (another host)."""
    status = str(record.get("status", ""))
    if status in ("running", "failed", "interrupted") and folder is not None and is_locked(folder):
        return "running"
    if status != "running":
        return status
    same_host = record.get("host", {}).get("node") == platform.node()
    pid = int(record.get("pid") or 0)
    if same_host and pid:
        return "running" if _alive(pid) else "interrupted"
    beat = record.get("heartbeat") or record.get("started", "")
    if not beat:
        return "running"
    age = (dt.datetime.now(dt.UTC) - dt.datetime.fromisoformat(beat)).total_seconds()
    return "interrupted" if age > STALE_S else "running"


def _alive(pid: int) -> bool:
    """Whether a process with this id exists on this host (a zombie counts as gone)."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    try:
        stat = Path(f"/proc/{pid}/stat").read_text(encoding="ascii")
    except OSError:
        return True
    return stat.rsplit(")", 1)[-1].split()[0] != "Z"


def current_status(row: dict[str, Any]) -> tuple[str, dict[str, Any] | None]:
    """A registry row's status now ("missing" when its folder is gone) and its run.json."""
    folder = Path(row["folder"])
    path = folder / "run.json"
    if not path.exists():
        return "missing", None
    record = json.loads(path.read_text(encoding="utf-8"))
    return liveness(record, folder), record
