"""Labelled results: one ``xarray.Dataset`` per run, written to compressed netCDF4.

Layout (dimension ``run`` = design point):

* coordinates ``<factor>`` (physical value, ``units`` as written in the study) and
  ``<factor>_level`` (0-based level index) for every factor; ``<name>_level`` alone for the
  empty orthogonal-array columns (error columns) and for the interaction columns (named in the
  attribute ``interaction_columns``: column name → the two factors); design labels such as
  ``swept_factor``; the attribute ``array_columns`` maps every name to its 1-based column;
* scalar responses on ``run``; curves on ``run × <angle>`` only when the study asks; with
  ``[noise]`` both gain a ``noise`` dimension after ``run`` (the noise cases) and every noise
  factor's value is the coordinate ``<factor>_noise`` on ``run × noise``;
* ``units`` and ``long_name`` on every variable; the study text, design, provenance and
  timings as global attributes (str/number only: dicts as JSON strings, booleans as ints).
"""

from __future__ import annotations

import errno
import json
import math
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Final

import netCDF4
import numpy as np
import xarray as xr
from xarray.backends import NetCDF4DataStore
from xarray.backends.netCDF4_ import NETCDF4_PYTHON_LOCK

from studies.common.blocks import code_range, first_runs, run_slices
from studies.common.errors import OutputsError, StudyError
from studies.define.plan import Plan, noise_label
from studies.run.runner import Evaluation
from studies.scenes.base import NOT_EVALUATED

COMPRESSION_LEVEL: Final = 4
COMPRESSION = {"zlib": True, "complevel": COMPRESSION_LEVEL}
# netCDF-C keeps a cache of decompressed chunks per variable (64 MiB by default): reading or
# writing every variable of a 10⁷-run file once, in order, would fill a gigabyte of them. One
# mebibyte holds the few chunks that sequential access touches.
CHUNK_CACHE_BYTES = 1 << 20
PASS_FAIL: Final = "not_evaluated fails passes"
ORDER_BLOCK: Final = 1 << 20  # runs placed at once when a full factorial's grid order is made
RUN_CHUNK: Final = 4096  # runs per netCDF chunk of a variable along run (coordinates too)
NOISE: Final = "noise"  # the dimension of the noise cases of each design point
NOISE_SUFFIX: Final = "_noise"  # <factor>_noise: a noise factor's value per run and case


def small_chunk_cache() -> None:
    """Make netCDF files opened from now on keep a small chunk cache per variable."""
    netCDF4.set_chunk_cache(CHUNK_CACHE_BYTES)


def open_results(path: Path) -> xr.Dataset:
    """A results file opened lazily, memory flat in its size: variables are read when used
    and not kept (``cache=False``), with a small chunk cache, and no pandas index is built
    for ``run`` (10⁷ runs: 100 MB; runs are selected by position, ``isel``)."""
    small_chunk_cache()
    return readable(path, cache=False, create_default_indexes=False)


def readable(path: Path | str, **options: Any) -> xr.Dataset:
    """``xr.open_dataset(path, **options)`` of a results file, or :class:`OutputsError` naming
    the file when it is none: a file no netCDF reader recognises (empty, damaged header) or
    a netCDF file without the ``run`` dimension every results file has."""
    try:
        ds = xr.open_dataset(path, **options)
    except ValueError:
        size = Path(path).stat().st_size
        what = "it is empty" if size == 0 else f"no netCDF reader recognises its {size} bytes"
        msg = f"{path} cannot be read as a results file: {what} (a damaged or foreign file)"
        raise OutputsError(msg) from None
    if "run" not in ds.dims:
        ds.close()
        msg = f"{path} is not a results file: it has no 'run' dimension (a damaged or foreign file)"
        raise OutputsError(msg)
    return ds


def build_dataset(plan: Plan, ev: Evaluation, attrs: dict[str, Any]) -> xr.Dataset:
    """The Dataset of a finished evaluation held in memory; ``attrs`` are added as global
    attributes. (A run streams the same layout to disk: :mod:`studies.run.results_writer`.)"""
    ds = layout(plan, attrs)
    data_vars: dict[str, Any] = {}
    for name in plan.responses:
        if name not in ev.scalars:
            continue  # a status response missing from chunks an older version checkpointed
        dims, dtype, attrs_r = response_layout(plan, name)
        values = stored_values(ev.scalars[name], dtype)
        data_vars[name] = (
            dims,
            values.reshape(plan.runs, -1) if len(dims) > 1 else values,
            attrs_r,
        )
    for name in plan.definition.curves:
        dims, _, attrs_c = curve_layout(plan, name)
        curve = ev.curves[name]
        shape = (plan.runs, plan.noise_cases, curve.shape[-1])
        data_vars[name] = (dims, curve.reshape(shape) if len(dims) > 2 else curve, attrs_c)
    return ds.assign(data_vars)


def run_dims(plan: Plan) -> tuple[str, ...]:
    """The dimensions of a scalar response: ``run``, and ``noise`` for a study with noise."""
    return ("run", NOISE) if plan.definition.noise is not None else ("run",)


def is_scalar(variable: xr.DataArray) -> bool:
    """Whether ``variable`` is laid out as a scalar response: a value per design point
    (``run``), or per design point and noise case (``run × noise``)."""
    return variable.dims in (("run",), ("run", NOISE))


@dataclass(frozen=True)
class RunCoordinate:
    """A coordinate with a value per design point (or per point and noise case): its values
    are made for a block of runs at a time (:func:`run_coordinates`)."""

    name: str
    dims: tuple[str, ...]
    dtype: np.dtype
    attrs: dict[str, Any]
    values: Callable[[slice], np.ndarray]  # the values of the runs ``part``


def run_coordinates(plan: Plan) -> list[RunCoordinate]:
    """The numeric coordinates along ``run``, in the order of the results file: the run
    number, the noise factors' values, each factor's value and level index, the empty and
    interaction columns' level indices."""
    d, scene, design = plan.definition, plan.scene, plan.design

    def codes(name: str) -> Callable[[slice], np.ndarray]:
        return lambda part: np.asarray(design.levels[name][part]).astype(np.int32)

    def factor(name: str) -> Callable[[slice], np.ndarray]:
        return lambda part: np.asarray(plan.factor_values(name, part))

    def noise(values: np.ndarray) -> Callable[[slice], np.ndarray]:
        return lambda part: values[part]

    def run(part: slice) -> np.ndarray:
        return np.arange(*part.indices(plan.runs))

    out = [RunCoordinate("run", ("run",), np.dtype(np.int64), {"long_name": "design point"}, run)]
    for name, values in plan.noise_values.items():
        param = scene.parameter(name)
        assert param is not None
        long_name = f"{param.long_name} under noise"
        attrs = {"units": param.units, "long_name": long_name}
        dims = ("run", NOISE)
        out.append(RunCoordinate(f"{name}{NOISE_SUFFIX}", dims, values.dtype, attrs, noise(values)))
    for f in d.factors:
        param = scene.parameter(f.name)
        attrs = {"units": f.units, "long_name": param.long_name if param else f.name}
        dtype = np.asarray(f.levels).dtype
        out.append(RunCoordinate(f.name, ("run",), dtype, attrs | {"role": f.role}, factor(f.name)))
        attrs = {"units": "1", "long_name": f"level index of {f.name}"}
        int32 = np.dtype(np.int32)
        out.append(RunCoordinate(f"{f.name}_level", ("run",), int32, attrs, codes(f.name)))
    for e in design.error_columns:
        attrs = {"units": "1", "long_name": f"empty array column {e} (error)"}
        out.append(RunCoordinate(f"{e}_level", ("run",), np.dtype(np.int32), attrs, codes(e)))
    for name, (a, b) in design.interactions.items():
        attrs = {"units": "1", "long_name": f"interaction column {a} x {b}"}
        out.append(RunCoordinate(f"{name}_level", ("run",), np.dtype(np.int32), attrs, codes(name)))
    return out


def layout(plan: Plan, attrs: dict[str, Any], per_run: bool = True) -> xr.Dataset:
    """Coordinates and global attributes of a run's results, without its responses; without
    the numeric coordinates along ``run`` unless ``per_run`` (the writer adds those block by
    block: :class:`studies.run.results_writer.ResultsWriter`)."""
    d, scene, design = plan.definition, plan.scene, plan.design
    every = run_coordinates(plan)
    kept = every if per_run else [c for c in every if not numeric(c.dtype)]
    whole = {c.name: (c.dims, c.values(slice(None)), c.attrs) for c in kept}
    coords: dict[str, Any] = {"run": whole.pop("run")} if "run" in whole else {}
    if d.noise is not None:
        coords[NOISE] = (NOISE, np.arange(plan.noise_cases), {"long_name": "noise case"})
    coords |= whole
    for label, values in design.labels.items():
        coords[label] = ("run", values.astype(str), {"long_name": label.replace("_", " ")})
    if d.curves:
        axis = scene.curve_axis
        assert axis is not None
        coords[axis.name] = (
            axis.name,
            scene.curve_coordinate(plan.settings),
            {"units": axis.units, "long_name": axis.long_name},
        )
    ds = xr.Dataset(coords=coords)
    ds.attrs = {
        "title": f"{d.name}: {d.description}".strip(": "),
        "study_name": d.name,
        "scene": d.scene,
        "design": design.name,
        "factors": json.dumps([f.name for f in d.factors]),
        "operating_factors": json.dumps(
            [f.name for f in d.factors if f.role in ("operating", "model")]
        ),
        "model_factors": json.dumps([f.name for f in d.factors if f.role == "model"]),
        "error_columns": json.dumps(list(design.error_columns)),
        "interaction_columns": json.dumps({k: list(v) for k, v in design.interactions.items()}),
        **({} if d.pool is None else {"pool": json.dumps(list(d.pool))}),
        "array_columns": json.dumps(design.columns),
        "responses": json.dumps(list(d.responses)),
        "noise_factors": json.dumps([f.name for f in d.noise.factors] if d.noise else []),
        "noise_design": noise_label(d),
        "limits": json.dumps(d.limits),
        **(
            {"samples": d.samples, "seed": d.seed, "second_order": int(d.second_order)}
            if d.samples
            else {}
        ),
        "settings": json.dumps(d.settings),
        "study_toml": d.text,
        "Conventions": "CF-1.10",
        **global_attributes(attrs),
    }
    return ds


def numeric(dtype: np.dtype) -> bool:
    """Whether values of ``dtype`` are stored as numbers (compressed, chunked along run)."""
    return dtype.kind in "fiu"


def global_attributes(attrs: dict[str, Any]) -> dict[str, Any]:
    """Attributes netCDF can hold: dicts and lists as JSON strings, booleans as ints."""
    return {
        k: json.dumps(v) if isinstance(v, dict | list) else int(v) if isinstance(v, bool) else v
        for k, v in attrs.items()
    }


def response_layout(plan: Plan, name: str) -> tuple[tuple[str, ...], type, dict[str, Any]]:
    """Dimensions, stored type and attributes of a scalar response."""
    r = plan.scene.response(name)
    assert r is not None
    attrs_r: dict[str, Any] = {
        "units": r.units,
        "long_name": r.long_name,
        "better": plan.definition.sense.get(name, r.sense),
        "none_means": plan.definition.none_means.get(name, r.none_means),
    }
    if r.used_for:
        attrs_r["used_for"] = r.used_for
    if r.none_label:
        attrs_r["none_label"] = r.none_label.format(**plan.definition.settings)
    if r.bits:
        masks = {
            "flag_masks": np.array([1 << i for i in range(len(r.bits))], dtype=np.int8),
            "flag_meanings": " ".join(r.bits),
            "valid_range": np.array([0, (1 << len(r.bits)) - 1], dtype=np.int8),
            "comment": f"0: none of the bits set; {NOT_EVALUATED}: not evaluated",
        }
        return run_dims(plan), np.int8, attrs_r | masks
    meanings = ("fails", "passes") if r.flag else r.codes
    if not meanings:
        return run_dims(plan), np.float64, attrs_r
    flags = {
        "flag_values": np.arange(NOT_EVALUATED, len(meanings), dtype=np.int8),
        "flag_meanings": " ".join(("not_evaluated", *meanings)),
    }
    return run_dims(plan), np.int8, attrs_r | flags


def is_status(da: xr.DataArray) -> bool:
    """Whether a stored response is a status code or bit mask (counted, never averaged): it
    has CF flag attributes other than a pass/fail flag's."""
    meanings = str(da.attrs.get("flag_meanings", ""))
    return "flag_masks" in da.attrs or ("flag_values" in da.attrs and meanings != PASS_FAIL)


def curve_layout(plan: Plan, name: str) -> tuple[tuple[str, ...], type, dict[str, Any]]:
    """Dimensions, stored type and attributes of a curve."""
    c, axis = plan.scene.curve(name), plan.scene.curve_axis
    assert c is not None
    assert axis is not None
    dims = (*run_dims(plan), axis.name)
    return dims, np.float64, {"units": c.units, "long_name": c.long_name}


def stored_values(values: np.ndarray, dtype: type) -> np.ndarray:
    """A response as stored: flags and status codes as int8 with -1 where not evaluated."""
    if dtype is np.int8:
        return np.where(np.isnan(values), NOT_EVALUATED, values).astype(np.int8)
    return values


def _run_chunks(variable: xr.DataArray) -> dict[str, tuple[int, ...]]:
    """netCDF chunks of RUN_CHUNK runs for a variable along ``run`` (the library's default
    for a 10⁷-run coordinate is 2·10⁶ runs: reading one run's value decompressed 16 MB)."""
    if not variable.dims or variable.dims[0] != "run" or 0 in variable.shape:
        return {}
    return {"chunksizes": (min(RUN_CHUNK, variable.shape[0]), *variable.shape[1:])}


def write_netcdf(ds: xr.Dataset, path: Path, atomic: bool = True) -> Path:
    """Write compressed netCDF4 (every numeric variable zlib-compressed); ``atomic``: under a
    temporary name renamed into place, so an interrupted write leaves no partial file.

    Written through xarray's netCDF4 store with the netCDF library's lock: ``to_netcdf`` first
    asks which Dask scheduler runs, and that imports Dask and dask.distributed (0.1-0.3 s) in
    every command that writes a file. A Dask-backed variable is computed first (the store would
    defer its write)."""
    encoding = {
        name: dict(COMPRESSION) | _run_chunks(ds[name])
        for name in list(ds.data_vars) + list(ds.coords)
        if ds[name].dtype.kind in "fiu"
    }
    if any(v.chunks for v in ds.variables.values()):
        ds = ds.compute()
    path.parent.mkdir(parents=True, exist_ok=True)
    target = path.with_name(path.name + ".writing") if atomic else path
    try:
        store = NetCDF4DataStore.open(target, mode="w", lock=NETCDF4_PYTHON_LOCK)
        try:
            ds.dump_to_store(store, encoding=encoding)
        finally:
            store.close()
    except RuntimeError as exc:  # the netCDF library's "HDF error" of a full disk
        target.unlink(missing_ok=True)
        raise netcdf_write_error(exc, path) from None
    if atomic:
        target.replace(path)
    return path


def netcdf_write_error(exc: RuntimeError, path: Path) -> OSError:
    """The netCDF library's write failure (it says "HDF error", not why) as an OSError
    naming the file, with the likely cause."""
    return OSError(errno.EIO, f"could not write netCDF ({exc}; is the disk full?)", str(path))


def grid_order(ds: xr.Dataset) -> tuple[list[str], tuple[int, ...], np.ndarray]:
    """Factors, level counts and the run at each grid cell (C order) of a complete full
    factorial; ValueError for any other design or an incomplete one."""
    factors, counts, order = grid_cells(ds)
    return factors, counts, np.arange(math.prod(counts)) if order is None else order


def grid_cells(ds: xr.Dataset) -> tuple[list[str], tuple[int, ...], np.ndarray | None]:
    """:func:`grid_order`, with None for the order when every run is at its own grid cell
    already (a full factorial as this engine writes it): no array of all runs is made then,
    the codes are read a block of runs at a time."""
    if ds.attrs.get("design") != "full_factorial":
        msg = f"a grid view needs a full_factorial result, this one is {ds.attrs.get('design')!r}"
        raise StudyError(msg)
    factors = json.loads(ds.attrs["factors"])
    runs = ds.sizes["run"]
    codes = [ds[f"{f}_level"].variable for f in factors]
    counts: tuple[int, ...] = ()
    for f, c in zip(factors, codes, strict=True):
        low, high = code_range(c)
        if low < 0:
            msg = f"the full factorial is incomplete: {f} has runs without a level"
            raise StudyError(msg)
        counts += (high + 1,)
    incomplete = f"the full factorial is incomplete: {runs} runs for {math.prod(counts)} grid cells"
    if runs != math.prod(counts):
        raise StudyError(incomplete)

    def cells(part: slice) -> np.ndarray:  # the C-order cell of each run of a block
        flat = np.zeros(part.stop - part.start, dtype=np.int64)
        for c, count in zip(codes, counts, strict=True):
            flat *= count
            flat += np.asarray(c[part])
        return flat

    parts = list(run_slices(runs))
    if all(np.array_equal(cells(p), np.arange(p.start, p.stop)) for p in parts):
        return factors, counts, None
    order = np.full(runs, -1, dtype=np.int64)
    for part in parts:
        order[cells(part)] = np.arange(part.start, part.stop)
    if (order < 0).any():
        raise StudyError(incomplete)
    return factors, counts, order


def as_grid(ds: xr.Dataset) -> xr.Dataset:
    """A full-factorial result with one dimension per factor instead of ``run``.

    Each factor is a dimension whose coordinate is its value at each level (so
    ``grid.sel(cam_speed=5000)`` works), with ``<factor>_level`` beside it; every variable on
    ``run`` is reshaped in O(N) (curves keep their angle dimension).
    """
    factors, counts, order = grid_order(ds)
    coords: dict[str, Any] = {}
    for f, n in zip(factors, counts, strict=True):
        first = first_runs(ds[f"{f}_level"].values, n)
        coords[f] = (f, ds[f].values[first], dict(ds[f].attrs))
        coords[f"{f}_level"] = (f, np.arange(n, dtype=np.int32), {"units": "1"})
    data_vars = {}
    for name, da in ds.data_vars.items():
        if da.dims[:1] != ("run",):
            continue
        values = da.values[order].reshape(counts + da.shape[1:])
        data_vars[name] = ((*factors, *da.dims[1:]), values, dict(da.attrs))
    coords |= {str(c): ds[c] for c in ds.coords if "run" not in ds[c].dims}
    return xr.Dataset(data_vars, coords=coords, attrs=dict(ds.attrs))
