"""The registry's file: created whole, opened with a bounded wait, and every failure said in one
line with the way out.

A new registry is built under a temporary name and linked into place, so a registry file is
never seen half-made (and a 0-byte ``registry.sqlite`` is damage, never "new"). Every SQLite
error becomes :class:`RegistryUnusable` (an OSError, exit code 4 on the command line) naming
the file, what is wrong and what to do:

    damaged (not a database, a corrupt page, a table missing, a directory, 0 bytes)
                → ``python -m studies reindex`` rebuilds it from the run folders
    locked by another process past :data:`BUSY_TIMEOUT_S` → try again when it is done
    read-only, full disk, I/O error → make it writable, free space, check the disk
"""

from __future__ import annotations

import os
import sqlite3
import threading
from collections.abc import Callable, Iterator
from contextlib import closing, contextmanager
from pathlib import Path

from studies.common.errors import OutputsError

REGISTRY = "registry.sqlite"
BUSY_TIMEOUT_S = 10.0  # how long a command waits for another process's write lock
_BUSY = (sqlite3.SQLITE_BUSY, sqlite3.SQLITE_LOCKED)
_DAMAGED = (
    sqlite3.SQLITE_CORRUPT,
    sqlite3.SQLITE_NOTADB,
    sqlite3.SQLITE_CANTOPEN,
    sqlite3.SQLITE_ERROR,
    sqlite3.SQLITE_SCHEMA,
    sqlite3.SQLITE_FORMAT,
)


class RegistryUnusable(OutputsError):
    """The registry cannot be read or written now: damaged, locked, read-only or full."""


def damaged(path: Path, what: str) -> RegistryUnusable:
    """The error for the registry file ``path`` when it holds no usable index (``what``: how
    it looks); the way out rebuilds it from the run folders beside it."""
    return RegistryUnusable(
        f"the registry {path} is damaged ({what}); the run folders are intact: rebuild it "
        f"from them with: python -m studies reindex --outputs {path.parent}"
    )


def unusable(exc: sqlite3.Error, path: Path) -> RegistryUnusable:
    """One line for a SQLite error on the registry file ``path``: what, and what to do."""
    code = (getattr(exc, "sqlite_errorcode", None) or sqlite3.SQLITE_ERROR) & 0xFF
    detail = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
    if code in _BUSY:
        text = (
            f"the registry {path} is locked by another process (waited {BUSY_TIMEOUT_S:g} s); "
            "nothing was changed: run the command again when that process is done"
        )
    elif code == sqlite3.SQLITE_READONLY:
        text = (
            f"the registry {path} is read-only ({detail}); nothing was changed: make it "
            "writable or choose another --outputs"
        )
    elif code == sqlite3.SQLITE_FULL:
        text = (
            f"the disk holding the registry {path} is full; nothing was changed: free some "
            "space and run the command again"
        )
    elif code in _DAMAGED and path.is_dir():
        return damaged(path, "it is a directory, not a file")
    elif code in _DAMAGED:
        return damaged(path, detail)
    else:
        text = (
            f"the registry {path} could not be written or read ({detail}); nothing was "
            "changed: check its disk (free space, quota, file size limit) and run it again"
        )
    return RegistryUnusable(text)


def open_file(path: Path, create: Callable[[sqlite3.Connection], None]) -> sqlite3.Connection:
    """A connection to the registry file ``path`` (in autocommit mode), made whole by
    ``create`` first if there is none. Raises :class:`RegistryUnusable`."""
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        if not path.exists():
            _create_whole(path, create)
        if path.is_file() and path.stat().st_size == 0:
            raise damaged(path, "it is empty, 0 bytes: its index of the runs is lost")
        return _open(path)
    except sqlite3.Error as exc:
        raise unusable(exc, path) from None


def _open(path: Path) -> sqlite3.Connection:
    """The one place a connection is made (tests wrap it to simulate a read-only or full disk)."""
    con = sqlite3.connect(path, timeout=BUSY_TIMEOUT_S, isolation_level=None)
    con.row_factory = sqlite3.Row
    return con


def _create_whole(path: Path, create: Callable[[sqlite3.Connection], None]) -> None:
    """Build a registry beside ``path`` and link it into place unless another process did first
    (where the filesystem has no hard links, SQLite creates it in place)."""
    tmp = path.with_name(f"{path.name}.new-{os.getpid()}-{threading.get_ident()}")
    try:
        with closing(_open(tmp)) as con:
            create(con)
        try:
            os.link(tmp, path)
        except FileExistsError:
            pass  # another process created it first: theirs is whole too, and it is used
        except OSError:
            if not path.exists():
                with closing(_open(path)) as con:
                    create(con)
    finally:
        tmp.unlink(missing_ok=True)


@contextmanager
def writing(con: sqlite3.Connection) -> Iterator[sqlite3.Connection]:
    """One write transaction, holding the registry's write lock from its start (so a
    concurrent writer waits up to :data:`BUSY_TIMEOUT_S` instead of failing midway)."""
    con.execute("BEGIN IMMEDIATE")
    try:
        yield con
    except BaseException:
        if con.in_transaction:
            con.execute("ROLLBACK")
        raise
    con.execute("COMMIT")
