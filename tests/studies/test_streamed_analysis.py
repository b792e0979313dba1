"""The analysis of a full factorial too large to hold: its level codes computed from the run
index and each response read from a scratch file a block at a time.

Expected values: the same analysis of the same results held in memory in one block (the
path every study up to 2²⁰ runs takes, itself checked against closed forms and statsmodels in
test_analysis, test_sums_of_squares and test_sensitivity). Blocks of 7 runs put a study of
60 runs on the streamed path.
"""

from __future__ import annotations

import itertools
import json
import tempfile
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from engine_kernels.valvetrain import rocker
from studies.analysis import grid_codes, scratch, sensitivity, taguchi
from studies.analysis.analyze import analyze, with_level_codes
from studies.common import blocks
from studies.run.results import open_results, write_netcdf
from studies.scenes.linkage.summaries import linkage_status_summary
from studies.scenes.valve.summaries import dynamics_status_summary

SHAPE = {"speed": 3, "a": 5, "b": 4}  # speed (operating) first: rows gathered by column


def factorial_results(seed: int, operating: tuple[str, ...] = ("speed",)) -> xr.Dataset:
    """A full factorial in grid order with a smooth response, one with NaN meaning "best"
    and an inf, one with NaN meaning "unknown" (left out) and a pass/fail flag."""
    rng = np.random.default_rng(seed)
    cells = np.array(list(itertools.product(*(range(n) for n in SHAPE.values()))))
    runs = len(cells)
    s, a, b = cells.T.astype(float)
    smooth = 1e3 + s * a + b**2 + rng.normal(0, 0.1, runs)
    gap = rng.uniform(0, 1, runs) + a
    gap[rng.choice(runs, 9, replace=False)] = np.nan
    gap[rng.integers(runs)] = np.inf
    patchy = rng.normal(0, 1, runs) + b
    patchy[rng.choice(runs, 6, replace=False)] = np.nan
    coords = {}
    for (f, n), c in zip(SHAPE.items(), cells.T, strict=True):
        coords[f] = ("run", np.linspace(1, 2, n)[c], {"units": "mm"})
        coords[f"{f}_level"] = ("run", c.astype(np.int32))
    flag = (smooth > np.median(smooth)).astype(np.int8)
    return xr.Dataset(
        {
            "smooth": ("run", smooth, {"units": "N", "better": "smaller"}),
            "gap": ("run", gap, {"units": "mm", "better": "smaller", "none_means": "best"}),
            "patchy": ("run", patchy, {"units": "mm", "better": "larger"}),
            "ok": ("run", flag, {"flag_values": [0, 1], "flag_meanings": "fail pass",
                                 "better": "larger"}),
        },
        coords=coords,
        attrs={"design": "full_factorial", "factors": json.dumps(list(SHAPE)),
               "responses": '["smooth", "gap", "patchy", "ok"]',
               "operating_factors": json.dumps(list(operating))},
    )  # fmt: skip


def assert_same(streamed: xr.Dataset, held: xr.Dataset) -> None:
    assert set(streamed.variables) == set(held.variables)
    for name in held.variables:
        a, b = streamed[name].values, held[name].values
        if a.dtype.kind == "f":
            np.testing.assert_allclose(a, b, rtol=1e-12, atol=1e-9, equal_nan=True, err_msg=name)
        else:
            np.testing.assert_array_equal(a, b, err_msg=name)


@pytest.mark.parametrize(("seed", "operating"), [(0, ("speed",)), (1, ()), (2, ("speed",))])
def test_streamed_analysis_equals_the_analysis_held_in_memory(
    seed: int, operating: tuple[str, ...], tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    ds = factorial_results(seed, operating)
    held = analyze(ds)
    path = write_netcdf(ds, tmp_path / "results.nc")
    reads, rows = [], []
    original = scratch.ScratchArray._read
    monkeypatch.setattr(
        scratch.ScratchArray, "_read", lambda self, key: reads.append(key) or original(self, key)
    )
    column = scratch.ScratchColumn.__getitem__
    monkeypatch.setattr(
        scratch.ScratchColumn,
        "__getitem__",
        lambda self, key: rows.append(key) or column(self, key),
    )
    monkeypatch.setattr(blocks, "BLOCK", 7)
    monkeypatch.setattr(sensitivity, "BLOCK", 7)
    lazy = with_level_codes(open_results(path))
    assert all(grid_codes.computed(lazy[f"{f}_level"].variable) for f in SHAPE)
    assert_same(analyze(lazy), held)
    assert reads, "the responses were not read from the scratch file"
    assert rows, "no scratch column was read (the optimum's row tables, the ANOVA's finite runs)"


def test_grid_codes_are_the_stored_codes(tmp_path: Path) -> None:
    ds = factorial_results(3)
    computed = with_level_codes(open_results(write_netcdf(ds, tmp_path / "results.nc")))
    for f in SHAPE:
        stored = ds[f"{f}_level"].values
        np.testing.assert_array_equal(computed[f"{f}_level"].values, stored)
        picks = np.array([0, 7, 8, 33, 59])
        np.testing.assert_array_equal(computed[f"{f}_level"].values[picks], stored[picks])


def test_runs_out_of_grid_order_keep_their_codes_in_memory(tmp_path: Path) -> None:
    ds = factorial_results(4).isel(run=np.random.default_rng(4).permutation(60))
    codes = with_level_codes(open_results(write_netcdf(ds, tmp_path / "results.nc")))
    for f in SHAPE:
        assert grid_codes.computed(codes[f"{f}_level"].variable) is None
        np.testing.assert_array_equal(codes[f"{f}_level"].values, ds[f"{f}_level"].values)


def test_without_a_scratch_file_the_response_is_read_where_it_is(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    ds = factorial_results(5)
    held = analyze(ds)
    path = write_netcdf(ds, tmp_path / "results.nc")

    def full_disk(*args: object, **kwargs: object) -> None:
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(scratch.tempfile, "TemporaryFile", full_disk)
    monkeypatch.setattr(blocks, "BLOCK", 7)
    monkeypatch.setattr(sensitivity, "BLOCK", 7)
    assert_same(analyze(with_level_codes(open_results(path))), held)


def test_a_scratch_column_reads_back_what_was_written_and_a_cut_file_raises() -> None:
    """Expected values: the values written (a file that lost its end would read as whatever
    the buffer held, so it must raise instead)."""
    values = np.random.default_rng(3).normal(size=50)
    with tempfile.TemporaryFile() as file:
        column = scratch.ScratchColumn(50, float, file)
        column[0:30] = values[:30]
        column[30:50] = values[30:]
        np.testing.assert_array_equal(column[0:50], values)
        np.testing.assert_array_equal(column[10:40:3], values[10:40:3])
        assert column[7] == values[7]
        file.truncate(40 * 8)
        with pytest.raises(OSError, match="short read"):
            column[20:50]


@pytest.mark.parametrize("seed", range(20))
def test_grid_codes_of_any_range_are_the_division_formula(seed: int) -> None:
    rng = np.random.default_rng(seed)
    count, stride = int(rng.integers(1, 9)), int(rng.integers(1, 50))
    runs = count * stride * int(rng.integers(1, 5))
    codes = grid_codes.GridCodes(runs, count, stride)
    start = int(rng.integers(0, runs))
    stop = int(rng.integers(start, runs + 1))
    expected = (np.arange(start, stop) // stride) % count  # the definition, run by run
    np.testing.assert_array_equal(codes._range(start, stop), expected)


def test_level_values_of_grid_codes_are_read_at_the_first_run_of_each_level() -> None:
    # GridCodes.first_runs (level x stride, no run read) against the search over the stored codes
    ds = factorial_results(6)
    grid = ds.assign_coords(grid_codes.grid_coordinates(ds, list(SHAPE), list(SHAPE.values())))
    for f, count in SHAPE.items():
        codes = grid_codes.computed(grid[f"{f}_level"].variable)
        assert codes is not None
        stored = ds[f"{f}_level"].values
        np.testing.assert_array_equal(codes.first_runs(), blocks.first_runs(stored, count))
        assert taguchi.level_values(grid, f) == taguchi.level_values(ds, f)


@pytest.mark.parametrize("seed", range(4))
def test_status_summaries_over_blocks_list_what_a_whole_array_search_finds(
    seed: int, monkeypatch: pytest.MonkeyPatch
) -> None:
    rng = np.random.default_rng(seed)
    runs = int(rng.integers(1, 90))
    status = rng.choice([0, 0, 0, 1, 2, 3], size=runs).astype(np.int8)
    chain = rng.choice([rocker.ROCKER_OK, rocker.ROCKER_OK, 1, 2, 4, 3], size=runs).astype(np.int8)
    ds = xr.Dataset({"status": ("run", status), "chain_status": ("run", chain)})
    monkeypatch.setattr(blocks, "BLOCK", 7)
    text = "\n".join(dynamics_status_summary(ds) + linkage_status_summary(ds))
    for name, values, groups in (
        ("status", status, [status == code for code in (1, 2, 3)]),
        (
            "chain_status",
            chain,
            [(chain != rocker.ROCKER_OK) & ((chain & f) != 0) for f in (1, 2, 4)],
        ),
    ):
        bad = np.flatnonzero(values != (0 if name == "status" else rocker.ROCKER_OK))
        if bad.size:
            assert f"({name}) at {bad.size} of {runs} points" in text
        for group in groups:
            found = np.flatnonzero(group)
            if found.size:  # count and the first 20, from the whole array
                shown = ", ".join(map(str, found[:20])) + (", …" if found.size > 20 else "")
                assert f": {found.size} (runs {shown})" in text
