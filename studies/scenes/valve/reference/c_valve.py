"""The C reference of the valve lane kernel (``valve_lanes.c``), built and called for the bench.

The issue sets the speed target as "a C -O3 kernel of this form"; rather than trust a figure
from another machine, ``python -m studies bench valve`` builds this C kernel with the
machine's compiler and times it on the same inputs in the same run. Built with ``$CC``
(default ``cc``), ``-O3 -march=native`` with FMA contraction (as the Numba kernels) and
OpenMP, once per source and flags, into a private cache folder of the user
(``$XDG_CACHE_HOME/engine_studies``, default ``~/.cache/engine_studies``, mode 0700): a library
is loaded only from a folder this user owns and nobody else can write, never from a predictable
name in a shared temporary folder. Without a C compiler the bench skips the comparison and
says so.
"""

from __future__ import annotations

import ctypes
import hashlib
import os
import shutil
import stat
import subprocess
from pathlib import Path

import numpy as np

SOURCE = Path(__file__).with_name("valve_lanes.c")
FLAGS = (
    "-O3",
    "-march=native",
    "-ffp-contract=fast",
    "-fno-trapping-math",
    "-fopenmp",
    "-shared",
    "-fPIC",
)
REAL = {np.dtype(np.float64): "double", np.dtype(np.float32): "float"}


class CompilerMissing(RuntimeError):
    """No C compiler (``$CC`` or ``cc``) on this machine."""


class CompileFailed(RuntimeError):
    """The compiler is there but rejected the C reference (or its flags, e.g. -fopenmp)."""


class UnsafeCacheFolder(CompileFailed):
    """The cache folder is not private to this user: a library there could be replaced."""


def cache_folder() -> Path:
    """This user's private folder for built libraries (created with mode 0700).

    Refused (``UnsafeCacheFolder``) when it belongs to another user or others may write it.
    """
    root = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    folder = Path(root) / "engine_studies"
    folder.mkdir(mode=0o700, parents=True, exist_ok=True)
    info = folder.lstat()
    if not stat.S_ISDIR(info.st_mode) or info.st_uid != os.getuid():
        msg = f"{folder} is not a folder of this user (uid {os.getuid()}): not loading from it"
        raise UnsafeCacheFolder(msg)
    if info.st_mode & (stat.S_IWGRP | stat.S_IWOTH):
        msg = f"{folder} is writable by other users (mode {info.st_mode & 0o777:o}): chmod 700 it"
        raise UnsafeCacheFolder(msg)
    return folder


def _check_owned(library: Path) -> None:
    """Load only a regular file of this user that no one else may write: a library another
    user put in the cache would run as this one."""
    info = library.lstat()
    if not stat.S_ISREG(info.st_mode) or info.st_uid != os.getuid():
        msg = f"{library} is not a file of this user (uid {os.getuid()}): delete it to rebuild"
        raise UnsafeCacheFolder(msg)
    if info.st_mode & (stat.S_IWGRP | stat.S_IWOTH):
        msg = f"{library} is writable by other users (mode {info.st_mode & 0o777:o}): delete it"
        raise UnsafeCacheFolder(msg)


def build(dtype: np.dtype) -> ctypes.CDLL:
    """Compile (or reuse) the C kernel with lanes of ``dtype`` (float64 or float32)."""
    compiler = os.environ.get("CC", "cc")
    if shutil.which(compiler) is None:
        raise CompilerMissing(f"C compiler {compiler!r} not found (set CC)")
    command = [compiler, *FLAGS, f"-DREAL={REAL[np.dtype(dtype)]}"]
    key = hashlib.sha256(SOURCE.read_bytes() + " ".join(command).encode()).hexdigest()[:16]
    library = cache_folder() / f"valve_c_{key}.so"
    if not library.exists():
        partial = library.with_suffix(f".{os.getpid()}.tmp")
        result = subprocess.run(
            [*command, "-o", str(partial), str(SOURCE), "-lm"],
            capture_output=True,
            text=True,
            check=False,
        )
        if result.returncode != 0:
            raise CompileFailed(f"{compiler} failed on {SOURCE.name}: {result.stderr.strip()}")
        partial.replace(library)
    _check_owned(library)
    lib = ctypes.CDLL(str(library))
    for name in ("valve_lanes", "valve_one_case"):
        getattr(lib, name).restype = None
    return lib


def valve_response_c(
    lib: ctypes.CDLL,
    kernel: str,
    excitation: np.ndarray,
    table_step: float,
    table_start: float,
    params: np.ndarray,
    out: np.ndarray,
) -> None:
    """Run ``kernel`` ("valve_lanes" or "valve_one_case") of ``lib`` on the scene's inputs.

    excitation : (3, nodes) array  Rows Y [m], Y' [m/rad], Y'' [m/rad²], in the precision
                                   ``lib`` was built for; table_step, table_start [rad]. params: (n, 11) ``P_*``
                                    rows; out: (n, 17) ``O_*`` rows, written.
    """
    table = np.ascontiguousarray(excitation[:3])
    rows = np.ascontiguousarray(params, dtype=np.float64)
    if out.dtype != np.float64 or not out.flags.c_contiguous:
        raise ValueError("out must be a C-contiguous float64 array")
    getattr(lib, kernel)(
        table.ctypes.data_as(ctypes.c_void_p),
        ctypes.c_long(table.shape[1]),
        ctypes.c_double(table_step),
        ctypes.c_double(table_start),
        rows.ctypes.data_as(ctypes.c_void_p),
        ctypes.c_long(rows.shape[0]),
        out.ctypes.data_as(ctypes.c_void_p),
    )
