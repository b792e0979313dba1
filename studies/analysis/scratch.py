"""A response of more than a block of runs held for the analysis on disk, not in memory.

The analysis reads each response many times (means, centring, level sums per term, the grid
optimum, the variance decomposition). Held in memory, one response of 10⁸ runs is 800 MB;
read again from ``results.nc`` each time, every pass pays the decompression (about 3 s at 10⁸
runs). So a response above :data:`studies.common.blocks.BLOCK` runs is decompressed once,
into an unlinked scratch file of doubles beside the results, and read back a block at a time:
the operating system's page cache holds it (memory it can reclaim and read again from the
disk), the process holds one block. The file has no name, so nothing is left behind, whatever
ends the process. Where no scratch file can be written (a full or read-only disk), the
response is read from ``results.nc`` a block at a time: slower, the same numbers.

Like :mod:`studies.analysis.filled_array`, an xarray backend array (``BackendArray`` with
``explicit_indexing_adapter``).
"""

from __future__ import annotations

import os
import tempfile
from collections.abc import Iterator
from contextlib import ExitStack, contextmanager
from contextvars import ContextVar
from pathlib import Path
from typing import IO, Any

import numpy as np
import xarray as xr
from xarray.backends import BackendArray
from xarray.core import indexing

from studies.common import blocks
from studies.common.blocks import run_slices

FOLDER: ContextVar[Path | None] = ContextVar("scratch_folder", default=None)
"""Where scratch files go while an analysis runs (:func:`in_folder`); None: the system's
temporary folder."""


class ScratchColumn:
    """``size`` values of one type in an unlinked scratch file, written and read a slice at
    a time (``column[a:b] = values``; ``column[a:b]``, ``column[i]``) with ``pwrite`` and
    ``pread``: a response, or a table per control combination of a grid, too large to hold.
    Closed with the ``stack`` it was made with."""

    ndim = 1

    def __init__(self, size: int, dtype: Any, file: IO[bytes]) -> None:
        self.size, self.shape, self.dtype, self.file = size, (size,), np.dtype(dtype), file

    def __len__(self) -> int:
        return self.size

    def __setitem__(self, part: slice, values: Any) -> None:
        start, _, _ = part.indices(self.size)
        data = np.ascontiguousarray(values, dtype=self.dtype).tobytes()
        os.pwrite(self.file.fileno(), data, start * self.dtype.itemsize)

    def __getitem__(self, key: slice | int) -> Any:
        if not isinstance(key, slice):
            return self[int(key) : int(key) + 1][0]
        start, stop, step = key.indices(self.size)
        values = np.empty(max(0, stop - start), self.dtype)  # filled by the read, not zeroed first
        read = (
            os.preadv(self.file.fileno(), [values.data], start * self.dtype.itemsize)
            if values.size
            else 0
        )
        if read < values.nbytes:
            raise OSError(f"scratch file ended before run {stop} (short read)")
        return values[::step]


class ScratchArray(BackendArray):
    """A :class:`ScratchColumn` as an xarray backend array (read where indexed)."""

    def __init__(self, column: ScratchColumn) -> None:
        self.column, self.shape, self.dtype = column, column.shape, column.dtype

    def __getitem__(self, key: indexing.ExplicitIndexer) -> Any:
        return indexing.explicit_indexing_adapter(
            key, self.shape, indexing.IndexingSupport.BASIC, self._read
        )

    def _read(self, key: tuple[Any, ...]) -> Any:
        (at,) = key
        return self.column[at]


def _scratch_file(stack: ExitStack) -> IO[bytes] | None:
    """An unlinked file in :data:`FOLDER`, closed with ``stack``; None when none can be made."""
    try:
        return stack.enter_context(tempfile.TemporaryFile(dir=FOLDER.get()))
    except OSError:
        return None


def column(size: int, dtype: Any, stack: ExitStack) -> Any:
    """``size`` values of ``dtype`` to fill and read a slice at a time: an array up to
    :data:`studies.common.blocks.BLOCK` (or when no scratch file can be made), else a
    :class:`ScratchColumn` closed with ``stack``."""
    file = None if size <= blocks.BLOCK else _scratch_file(stack)
    return np.empty(size, dtype) if file is None else ScratchColumn(size, dtype, file)


@contextmanager
def held(variable: xr.Variable) -> Iterator[xr.Variable]:
    """``variable`` (one value per run) as the analysis reads it while the block runs: in
    memory up to :data:`studies.common.blocks.BLOCK` runs (or when it is there already), else
    as doubles in a scratch file (in :data:`FOLDER`) read where indexed; from where it is when
    no scratch file can be written."""
    if variable.ndim != 1 or variable.size <= blocks.BLOCK or blocks.in_memory(variable):
        yield variable.copy(deep=False).load()
        return
    with ExitStack() as stack:
        copy = _written(variable, stack)
        if copy is None:
            yield variable
            return
        lazy = indexing.LazilyIndexedArray(ScratchArray(copy))
        yield xr.Variable(variable.dims, lazy, variable.attrs)


def _written(variable: xr.Variable, stack: ExitStack) -> ScratchColumn | None:
    """``variable`` as doubles in a :class:`ScratchColumn` (closed with ``stack``), written a
    block at a time; None when it cannot be written."""
    file = _scratch_file(stack)
    if file is None:
        return None
    copy = ScratchColumn(variable.size, float, file)
    try:
        for part in run_slices(variable.size):
            copy[part] = variable[part].values
    except OSError:
        return None
    return copy


@contextmanager
def in_folder(ds: xr.Dataset) -> Iterator[None]:
    """Scratch files beside the file ``ds`` was read from (its ``source`` encoding; else the
    system's temporary folder) while the block runs."""
    source = ds.encoding.get("source")
    token = FOLDER.set(Path(source).parent if source else None)
    try:
        yield
    finally:
        FOLDER.reset(token)
