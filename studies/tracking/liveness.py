"""Whether a run lives: an exclusive lock on its folder, and a heartbeat thread.

A run, or a resume, holds an exclusive ``flock`` on its run folder from the moment the folder
exists until its last write. Another process on the machine (``rm``, ``gc``, a second
``--resume``, the registry's registration on sight) that cannot take the lock knows the run
lives, whatever its process id says; the kernel drops the lock when the process dies, even by
SIGKILL. Across machines, the heartbeat in ``run.json`` tells: :class:`Heartbeat` rewrites it
from a thread every few seconds while the run lives (compiling, computing chunks or analysing
alike: the kernels release the GIL), so a stale heartbeat means the process is gone.

Locks exist where ``fcntl.flock`` does (Linux, macOS, BSD); elsewhere a lock is always granted
and liveness falls back to the process id and the heartbeat.
"""

from __future__ import annotations

import os
import sys
import threading
import time
from collections.abc import Callable
from pathlib import Path
from types import TracebackType
from typing import Self

POLL_S = 0.02  # between attempts to take a lock that is held


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
