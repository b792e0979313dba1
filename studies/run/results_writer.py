"""``results.nc`` written while the run computes: memory flat in the number of design points.

The file is laid out first (the small coordinates and global attributes by xarray, from the
plan; the numeric coordinates along ``run`` block by block; then one compressed variable per
response and curve, netCDF chunks of the runner's chunk size);
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
    ORDER_BLOCK,
    RUN_CHUNK,
    curve_layout,
    global_attributes,
    layout,
    netcdf_write_error,
    numeric,
    response_layout,
    run_coordinates,
    small_chunk_cache,
    stored_values,
    write_netcdf,
)
from studies.scenes import SceneOutput

PARTIAL_SUFFIX = ".partial"
COORDINATE_BLOCK = ORDER_BLOCK  # runs of a coordinate made and written at once
T = TypeVar("T")


class ResultsWriter:
    """Write a run's results chunk by chunk; :meth:`close` puts the finished file in place."""

    def __init__(self, plan: Plan, path: Path, attrs: dict[str, Any], chunk_size: int) -> None:
        self.plan, self.path = plan, Path(path)
        self.partial = self.path.with_name(self.path.name + PARTIAL_SUFFIX)
        small_chunk_cache()
        write_netcdf(layout(plan, attrs, per_run=False), self.partial, atomic=False)
        self.file = self._netcdf(netCDF4.Dataset, self.partial, "r+")
        try:
            self._run_coordinates(plan)
            self._layout(plan, chunk_size)
        except RuntimeError as exc:
            self.abandon()
            raise netcdf_write_error(exc, self.partial) from None

    def _run_coordinates(self, plan: Plan) -> None:
        """The numeric coordinates along ``run``, written :data:`COORDINATE_BLOCK` runs at a
        time (a 10⁷-run study's held 0.8 GB at once when xarray wrote them), as xarray writes
        coordinates: compressed, chunked along run, NaN-filled floats, listed in the global
        ``coordinates`` attribute."""
        self.file.set_auto_maskandscale(False)
        if "run" not in self.file.dimensions:
            self.file.createDimension("run", plan.runs)
        listed = set(str(getattr(self.file, "coordinates", "")).split())
        for c in run_coordinates(plan):
            if not numeric(c.dtype):
                continue  # strings: laid out by xarray with the rest
            chunks = (
                min(RUN_CHUNK, plan.runs),
                *(len(self.file.dimensions[d]) for d in c.dims[1:]),
            )
            variable = self.file.createVariable(
                c.name,
                c.dtype,
                c.dims,
                zlib=True,
                complevel=COMPRESSION_LEVEL,
                shuffle=True,
                chunksizes=chunks,
                fill_value=np.nan if c.dtype.kind == "f" else None,
            )
            variable.setncatts(c.attrs)
            for start in range(0, plan.runs, COORDINATE_BLOCK):
                part = slice(start, min(start + COORDINATE_BLOCK, plan.runs))
                variable[part] = c.values(part)
            listed |= {c.name} - {"run"}
        if listed:
            self.file.setncattr("coordinates", " ".join(sorted(listed)))

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
