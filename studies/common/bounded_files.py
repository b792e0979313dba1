"""Input files read with bounds: a study file, a lift or pressure table, a tolerance file must be
a regular file no larger than its cap, so ``/dev/zero``, a FIFO or a runaway log given as input
is refused at once with one sentence instead of being read until memory runs out (or forever).

The file is opened without blocking (a FIFO would otherwise wait for a writer), checked on the
open descriptor (no race with a rename) and read up to one byte past its cap (``/proc`` files
report a size of 0).
"""

from __future__ import annotations

import os
import stat
from pathlib import Path

from studies.common.errors import StudyError

STUDY_FILE_BYTES = 128 * 1024
"""Largest study file [bytes]: tomllib reads 0.4–1 MB/s (2 loaded cores to idle), so any study
under this cap is checked in under a second whatever its level lists (about 20 000 levels fit);
the shipped studies are 1–4 kB."""
TABLE_FILE_BYTES = 16 * 1024 * 1024
"""Largest lift, pressure or tolerance table [bytes] (a measured table of 10⁵ rows is ~2 MB)."""
UTF8_BOM = "\ufeff"


class InputFileError(StudyError):
    """An input file that is not a regular file, is larger than its cap or cannot be read."""


def read_bounded_bytes(path: str | Path, what: str, cap: int) -> bytes:
    """The bytes of ``path`` (``what`` names it in messages, e.g. ``"study file"``)."""
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK)
    except FileNotFoundError:
        raise InputFileError(f"{what} {path}: no such file") from None
    except OSError as exc:
        raise InputFileError(f"{what} {path}: cannot be read ({exc.strerror})") from None
    info = os.fstat(fd)
    if not stat.S_ISREG(info.st_mode):
        os.close(fd)
        raise InputFileError(f"{what} {path} is {_kind(info.st_mode)}, not a regular file")
    with os.fdopen(fd, "rb") as file:
        if info.st_size > cap:
            raise InputFileError(_too_large(path, what, f"{info.st_size} bytes", cap))
        try:
            data = file.read(cap + 1)
        except OSError as exc:
            raise InputFileError(f"{what} {path}: cannot be read ({exc.strerror})") from None
    if len(data) > cap:
        raise InputFileError(_too_large(path, what, f"more than {cap} bytes", cap))
    return data


def read_bounded_text(path: str | Path, what: str, cap: int) -> str:
    """The UTF-8 text of ``path`` (a leading byte-order mark is dropped); see
    :func:`read_bounded_bytes`."""
    data = read_bounded_bytes(path, what, cap)
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        msg = f"{what} {path} is not UTF-8 text (byte {exc.start}: {data[exc.start : exc.start + 1]!r})"
        raise InputFileError(msg) from None
    return text.removeprefix(UTF8_BOM)


def _too_large(path: str | Path, what: str, size: str, cap: int) -> str:
    return f"{what} {path} has {size}: at most {cap} bytes are read"


def _kind(mode: int) -> str:
    kinds = (
        (stat.S_ISDIR, "a folder"),
        (stat.S_ISFIFO, "a FIFO (named pipe)"),
        (stat.S_ISCHR, "a character device"),
        (stat.S_ISBLK, "a block device"),
        (stat.S_ISSOCK, "a socket"),
    )
    return next((name for test, name in kinds if test(mode)), "not a regular file")
