"""Range analysis, ANOVA, text tables and main-effect plots on small labelled Datasets.

Expected values come from statsmodels (``ols`` + ``anova_lm(typ=1)``, an independent ANOVA),
from closed forms (2-level SS = (T1 - T2)²/n; the F(1, 1) tail 1 - (2/π)·arctan√F) and from
direct numpy level means.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pandas as pd
import pytest
import xarray as xr
from hypothesis import given, settings
from hypothesis import strategies as st
from statsmodels.formula.api import ols
from statsmodels.stats.anova import anova_lm

from studies.analysis.analyze import analyze, anova, range_analysis
from studies.analysis.statistics import f_quantile, f_survival
from studies.define.designs.orthogonal_arrays import orthogonal_array
from studies.report.plots import main_effects_figure, save_main_effects
from studies.report.text import format_tables

# Physical values of the 12V150 L9 study (physics §9): A, B, C; D is the empty column.
VALUES = {"A": [7.0, 9.0, 11.0], "B": [3.5, 4.5, 5.5], "C": [12.0, 14.0, 16.0]}
UNITS = {"A": "deg", "B": "mm/rad^2", "C": "mm/rad^2"}


def make_dataset(
    levels: np.ndarray,
    factors: list[str],
    error: list[str],
    y: np.ndarray,
    values: dict[str, list[float]] | None = None,
    better: str | None = None,
) -> xr.Dataset:
    """A results Dataset: column i of ``levels`` is factor i, then the error columns."""
    values = values or {}
    coords = {}
    for i, f in enumerate(factors):
        lv = levels[:, i]
        phys = np.asarray(values.get(f, np.arange(lv.max() + 1) * 10.0))[lv]
        coords[f] = ("run", phys, {"units": UNITS.get(f, "mm")})
        coords[f"{f}_level"] = ("run", lv.astype(np.int32))
    for j, e in enumerate(error):
        coords[f"{e}_level"] = ("run", levels[:, len(factors) + j].astype(np.int32))
    attrs = {"units": "MPa", "long_name": "max contact stress"}
    if better:
        attrs["better"] = better
    ds = xr.Dataset({"stress": ("run", y, attrs)}, coords=coords)
    ds.attrs = {"factors": json.dumps(factors), "error_columns": json.dumps(error)}
    return ds


def statsmodels_table(ds: xr.Dataset, factors: list[str]) -> pd.DataFrame:
    # Prefixed column names: a factor called C would clash with patsy's C().
    frame = pd.DataFrame({f"x{f}": ds[f"{f}_level"].values for f in factors})
    frame["y"] = ds["stress"].values
    formula = "y ~ " + " + ".join(f"C(x{f})" for f in factors)
    return anova_lm(ols(formula, data=frame).fit(), typ=1)


def assert_matches_statsmodels(table: pd.DataFrame, ds: xr.Dataset, factors: list[str]):
    ref = statsmodels_table(ds, factors)
    for f in factors:
        row = ref.loc[f"C(x{f})"]
        assert table.loc[f, "SS"] == pytest.approx(row["sum_sq"], rel=1e-10)
        assert table.loc[f, "dof"] == row["df"]
        assert table.loc[f, "F"] == pytest.approx(row["F"], rel=1e-9)
        assert table.loc[f, "P"] == pytest.approx(row["PR(>F)"], rel=1e-8)
    res = ref.loc["Residual"]
    assert table.loc["error", "SS"] == pytest.approx(res["sum_sq"], rel=1e-10)
    assert table.loc["error", "dof"] == res["df"]
    assert table.loc["total", "SS"] == pytest.approx(ref["sum_sq"].sum(), rel=1e-12)


@pytest.fixture
def l9() -> xr.Dataset:
    rng = np.random.default_rng(7)
    y = rng.normal(800.0, 40.0, size=9)
    return make_dataset(orthogonal_array("L9"), ["A", "B", "C"], ["D"], y, VALUES)


def test_anova_l9_with_empty_column_matches_statsmodels(l9):
    table = anova(l9, "stress")
    assert_matches_statsmodels(table, l9, ["A", "B", "C"])
    assert table.loc["error", "dof"] == 2
    assert table.attrs["pooled"] == []
    assert table.attrs["units"] == "MPa"
    assert table.loc[["A", "B", "C", "error"], "contribution"].sum() == pytest.approx(100.0)
    # For an orthogonal array the error SS is the SS of the empty column D (closed form).
    y, d = l9["stress"].values, l9["D_level"].values
    ss_d = sum(3 * (y[d == lv].mean() - y.mean()) ** 2 for lv in range(3))
    assert table.loc["error", "SS"] == pytest.approx(ss_d, rel=1e-10)


def test_anova_l18_matches_statsmodels():
    rng = np.random.default_rng(3)
    factors = ["P", "Q", "R", "S", "T", "U", "V"]
    y = rng.normal(5.0, 1.0, size=18)
    ds = make_dataset(orthogonal_array("L18"), factors, ["e8"], y)
    assert_matches_statsmodels(anova(ds, "stress"), ds, factors)


def test_anova_full_factorial_main_effects_matches_statsmodels():
    # 3 x 2 x 4 full factorial, no empty column: the error is the 17 interaction dof.
    grid = np.array([(a, b, c) for a in range(3) for b in range(2) for c in range(4)])
    rng = np.random.default_rng(11)
    y = grid @ np.array([1.0, -2.0, 0.5]) + rng.normal(0.0, 0.3, size=len(grid))
    ds = make_dataset(grid, ["A", "B", "C"], [], y, VALUES | {"B": [3.5, 4.5], "C": [1.0, 2, 3, 4]})
    del ds.attrs["error_columns"]
    table = anova(ds, "stress")
    assert_matches_statsmodels(table, ds, ["A", "B", "C"])
    assert table.loc["error", "dof"] == 24 - 1 - (2 + 1 + 3)


def test_anova_drops_missing_runs_like_statsmodels(l9):
    l9["stress"].values[4] = np.nan
    table = anova(l9, "stress")
    ref = statsmodels_table(l9, ["A", "B", "C"])  # its formula API drops the NaN row too
    for f in ["A", "B", "C"]:
        assert table.loc[f, "SS"] == pytest.approx(ref.loc[f"C(x{f})", "sum_sq"], rel=1e-9)
    assert table.loc["error", "dof"] == 1
    assert "1 run(s)" in table.attrs["note"]


def test_anova_l4_closed_form():
    # L4: A in column 1, B in column 2, column 3 empty. y = 10, 12, 15, 19.
    # SS = (T1 - T2)² / 4: A (22 - 34)²/4 = 36, B (25 - 31)²/4 = 9, e (29 - 27)²/4 = 1;
    # total 46. F(1, 1) tail: P = 1 - (2/π)·arctan(√F).
    y = np.array([10.0, 12.0, 15.0, 19.0])
    ds = make_dataset(orthogonal_array("L4"), ["A", "B"], ["e"], y)
    table = anova(ds, "stress")
    assert table.loc[["A", "B", "error", "total"], "SS"].tolist() == pytest.approx([36, 9, 1, 46])
    assert table.loc[["A", "B", "error", "total"], "dof"].tolist() == [1, 1, 1, 3]
    assert table.loc["A", "F"] == pytest.approx(36.0)
    assert table.loc["B", "F"] == pytest.approx(9.0)
    assert table.loc["A", "P"] == pytest.approx(1 - 2 / math.pi * math.atan(6.0), rel=1e-10)
    assert table.loc["B", "P"] == pytest.approx(1 - 2 / math.pi * math.atan(3.0), rel=1e-10)
    assert table.loc["A", "contribution"] == pytest.approx(100 * 36 / 46)


def level_ss(y: np.ndarray, levels: np.ndarray) -> float:
    """Closed-form main-effect SS of a balanced column: Σ n_i (ȳ_i - ȳ)²."""
    return sum((levels == lv).sum() * (y[levels == lv].mean() - y.mean()) ** 2
               for lv in np.unique(levels))  # fmt: skip


def test_saturated_l9_pools_the_smallest_factor():
    rng = np.random.default_rng(5)
    table = orthogonal_array("L9")
    # Strong A, B, C effects and no D effect, plus noise.
    y = 3.0 * table[:, 0] - 2.0 * table[:, 1] + 1.0 * table[:, 2] + rng.normal(0, 0.1, 9)
    ds = make_dataset(table, ["A", "B", "C", "D"], [], y)
    ss = {f: level_ss(y, table[:, i]) for i, f in enumerate("ABCD")}
    smallest = min(ss, key=ss.get)
    result = anova(ds, "stress")
    assert result.attrs["pooled"] == [smallest]
    assert smallest in result.attrs["note"]
    assert "pooled" in result.attrs["note"]
    assert bool(result.loc[smallest, "pooled"])
    assert np.isnan(result.loc[smallest, "F"])
    assert np.isnan(result.loc[smallest, "P"])
    assert result.loc["error", "SS"] == pytest.approx(ss[smallest], rel=1e-10)
    assert result.loc["error", "dof"] == 2
    kept = [f for f in "ABCD" if f != smallest]
    for f in kept:
        assert result.loc[f, "SS"] == pytest.approx(ss[f], rel=1e-10)
        assert result.loc[f, "F"] == pytest.approx((ss[f] / 2) / (ss[smallest] / 2))


def test_explicit_pool_and_no_pool():
    table = orthogonal_array("L9")
    y = np.array([1.0, 4.0, 2.0, 8.0, 5.0, 7.0, 3.0, 9.0, 6.0])
    ds = make_dataset(table, ["A", "B", "C", "D"], [], y)
    pooled = anova(ds, "stress", pool=["B", "C"])
    assert pooled.attrs["pooled"] == ["B", "C"]
    assert pooled.loc["error", "dof"] == 4
    expected = level_ss(y, table[:, 1]) + level_ss(y, table[:, 2])
    assert pooled.loc["error", "SS"] == pytest.approx(expected, rel=1e-10)
    unpooled = anova(ds, "stress", pool=[])
    assert unpooled.attrs["pooled"] == []
    assert unpooled.loc["error", "dof"] == 0
    assert unpooled["F"].isna().all()
    assert "no degrees of freedom" in unpooled.attrs["note"]
    with pytest.raises(ValueError, match="cannot pool"):
        anova(ds, "stress", pool=["Z"])


def test_range_analysis_matches_numpy_level_means():
    rng = np.random.default_rng(2)
    table = orthogonal_array("L18")
    factors = ["P", "Q", "R"]
    y = rng.normal(10.0, 2.0, size=18)
    ds = make_dataset(table[:, [0, 1, 2, 7]], factors, ["e"], y, better="larger")
    ra = range_analysis(ds, "stress")
    assert ra.attrs["sense"] == "larger"
    assert ra["k"].attrs["units"] == "MPa"
    for i, f in enumerate(factors):
        lv = table[:, i]
        means = np.array([y[lv == v].mean() for v in range(lv.max() + 1)])
        k = ra.k.sel(factor=f).values
        np.testing.assert_allclose(k[: len(means)], means, rtol=1e-12)
        assert np.isnan(k[len(means) :]).all()  # P has 2 levels, the others 3
        assert float(ra.R.sel(factor=f)) == pytest.approx(means.max() - means.min())
        assert int(ra.best_level.sel(factor=f)) == int(np.argmax(means))
        np.testing.assert_allclose(
            ra.level_value.sel(factor=f).values[: len(means)], np.arange(len(means)) * 10.0
        )
    order = np.argsort(-ra.R.values)
    assert (ra["rank"].values[order] == np.arange(1, 4)).all()


def test_ranges_equal_to_round_off_share_their_rank() -> None:
    # y = 0.1·a + 0.1·b + 0.3·c on an L9 (levels 0, 1, 2): R_A and R_B are 0.2 in exact
    # arithmetic; with 1e-15 added to one level mean they differ by round-off only, and must
    # not be ranked 2 and 3 (the luffing study ranked two identical k tables 1 and 2).
    table = orthogonal_array("L9")
    y = 0.1 * table[:, 0] + 0.1 * table[:, 1] + 0.3 * table[:, 2] + 1e-15 * (table[:, 0] == 2)
    ds = make_dataset(table, ["A", "B", "C"], ["D"], y)
    ra = range_analysis(ds, "stress")
    assert abs(float(ra.R.sel(factor="A")) - float(ra.R.sel(factor="B"))) > 0.0
    assert ra["rank"].sel(factor=["C", "A", "B"]).values.tolist() == [1, 2, 2]
    # a real difference of 1e-6 relative still ranks
    y[table[:, 0] == 2] += 1e-7
    ra = range_analysis(make_dataset(table, ["A", "B", "C"], ["D"], y), "stress")
    assert ra["rank"].sel(factor=["C", "A", "B"]).values.tolist() == [1, 2, 3]


def test_best_level_respects_sense(l9):
    y = l9["stress"].values
    for sense, pick in [("smaller", np.argmin), ("larger", np.argmax)]:
        ra = range_analysis(l9, "stress", sense=sense)
        for f in ["A", "B", "C"]:
            lv = l9[f"{f}_level"].values
            means = [y[lv == v].mean() for v in range(3)]
            assert int(ra.best_level.sel(factor=f)) == int(pick(means))
    with pytest.raises(ValueError, match="sense"):
        range_analysis(l9, "stress", sense="nominal")


def test_bad_names_are_reported(l9):
    with pytest.raises(ValueError, match="no response 'nope'"):
        anova(l9, "nope")
    with pytest.raises(ValueError, match="no level coordinate"):
        range_analysis(l9, "stress", factors=["A", "Z"])
    with pytest.raises(ValueError, match="both as factor and as error"):
        anova(l9, "stress", error=["A"])


@settings(max_examples=30, deadline=None)
@given(
    st.lists(st.floats(-1e3, 1e3, allow_nan=False, allow_subnormal=False), min_size=9, max_size=9)
)
def test_sums_of_squares_add_up(y):
    # Law: for an orthogonal array the factor and error SS add to the total SS, and range
    # analysis level means average to the grand mean for every factor (balance).
    y = np.array(y)
    ds = make_dataset(orthogonal_array("L9"), ["A", "B", "C"], ["D"], y)
    table = anova(ds, "stress")
    parts = table.loc[["A", "B", "C", "error"], "SS"].sum()
    assert parts == pytest.approx(table.loc["total", "SS"], rel=1e-9, abs=1e-6)
    ra = range_analysis(ds, "stress")
    np.testing.assert_allclose(ra.k.mean("level").values, y.mean(), rtol=1e-9, atol=1e-9)


def test_format_tables_shows_units_sources_and_notes():
    table = orthogonal_array("L9")
    y = np.array([1.0, 4.0, 2.0, 8.0, 5.0, 7.0, 3.0, 9.0, 6.0])
    ds = make_dataset(table, ["A", "B", "C", "D"], [], y, VALUES | {"D": [1.0, 2.0, 3.0]})
    text = format_tables(analyze(ds, ["stress"]), "stress")
    for expected in ["Range analysis", "[MPa]", "(MPa)^2", "deg", "7, 9, 11", "error", "total",
                     "(pooled)", "Note:"]:  # fmt: skip
        assert expected in text, expected


def test_main_effects_figure_has_one_panel_per_factor(l9):
    fig = main_effects_figure(analyze(l9, ["stress"]), "stress")
    axes = fig.axes
    assert len(axes) == 3
    assert axes[0].get_xlabel() == "A [deg]"
    assert axes[0].get_ylabel() == "stress [MPa]"
    assert "max contact stress" in fig.get_suptitle()
    line, grand = axes[0].get_lines()
    np.testing.assert_allclose(line.get_xdata(), VALUES["A"])
    assert grand.get_linestyle() == "--"
    assert grand.get_ydata()[0] == pytest.approx(l9["stress"].values.mean())


def test_factor_without_numeric_values_shows_its_level_names(l9):
    shapes = np.array(["lin", "sin_full", "fillet"])[l9["A_level"].values]
    ds = l9.assign_coords(A=("run", shapes))
    ra = range_analysis(ds, "stress")
    assert np.isnan(ra.level_value.sel(factor="A")).all()
    assert np.isfinite(ra.level_value.sel(factor="B")).all()
    an = analyze(ds, ["stress"])
    ax = main_effects_figure(an, "stress").axes[0]
    assert ax.get_xlabel() == "A"
    np.testing.assert_allclose(ax.get_lines()[0].get_xdata(), [1, 2, 3])
    assert [t.get_text() for t in ax.get_xticklabels()] == ["lin", "sin_full", "fillet"]
    # analysis.txt names the levels of a categorical factor and its best one
    lines = format_tables(an, "stress").splitlines()
    row = next(line for line in lines if line.strip().startswith("A "))  # the range table
    assert "lin, sin_full, fillet" in row
    best = int(an["best_level"].sel(response="stress", term="A"))
    assert row.rstrip().endswith(f"{best + 1} ({['lin', 'sin_full', 'fillet'][best]})")


def test_save_main_effects_writes_pngs(l9, tmp_path):
    l9["flow"] = l9["stress"] * 2.0
    l9["flow"].attrs = {"units": "kg/s"}
    an = analyze(l9, ["stress", "flow"])
    paths = save_main_effects(an, ["stress", "flow"], tmp_path / "plots")
    assert [p.name for p in paths] == ["main_effects_stress.png", "main_effects_flow.png"]
    for p in paths:
        data = p.read_bytes()
        assert data.startswith(b"\x89PNG\r\n\x1a\n")
        assert len(data) > 1000


def test_main_effects_over_more_than_two_decades_get_a_log_axis(l9):
    spread = l9.assign(error=("run", 10.0 ** l9["A_level"].values * 1e-3, {"units": "mm"}))
    an = analyze(spread, ["error", "stress"])
    assert main_effects_figure(an, "error").axes[0].get_yscale() == "log"  # 1e-3 … 1e-1
    assert main_effects_figure(an, "stress").axes[0].get_yscale() == "linear"


@settings(max_examples=300, deadline=None)
@given(
    f=st.one_of(st.floats(-5.0, 1e4), st.sampled_from([0.0, math.inf, math.nan])),
    dof=st.integers(0, 80),
    dof_error=st.integers(0, 500),
    q=st.floats(0.5, 0.999),
)
def test_the_f_distribution_is_scipy_stats_bit_for_bit(
    f: float, dof: int, dof_error: int, q: float
) -> None:
    # the analysis reads F's tail and quantile from scipy.special (scipy.stats costs a second
    # of start-up); reference: scipy.stats.f itself
    from scipy import stats

    expected = float(stats.f.sf(f, dof, dof_error))
    got = f_survival(f, dof, dof_error)
    assert got == expected or (math.isnan(got) and math.isnan(expected))
    expected_q = float(stats.f.ppf(q, dof, dof_error))
    got_q = f_quantile(q, dof, dof_error)
    assert got_q == expected_q or (math.isnan(got_q) and math.isnan(expected_q))
