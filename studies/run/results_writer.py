"""``results.nc`` written while the run computes: memory flat in the number of design points.

The file is laid out first (coordinates and global attributes by xarray, from the plan, then
one compressed variable per response and curve, netCDF chunks of the runner's chunk size);
each finished chunk of design points is then written into its slice of every variable. The
file is built under a temporary name and renamed into place when complete, so a run killed
while writing never leaves a partial ``results.nc`` behind. Reading it back gives the same
Dataset as :func:`studies.run.results.build_dataset` on the same values (tested).
"""

from __future__ import annotations

import contextlib
from collections.abc import Callable
from pathlib import Path
from typing import Any, TypeVar

import netCDF4
import numpy as np

from studies.define.plan import Plan
from studies.run.results import (
    COMPRESSION_LEVEL,
    curve_layout,
    global_attributes,
    layout,
    netcdf_write_error,
    response_layout,
    small_chunk_cache,
    stored_values,
    write_netcdf,
)
from studies.scenes import SceneOutput

PARTIAL_SUFFIX = ".partial"
T = TypeVar("T")


class ResultsWriter:
    """Write a run's results chunk by chunk; :meth:`close` puts the finished file in place."""

    def __init__(self, plan: Plan, path: Path, attrs: dict[str, Any], chunk_size: int) -> None:
        self.plan, self.path = plan, Path(path)
        self.partial = self.path.with_name(self.path.name + PARTIAL_SUFFIX)
        small_chunk_cache()
        write_netcdf(layout(plan, attrs), self.partial, atomic=False)
        self.file = self._netcdf(netCDF4.Dataset, self.partial, "r+")
        try:
            self._layout(plan, chunk_size)
        except RuntimeError as exc:
            self.abandon()
            raise netcdf_write_error(exc, self.partial) from None

    def _layout(self, plan: Plan, chunk_size: int) -> None:
        self.file.set_auto_maskandscale(False)
        cases = plan.noise_cases
        run_chunk = max(1, min(chunk_size // cases, plan.runs))
        self.dtypes: dict[str, type] = {}
        for name in plan.responses:
            dims, dtype, attrs_r = response_layout(plan, name)
            self._variable(name, dims, dtype, attrs_r, (run_chunk, cases)[: len(dims)])
        for name in plan.definition.curves:
            dims, dtype, attrs_c = curve_layout(plan, name)
            width = len(self.file.dimensions[dims[-1]])
            inner = (cases, width) if len(dims) > 2 else (width,)
            self._variable(name, dims, dtype, attrs_c, (run_chunk, *inner))

    def _variable(
        self,
        name: str,
        dims: tuple[str, ...],
        dtype: type,
        attrs: dict[str, Any],
        chunks: tuple[int, ...],
    ) -> None:
        variable = self.file.createVariable(
            name,
            np.dtype(dtype),
            dims,
            zlib=True,
            complevel=COMPRESSION_LEVEL,
            chunksizes=chunks,
            fill_value=np.nan if dtype is np.float64 else False,
        )
        variable.setncatts(attrs)
        self.dtypes[name] = dtype

    def width(self, curve: str) -> int:
        """The number of curve-axis values of ``curve`` (its second dimension)."""
        return int(self.file[curve].shape[1])

    def write(self, part: slice, out: SceneOutput) -> None:
        """Store one chunk's responses and curves (computed points ``part``: design points ×
        noise cases, flat)."""
        self._netcdf(self._write, part, out)

    def _write(self, part: slice, out: SceneOutput) -> None:
        n = self.plan.noise_cases  # a chunk holds whole design points (pipeline.chunk_cases)
        rows = slice(part.start // n, part.stop // n)
        noisy = self.plan.definition.noise is not None
        for name, values in out.scalars.items():
            if name in self.dtypes:
                stored = stored_values(values, self.dtypes[name])
                self.file[name][rows] = stored.reshape(-1, n) if noisy else stored
        for name, values in out.curves.items():
            self.file[name][rows] = values.reshape(-1, n, values.shape[-1]) if noisy else values

    def close(self, attrs: dict[str, Any]) -> Path:
        """Add the global ``attrs`` known only at the end (timings), finish the file and
        rename it into place; return its path."""
        self._netcdf(self.file.setncatts, global_attributes(attrs))
        self._netcdf(self.file.close)
        self.partial.replace(self.path)
        return self.path

    def abandon(self) -> None:
        """Close and delete the unfinished file (the run's checkpoints keep its chunks).
        Never raises: it runs while another error (often a full disk) is being reported."""
        with contextlib.suppress(Exception):
            if self.file.isopen():
                self.file.close()
        with contextlib.suppress(OSError):
            self.partial.unlink(missing_ok=True)

    def _netcdf(self, call: Callable[..., T], *args: Any) -> T:
        """``call(*args)``, the netCDF library's RuntimeError (a full disk) as an OSError."""
        try:
            return call(*args)
        except RuntimeError as exc:
            raise netcdf_write_error(exc, self.partial) from None
