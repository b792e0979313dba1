"""Figure jobs for tests/studies/test_figure_pool.py, importable by a worker process (a test
module is not: pytest imports it by path)."""

from __future__ import annotations

import os
import time
from pathlib import Path


def drawn_by(tag: str) -> list[Path]:
    """A figure job that names the process that ran it."""
    return [Path(f"{tag}-{os.getpid()}")]


def dies_in_a_worker(parent: int) -> list[Path]:
    """Ends a worker at once, as a worker killed by the system would end; drawn in ``parent``
    it returns a path."""
    if os.getpid() != parent:
        os._exit(1)
    return [Path("drawn here")]


def fails(kind: type[Exception]) -> list[Path]:
    raise kind("no display")


def writes_after(path: Path, seconds: float) -> list[Path]:
    """A slow figure: waits, then writes ``path``."""
    time.sleep(seconds)
    path.write_bytes(b"late")
    return [path]
