"""Runs without a value, stated where they act (issue 23, item 3).

The shipped reed study: at length 25 mm, 3 of the 15 design points have no crossing of any
engine order up to max_order — the best designs. ``first_crossing_order`` declares
``none_means = "best"``, so those points count at the best order seen (a bound), not dropped.
Expected level means are recomputed here from the results with numpy.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import xarray as xr

from studies.analysis import missing
from studies.analysis.analyze import analyze
from studies.analysis.filled_array import filled_variable
from studies.define.plan import plan_study
from studies.report.markdown_report import report_text
from studies.report.plots import main_effects_figure
from studies.report.text import format_tables
from studies.run.results import build_dataset
from studies.run.runner import evaluate

NAME = "first_crossing_order"


@pytest.fixture(scope="module")
def reed() -> xr.Dataset:
    plan = plan_study("reed_resonance")
    return build_dataset(plan, evaluate(plan, progress=False), {})


def test_reed_no_crossing_counts_as_best_at_length_25(reed: xr.Dataset) -> None:
    y = reed[NAME].values
    at_25 = reed["length_level"].values == 0
    assert reed[NAME].attrs["none_means"] == "best"
    assert np.isnan(y[at_25]).sum() == 3  # the three points
    assert np.isnan(y).sum() == 3  # ... and no others
    best = np.nanmax(y)  # larger is better: the highest engine order that crosses
    assert best == 3.0  # engine order 3 = max_order
    expected = np.where(np.isnan(y[at_25]), best, y[at_25]).mean()  # 15 runs, 3 at the bound
    an = analyze(reed)
    r = an.sel(response=NAME, term="length")
    assert float(r.k.values[0]) == pytest.approx(expected, rel=1e-12)
    assert float(r.k.values[0]) > np.nanmean(y[at_25])  # dropping them made 25 mm look worse
    assert int(r.bounded.values[0]) == 3
    assert int(r.left_out.values.sum()) == 0
    assert float(an["best_bound"].sel(response=NAME)) == best
    assert int(r.best_level) == 0  # 25 mm: the highest crossing orders, none counted as best
    assert "left out" not in str(an["anova_note"].sel(response=NAME).values)  # all 75 runs
    assert int(an["dof"].sel(response=NAME, source="total")) == 74
    text = format_tables(an, NAME)
    assert "†" in text
    assert "length = 25 mm: 3 of 15" in text
    assert "best value seen (3)" in text
    report = report_text(reed, an, [NAME])
    assert "length = 25 mm: 3 of 15" in report


def test_unknown_leaves_runs_out_and_says_how_many_per_level(reed: xr.Dataset) -> None:
    ds = reed.copy()
    ds[NAME].attrs["none_means"] = "unknown"
    y = ds[NAME].values
    at_25 = ds["length_level"].values == 0
    an = analyze(ds)
    r = an.sel(response=NAME, term="length")
    assert float(r.k.values[0]) == pytest.approx(np.nanmean(y[at_25]), rel=1e-12)  # 12 runs
    assert int(r.left_out.values[0]) == 3
    assert int(r.left_out.values[1:].sum()) == 0
    assert "3 run(s) with no finite value" in str(an["anova_note"].sel(response=NAME).values)
    text = format_tables(an, NAME)
    assert "*" in text
    assert "length = 25 mm: 3 of 15" in text
    ax = main_effects_figure(an, NAME).axes[0]  # the length panel
    hollow = [line for line in ax.get_lines() if line.get_markerfacecolor() == "white"]
    assert len(hollow) == 1
    np.testing.assert_allclose(hollow[0].get_xdata(), [25.0])
    assert any(t.get_text() == "3/15 left out" for t in ax.texts)


def test_inf_is_a_value_beyond_every_finite_one(tmp_path: Path) -> None:
    # A smaller-is-better response with +inf at two runs: they count at the worst finite value
    # (a bound), and the runs table prints "inf", never NaN or a dash.
    ds = xr.Dataset(
        {"stress": ("run", np.array([1.0, 2.0, np.inf, 4.0, np.inf, 6.0]),
                    {"units": "MPa", "better": "smaller"})},
        coords={"a": ("run", np.repeat([1.0, 2.0, 3.0], 2), {"units": "mm"}),
                "a_level": ("run", np.repeat([0, 1, 2], 2)),
                "b": ("run", np.tile([5.0, 6.0], 3), {"units": "N"}),
                "b_level": ("run", np.tile([0, 1], 3))},
        attrs={"design": "full_factorial", "factors": '["a", "b"]', "responses": '["stress"]'},
    )  # fmt: skip
    an = analyze(ds)
    r = an.sel(response="stress")
    assert float(r.worst_bound) == 6.0
    np.testing.assert_allclose(r.k.sel(term="a").values[:3], [1.5, 5.0, 6.0])
    np.testing.assert_array_equal(r.bounded.sel(term="a").values[:3], [0, 1, 1])
    assert int(r.optimum_run.values[0]) == 0  # the best computed point is finite
    text = report_text(ds, an, ["stress"])
    assert "| 3 | 2 | 5 | inf |" in text


@pytest.mark.parametrize("name", [NAME, "first_crossing_speed", "second_crossing_order"])
def test_no_crossing_is_the_best_computed_point(reed: xr.Dataset, name: str) -> None:
    """none_means = "best": a run without a crossing is better than every computed value (S2 of
    the report re-read: "Best first_crossing_order: 3 in run 7" while runs 10, 13, 14 have no
    crossing). Brute force over results.nc: the best run must be one of the NaN runs, the
    one whose levels have the best main effects (pandas groupby of the values with the NaN
    runs at the best value seen), and the report says what it is and that several tie."""
    y = reed[name].values
    none = np.flatnonzero(np.isnan(y))
    assert none.size >= 2
    filled = np.where(np.isnan(y), np.nanmax(y), y)  # larger is better: the bound is the max
    frame = pd.DataFrame(
        {f: reed[f"{f}_level"].values for f in ("length", "thickness", "material")}
    )
    score = sum(frame[f].map(pd.Series(filled).groupby(frame[f]).mean()).to_numpy() for f in frame)
    expected = int(none[np.argmax(score[none])])
    an = analyze(reed)
    r = an.sel(response=name)
    assert int(r.optimum_run.values[0]) == expected
    assert int(r.optimum_ties) == none.size
    report = report_text(reed, an, [name])
    line = next(x for x in report.splitlines() if x.startswith(f"Best {name}"))
    max_order = json.loads(reed.attrs["settings"])["max_order"]
    assert f"**no crossing up to order {max_order:g}** in run {expected + 1} " in line
    assert "none_means = best" in line
    assert f"{none.size} level combinations share this best value" in report
    if name == NAME:  # the runs: 10, 13 and 14 (1-based) have no crossing up to 3
        np.testing.assert_array_equal(none + 1, [10, 13, 14])


def test_the_trade_off_never_shows_a_bound_as_a_computed_value(reed: xr.Dataset) -> None:
    # Two responses: the value table gives each at its own optimum and at the chosen levels;
    # a run without a crossing reads as such, never as the order it was counted at.
    an = analyze(reed)
    report = report_text(reed, an, [NAME, "first_frequency"])
    chosen = {f: int(an["chosen_level"].sel(term=f)) for f in ("length", "thickness", "material")}
    hit = np.ones(reed.sizes["run"], dtype=bool)
    for f, level in chosen.items():
        hit &= reed[f"{f}_level"].values == level
    (run,) = np.flatnonzero(hit)  # brute force: the one run at the chosen levels
    y = reed[NAME].values
    own = int(an["optimum_run"].sel(response=NAME).values[0])
    cells = ["no crossing up to order 3" if np.isnan(y[i]) else f"{y[i]:.4g}" for i in (own, run)]
    assert f"| {NAME} | larger | {cells[0]} | {cells[1]} |" in report


@pytest.mark.parametrize("sense", ["smaller", "larger", "none"])
@pytest.mark.parametrize("meaning", ["best", "worst", "unknown"])
def test_lazily_filled_values_equal_the_filled_response_at_any_runs(
    tmp_path: Path, sense: str, meaning: str
) -> None:
    # Reference: missing.fill over the whole response, then indexed; the lazy variable reads
    # the stored file at the runs asked for (a slice, a scattered list, one run).
    rng = np.random.default_rng(5)
    y = rng.normal(size=2000)
    y[rng.random(2000) < 0.2] = np.nan
    y[rng.random(2000) < 0.05] = np.inf
    y[rng.random(2000) < 0.05] = -np.inf
    ran = rng.random(2000) < 0.9
    xr.Dataset({"y": ("run", y)}).to_netcdf(tmp_path / "r.nc")
    expected = missing.fill(y, ran, meaning, sense)
    with xr.open_dataset(tmp_path / "r.nc", cache=False) as ds:
        assert expected.rule is not None
        lazy = filled_variable(ds["y"].variable, ran, expected.rule)
        for runs in (slice(100, 700), rng.choice(2000, 50), [1999]):
            got = lazy[runs].values
            np.testing.assert_array_equal(got, expected.values[runs])
        np.testing.assert_array_equal(lazy.values, expected.values)
