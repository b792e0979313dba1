"""S/N ratios, ANOVA with interaction columns, predicted optimum and its interval, confirmation
run and trade-off summary on small labelled Datasets.

Expected values come from the S/N definitions evaluated by hand (Phadke 1989, ch. 5), from
statsmodels (``ols`` + ``anova_lm(typ=1)`` and ``get_prediction``, an independent least-squares
fit whose confidence interval of the fitted mean equals Taguchi's n_eff interval on a balanced
array), from brute-force enumeration of level combinations and from noise-free additive data
whose optimum is known in closed form.
"""

from __future__ import annotations

import itertools
import json
import math
import tomllib

import numpy as np
import pandas as pd
import pytest
import xarray as xr
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy import stats
from statsmodels.formula.api import ols
from statsmodels.stats.anova import anova_lm

from studies.analysis import confirmation, prediction, taguchi, tradeoff
from studies.analysis.analyze import range_analysis
from studies.define import designs
from studies.define.designs.orthogonal_arrays import list_orthogonal_arrays, orthogonal_array


def make_dataset(
    design: designs.Design, y: np.ndarray | dict[str, np.ndarray], **attrs
) -> xr.Dataset:
    """A results Dataset as :mod:`studies.run.results` writes it, values 10·(level + 1) in mm."""
    coords = {}
    for f in design.factors:
        coords[f] = ("run", 10.0 * (design.levels[f] + 1), {"units": "mm"})
        coords[f"{f}_level"] = ("run", design.levels[f].astype(np.int32))
    for name in [*design.interactions, *design.error_columns]:
        coords[f"{name}_level"] = ("run", design.levels[name].astype(np.int32))
    ys = y if isinstance(y, dict) else {"y": y}
    data = {
        name: (("run", "replicate")[: values.ndim], values,
               {"units": "MPa", "long_name": f"stress {name}", "better": "smaller"})
        for name, values in ys.items()
    }  # fmt: skip
    ds = xr.Dataset(data, coords=coords)
    ds.attrs = {
        "design": design.name,
        "factors": json.dumps(list(design.factors)),
        "error_columns": json.dumps(list(design.error_columns)),
        "interaction_columns": json.dumps({k: list(v) for k, v in design.interactions.items()}),
        "array_columns": json.dumps(design.columns),
        **attrs,
    }
    return ds


def oa(array: str, factors: str, pairs=(), errors=()) -> designs.Design:
    counts = dict.fromkeys(factors, 3 if "9" in array or "27" in array else 2)
    return designs.orthogonal(array, counts, dict.fromkeys(factors), tuple(errors), list(pairs))


def frame(ds: xr.Dataset, names: list[str], response: str = "y") -> pd.DataFrame:
    # Prefixed column names: a factor called C would clash with patsy's C().
    out = pd.DataFrame({f"x{n}": ds[f"{n}_level"].values for n in names})
    out["y"] = ds[response].values
    return out


# --- S/N ratios ---------------------------------------------------------------------------------
def test_sn_ratios_match_their_definitions_by_hand() -> None:
    # smaller: (2² + 14²)/2 = 100 → -20 dB; larger: (1/4 + 1/4 + 1)/3 = 1/2 → 10·log10 2 dB;
    # nominal: ȳ = 10, s² = (4 + 0 + 4)/2 = 4 → 10·log10(100/4) = 10·log10 25 dB.
    y = xr.DataArray([[2.0, 14.0, np.nan], [2.0, 2.0, 1.0], [8.0, 10.0, 12.0]],
                     dims=("run", "replicate"))  # fmt: skip
    smaller = taguchi.signal_to_noise(y, "smaller")
    larger = taguchi.signal_to_noise(y, "larger")
    nominal = taguchi.signal_to_noise(y, "nominal")
    assert smaller.dims == ("run",)
    assert smaller.attrs["units"] == "dB"
    assert float(smaller[0]) == pytest.approx(-20.0, rel=1e-12)  # the NaN replicate is left out
    assert float(larger[1]) == pytest.approx(10 * math.log10(2.0), rel=1e-12)
    assert float(nominal[2]) == pytest.approx(10 * math.log10(25.0), rel=1e-12)
    # nominal of run 0: ȳ = 8, s² = (36 + 36)/1 = 72 → 10·log10(64/72)
    assert float(nominal[0]) == pytest.approx(10 * math.log10(64 / 72), rel=1e-12)


def test_sn_without_replicates_and_bad_kinds() -> None:
    # One observation: smaller -20·log10|y|, larger +20·log10|y|.
    y = xr.DataArray([10.0, 0.1], dims="run")
    np.testing.assert_allclose(taguchi.signal_to_noise(y, "smaller"), [-20.0, 20.0])
    np.testing.assert_allclose(taguchi.signal_to_noise(y, "larger"), [20.0, -20.0])
    with pytest.raises(ValueError, match="at least 2 observations"):
        taguchi.signal_to_noise(y, "nominal")
    with pytest.raises(ValueError, match="S/N kind"):
        taguchi.signal_to_noise(y, "biggest")


def test_larger_is_better_sn_of_a_value_at_or_below_zero_is_the_worst() -> None:
    # -10 log10 mean(1/y²) is defined for y > 0 and falls to -∞ as y falls to 0; 1/y² is the
    # same for -7 and 7, so a violated margin (or a concave cam's -∞) must not read as good.
    y = xr.DataArray([[7.0, 7.0], [-7.0, 7.0], [0.0, 7.0], [-np.inf, 7.0], [np.inf, np.inf]],
                     dims=("run", "replicate"))  # fmt: skip
    eta = taguchi.signal_to_noise(y, "larger").values
    assert eta[0] == pytest.approx(20 * math.log10(7.0), rel=1e-12)
    assert np.all(eta[1:4] == -np.inf)
    assert eta[4] == np.inf  # 1/∞² = 0: the best
    # the level of an L9 whose runs all have a negative value is never the S/N's best level
    design = oa("L9", "ABC", errors=["D"])
    values = np.where(design.levels["A"] == 0, -50.0, 1.0 + design.levels["A"])
    ds = taguchi.with_sn(make_dataset(design, values[:, None] * [1.0, 1.1]), "y", {"y": "larger"})
    ra = range_analysis(ds, "y_sn")
    assert int(ra.best_level.sel(factor="A")) == 2  # the largest positive values, not |-50|


def test_smaller_is_better_sn_is_none_where_a_value_is_below_zero() -> None:
    # -10 log10 mean(y²) is the distance from a target of 0: for y < 0 it rates -y as y, so
    # on an L9 whose level 1 of A holds the most negative (smallest) values it would call
    # that level the worst while the level means call it the best. Left out instead, and said.
    y = xr.DataArray([[3.0, 4.0], [0.0, 2.0]], dims=("run", "replicate"))
    eta = taguchi.signal_to_noise(y, "smaller").values
    assert eta[0] == pytest.approx(-10 * math.log10(12.5), rel=1e-12)  # mean(9, 16)
    assert eta[1] == pytest.approx(-10 * math.log10(2.0), rel=1e-12)
    design = oa("L9", "ABC", errors=["D"])
    values = np.where(design.levels["A"] == 0, -50.0, 1.0 + design.levels["A"])
    ds = make_dataset(design, values[:, None] * [1.0, 1.1])
    assert np.isnan(taguchi.with_sn(ds, "y", {"y": "smaller"})["y_sn"].values).all()
    ds["y"].attrs["better"] = "smaller"
    assert "y is below 0 in some runs" in taguchi.sn_left_out(ds, "y")
    ds["y"] = abs(ds["y"])
    assert taguchi.sn_left_out(ds, "y") == ""


@settings(max_examples=40, deadline=None)
@given(
    st.lists(st.floats(0.01, 1e3), min_size=2, max_size=6),
    st.floats(0.01, 100.0),
)
def test_sn_scaling_laws(values, k) -> None:
    # Laws of the definitions: scaling y by k shifts smaller-is-better by -20·log10 k and
    # larger-is-better by +20·log10 k; nominal-is-best (ȳ²/s²) does not change.
    y = xr.DataArray([values], dims=("run", "replicate"))
    shift = 20 * math.log10(k)
    for kind, sign in [("smaller", -1.0), ("larger", 1.0)]:
        base = float(taguchi.signal_to_noise(y, kind)[0])
        scaled = float(taguchi.signal_to_noise(k * y, kind)[0])
        assert scaled == pytest.approx(base + sign * shift, abs=1e-9)
    if np.ptp(values) > 1e-6 * max(values):
        base = float(taguchi.signal_to_noise(y, "nominal")[0])
        assert float(taguchi.signal_to_noise(k * y, "nominal")[0]) == pytest.approx(base, abs=1e-7)


def test_with_sn_adds_mean_and_sn_of_a_replicated_response() -> None:
    design = oa("L9", "ABC", errors=["D"])
    rng = np.random.default_rng(4)
    y = rng.uniform(1.0, 5.0, size=(9, 4))
    ds = taguchi.with_sn(make_dataset(design, y), "y", {"y": "nominal"})
    assert ds["y_mean"].dims == ("run",)
    np.testing.assert_allclose(ds["y_mean"], y.mean(axis=1), rtol=1e-12)
    assert ds["y_mean"].attrs["units"] == "MPa"
    expected = 10 * np.log10(y.mean(axis=1) ** 2 / y.var(axis=1, ddof=1))  # definition
    np.testing.assert_allclose(ds["y_sn"], expected, rtol=1e-12)
    attrs = ds["y_sn"].attrs
    assert (attrs["units"], attrs["better"], attrs["sn_kind"]) == ("dB", "larger", "nominal")
    assert ds["y_sn"].attrs["observations"] == 4
    ra = range_analysis(ds, "y_sn")  # the S/N is an ordinary run response for the analysis
    levels = ds["A_level"].values
    means = [expected[levels == lv].mean() for lv in range(3)]
    assert int(ra.best_level.sel(factor="A")) == int(np.argmax(means))


# --- ANOVA against statsmodels ----------------------------------------------------------------
# L27 with 12 three-level factors is the hard case: a design matrix with a dummy for every level
# would be rank-deficient and lstsq misjudged its rank; treatment coding keeps it full-rank.
ARRAYS = [pytest.param(info, id=info.name) for info in list_orthogonal_arrays()]


@pytest.mark.parametrize("info", ARRAYS)
def test_anova_matches_statsmodels_for_every_array(info) -> None:
    # Every column but the last carries a factor; the last is the error column (dof > 0).
    table = orthogonal_array(info.name)
    names = [f"F{i + 1}" for i in range(info.columns - 1)]
    counts = {n: info.levels[i] for i, n in enumerate(names)}
    design = designs.orthogonal(info.name, counts, {n: i + 1 for i, n in enumerate(names)}, ("e",))
    np.testing.assert_array_equal(design.levels["e"], table[:, -1])
    y = np.random.default_rng(info.runs + info.columns).normal(50.0, 5.0, size=info.runs)
    ds = make_dataset(design, y)
    result = taguchi.anova_table(ds, "y")
    ref = anova_lm(ols("y ~ " + " + ".join(f"C(x{n})" for n in names), frame(ds, names)).fit())
    for n in names:
        row = ref.loc[f"C(x{n})"]
        assert result.loc[n, "SS"] == pytest.approx(row["sum_sq"], rel=1e-8, abs=1e-9)
        assert result.loc[n, "dof"] == row["df"]
        assert result.loc[n, "F"] == pytest.approx(row["F"], rel=1e-7)
        assert result.loc[n, "P"] == pytest.approx(row["PR(>F)"], rel=1e-6, abs=1e-12)
    assert result.loc["error", "SS"] == pytest.approx(ref.loc["Residual", "sum_sq"], rel=1e-8)
    # error dof = N - 1 - Σ (s_i - 1): the empty column plus any dof the factors leave
    dof_error = info.runs - 1 - sum(s - 1 for s in info.levels[:-1])
    assert result.loc["error", "dof"] == ref.loc["Residual", "df"] == dof_error


@pytest.mark.parametrize(
    ("array", "factors", "pairs"),
    [("L8", "ABC", [("A", "B")]), ("L16", "ABCD", [("A", "B"), ("C", "D")]),
     ("L27", "ABCD", [("A", "B"), ("A", "C")])],
)  # fmt: skip
def test_interaction_columns_match_statsmodels_interaction_terms(array, factors, pairs) -> None:
    # The SS of an interaction's columns together is the SS of the A:B term of a least-squares
    # fit with main effects and that interaction, and F and P of the pair match its row.
    design = oa(array, factors, pairs)
    levels = np.array([design.levels[f] for f in factors]).T
    rng = np.random.default_rng(len(factors))
    y = levels @ rng.normal(0, 1, len(factors)) + rng.normal(0, 0.5, design.runs)
    a, b = design.levels["A"], design.levels["B"]
    y = y + 1.5 * (a == b)  # an A x B interaction
    ds = make_dataset(design, y)
    table = taguchi.anova_table(ds, "y")
    inter = taguchi.interaction_anova(table, ds)
    terms = [f"C(x{f})" for f in factors] + [f"C(x{p}):C(x{q})" for p, q in pairs]
    ref = anova_lm(ols("y ~ " + " + ".join(terms), frame(ds, list(factors))).fit())
    for p, q in pairs:
        row, mine = ref.loc[f"C(x{p}):C(x{q})"], inter.loc[f"{p} x {q}"]
        assert mine["SS"] == pytest.approx(row["sum_sq"], rel=1e-8)
        assert mine["dof"] == row["df"]
        assert mine["F"] == pytest.approx(row["F"], rel=1e-7)
        assert mine["P"] == pytest.approx(row["PR(>F)"], rel=1e-6)
    assert table.loc["error", "SS"] == pytest.approx(ref.loc["Residual", "sum_sq"], rel=1e-8)
    assert table.loc["error", "dof"] == ref.loc["Residual", "df"]


# --- predicted optimum --------------------------------------------------------------------------
def statsmodels_prediction(ds, terms_formula, names, levels, alpha=0.05):
    """Fitted mean and its confidence interval, and the single-observation interval."""
    fit = ols("y ~ " + terms_formula, frame(ds, names)).fit()
    point = pd.DataFrame({f"x{n}": [levels[n]] for n in names})
    pred = fit.get_prediction(point).summary_frame(alpha=alpha)
    return pred.iloc[0]


def test_predicted_optimum_matches_direct_computation_l9() -> None:
    design = oa("L9", "ABC", errors=["D"])
    y = np.random.default_rng(8).normal(800.0, 40.0, size=9)
    ds = make_dataset(design, y)
    p = prediction.predict_optimum(ds, "y")
    # Direct: level means, best = smallest, ŷ = T̄ + Σ (k_best - T̄).
    grand = y.mean()
    best = {f: int(np.argmin([y[design.levels[f] == lv].mean() for lv in range(3)])) for f in "ABC"}
    expected = grand + sum(y[design.levels[f] == best[f]].mean() - grand for f in "ABC")
    assert p.levels == best
    assert p.mean == pytest.approx(expected, rel=1e-12)
    assert p.n_eff == pytest.approx(9 / (1 + 6))
    assert p.error_dof == 2
    # Independent: least squares with the same terms (balanced array → same mean and interval).
    ref = statsmodels_prediction(ds, "C(xA) + C(xB) + C(xC)", ["A", "B", "C"], best)
    assert p.mean == pytest.approx(ref["mean"], rel=1e-12)
    assert p.interval == pytest.approx((ref["mean_ci_lower"], ref["mean_ci_upper"]), rel=1e-10)
    assert p.confirmation_interval == pytest.approx(
        (ref["obs_ci_lower"], ref["obs_ci_upper"]), rel=1e-10
    )
    # Brute force over all 27 combinations: none predicts lower.
    fit = ols("y ~ C(xA) + C(xB) + C(xC)", frame(ds, ["A", "B", "C"])).fit()
    grid = pd.DataFrame(list(itertools.product(range(3), repeat=3)), columns=["xA", "xB", "xC"])
    assert fit.predict(grid).min() == pytest.approx(p.mean, rel=1e-12)


def test_confirmation_interval_for_several_runs_and_larger_is_better() -> None:
    design = oa("L9", "ABC", errors=["D"])
    y = np.random.default_rng(9).normal(10.0, 2.0, size=9)
    ds = make_dataset(design, y)
    p = prediction.predict_optimum(ds, "y", sense="larger", alpha=0.1, confirmation_runs=3)
    best = {f: int(np.argmax([y[design.levels[f] == lv].mean() for lv in range(3)])) for f in "ABC"}
    assert p.levels == best
    # Ross (1996): ± sqrt(F(0.9; 1, ν_e) · V_e · (1/n_eff + 1/r)), F(1, ν) = t(0.95; ν)².
    d = design.levels["D"]
    ss_error = sum(3 * (y[d == lv].mean() - y.mean()) ** 2 for lv in range(3))
    ve = ss_error / 2
    t = stats.t.ppf(0.95, 2)
    assert p.error_ms == pytest.approx(ve, rel=1e-10)
    assert p.half_width == pytest.approx(t * math.sqrt(ve * 7 / 9), rel=1e-10)
    assert p.confirmation_half_width == pytest.approx(
        t * math.sqrt(ve * (7 / 9 + 1 / 3)), rel=1e-10
    )


def test_saturated_l9_prediction_uses_the_pooled_error() -> None:
    # All four columns are factors: the ANOVA pools the smallest SS, the model keeps three terms.
    design = oa("L9", "ABCD")
    table = orthogonal_array("L9")
    y = (
        3.0 * table[:, 0]
        - 2.0 * table[:, 1]
        + table[:, 2]
        + np.random.default_rng(5).normal(0, 0.1, 9)
    )
    ds = make_dataset(design, y)
    ss = {f: sum(3 * (y[table[:, i] == lv].mean() - y.mean()) ** 2 for lv in range(3))
          for i, f in enumerate("ABCD")}  # fmt: skip
    pooled = min(ss, key=ss.get)
    kept = [f for f in "ABCD" if f != pooled]
    p = prediction.predict_optimum(ds, "y")
    assert set(p.terms) == set(kept)
    assert p.error_dof == 2
    assert p.error_ms == pytest.approx(ss[pooled] / 2, rel=1e-10)
    ref = statsmodels_prediction(ds, " + ".join(f"C(x{f})" for f in kept), list("ABCD"), p.levels)
    assert p.mean == pytest.approx(ref["mean"], rel=1e-12)
    assert p.interval == pytest.approx((ref["mean_ci_lower"], ref["mean_ci_upper"]), rel=1e-10)
    unpooled = prediction.predict_optimum(ds, "y", pool=[])
    assert unpooled.error_dof == 0
    assert np.isnan(unpooled.half_width)


def test_optimum_with_an_interaction_is_the_best_cell_of_the_fitted_model() -> None:
    design = oa("L8", "ABC", [("A", "B")])
    a, b, c = (design.levels[f] for f in "ABC")
    y = 10 + 2 * a + 1 * b - 4 * a * b + 0.5 * c + np.random.default_rng(2).normal(0, 0.1, 8)
    ds = make_dataset(design, y)
    p = prediction.predict_optimum(ds, "y", sense="larger")
    assert set(p.terms) == {"A", "B", "C", "A_x_B"}
    formula = "C(xA) + C(xB) + C(xC) + C(xA):C(xB)"
    fit = ols("y ~ " + formula, frame(ds, ["A", "B", "C"])).fit()
    grid = pd.DataFrame(list(itertools.product(range(2), repeat=3)), columns=["xA", "xB", "xC"])
    predicted = fit.predict(grid)
    top = grid.iloc[int(np.argmax(predicted))]
    assert p.levels == {"A": top["xA"], "B": top["xB"], "C": top["xC"]}
    ref = statsmodels_prediction(ds, formula, ["A", "B", "C"], p.levels)
    assert p.mean == pytest.approx(ref["mean"], rel=1e-10)
    assert p.interval == pytest.approx((ref["mean_ci_lower"], ref["mean_ci_upper"]), rel=1e-9)


def test_predict_at_given_levels_and_bad_input() -> None:
    design = oa("L9", "ABC", errors=["D"])
    y = np.random.default_rng(3).normal(5.0, 1.0, size=9)
    ds = make_dataset(design, y)
    levels = {"A": 2, "B": 0, "C": 1}
    p = prediction.predict(ds, "y", levels)
    ref = statsmodels_prediction(ds, "C(xA) + C(xB) + C(xC)", ["A", "B", "C"], levels)
    assert p.mean == pytest.approx(ref["mean"], rel=1e-12)
    only_a = prediction.predict(ds, "y", levels, terms=["A"])  # n_eff = 9 / (1 + 2)
    assert only_a.mean == pytest.approx(y[design.levels["A"] == 2].mean(), rel=1e-12)
    assert only_a.n_eff == pytest.approx(3.0)
    with pytest.raises(ValueError, match="levels missing"):
        prediction.predict(ds, "y", {"A": 0})
    with pytest.raises(ValueError, match="unknown model term"):
        prediction.predict(ds, "y", levels, terms=["Z"])


# --- interaction means, confirmation run, trade-off ---------------------------------------------
def test_interaction_means_are_cell_means() -> None:
    design = oa("L9", "AB", [("A", "B")])
    y = np.arange(9.0) ** 1.5
    means = taguchi.interaction_means(make_dataset(design, y), "y", "A", "B")
    assert means.dims == ("A", "B")
    np.testing.assert_allclose(means["A"], [10.0, 20.0, 30.0])
    a, b = design.levels["A"], design.levels["B"]
    for i, j in itertools.product(range(3), repeat=2):
        assert float(means[i, j]) == pytest.approx(y[(a == i) & (b == j)].mean())


STUDY = """
name = "demo"
scene = "cam"
description = "demo"
responses = ["y"]
[design]
type = "L9"
error_columns = ["D"]
[parameters]
base_radius = 20.5
law = "six_segment"
cam_width = { value = 2.0, units = "cm" }
[factors.A]
levels = [10.0, 20.0, 30.0]
units = "mm"
column = 1
[factors.B]
levels = [10.0, 20.0, 30.0]
units = "mm"
[factors.C]
levels = [10.0, 20.0, 30.0]
units = "mm"
[sense]
y = "smaller"
"""


def test_confirmation_study_runs_the_chosen_levels_once() -> None:
    design = oa("L9", "ABC", errors=["D"])
    ds = make_dataset(design, np.arange(9.0), study_toml=STUDY, study_name="demo", run_id="r1")
    text = confirmation.confirmation_toml(ds, {"A": 2, "B": 0, "C": 1})
    study = tomllib.loads(text)
    original = tomllib.loads(STUDY)
    assert study["name"] == "demo_confirmation"
    assert study["design"] == {"type": "full_factorial"}
    assert study["factors"] == {
        "A": {"levels": [30.0], "units": "mm"},
        "B": {"levels": [10.0], "units": "mm"},
        "C": {"levels": [20.0], "units": "mm"},
    }
    for key in ["scene", "responses", "parameters", "sense"]:
        assert study[key] == original[key]
    assert text.startswith("# Confirmation run of demo (run r1)")
    bare = tomllib.loads(confirmation.confirmation_toml(make_dataset(design, np.arange(9.0)), {"A": 0,
                                                   "B": 0, "C": 0}))  # fmt: skip
    assert set(bare) == {"factors"}


def test_tradeoff_of_conflicting_responses() -> None:
    # Noise-free additive data on L9 (A, B; two empty columns): y1 = 10a + b, y2 = -a + 10b,
    # both smaller-is-better. A: y1 wants level 1, y2 level 3 → conflict, decided by y1 (A
    # carries 100/101 of y1's variation). B: both want level 1. Predictions are exact.
    design = oa("L9", "AB")
    a, b = design.levels["A"].astype(float), design.levels["B"].astype(float)
    ds = make_dataset(design, {"y1": 10 * a + b, "y2": -a + 10 * b})
    result = tradeoff.tradeoff(ds, ["y1", "y2"])
    t = result.table
    assert (t.loc["A", "best y1"], t.loc["A", "best y2"]) == (1, 3)
    assert t["conflict"].tolist() == [True, False]
    assert t["choice"].tolist() == [1, 1]
    assert t["decided by"].tolist() == ["y1", "y2"]
    assert t.loc["A", "% y1"] == pytest.approx(100 * 100 / 101)
    assert result.levels == {"A": 0, "B": 0}
    pred = result.predictions
    assert pred.loc["y1", "own optimum"] == pytest.approx(0.0, abs=1e-10)
    assert pred.loc["y2", "own optimum"] == pytest.approx(-2.0, abs=1e-10)
    assert pred.loc["y2", "compromise"] == pytest.approx(0.0, abs=1e-10)
    assert pred.loc["y1", "units"] == "MPa"


def test_sn_goes_to_measured_varying_responses_of_arrays_or_replicates() -> None:
    design = oa("L9", "ABC", errors=["D"])
    y = np.arange(1.0, 10.0)
    ds = make_dataset(design, {"y": y, "flat": np.full(9, 3.0), "rep": np.c_[y, y + 1]})
    ds["flag"] = ("run", (y > 4).astype(np.int8), {"flag_values": np.array([0, 1])})
    names = ["y", "flat", "rep", "flag"]
    assert taguchi.sn_responses(ds, names) == ["y", "rep"]
    ds.attrs["design"] = "full_factorial"
    assert taguchi.sn_responses(ds, names) == ["rep"]
    assert not taguchi.varies(ds, "flat")
    assert taguchi.varies(ds, "y")


def test_the_tradeoff_gives_each_responses_confirmation_interval_at_the_chosen_levels() -> None:
    # The confirmation study runs the trade-off's chosen levels, and the report told the user
    # to compare its result with intervals given at each response's own optimum (and showed
    # the interval of the mean at the chosen levels). Expected: statsmodels' interval of a new
    # observation (obs_ci) at the chosen levels, least squares on the same terms.
    design = oa("L9", "AB", errors=["C", "D"])
    rng = np.random.default_rng(21)
    a, b = design.levels["A"].astype(float), design.levels["B"].astype(float)
    ys = {"y1": 10 * a + b + rng.normal(0, 0.3, 9), "y2": -a + 10 * b + rng.normal(0, 0.3, 9)}
    ds = make_dataset(design, ys)
    result = tradeoff.tradeoff(ds, ["y1", "y2"])
    for name, y in ys.items():
        ref = statsmodels_prediction(
            make_dataset(design, y), "C(xA) + C(xB)", ["A", "B"], result.levels
        )
        half = (ref["obs_ci_upper"] - ref["obs_ci_lower"]) / 2
        row = result.predictions.loc[name]
        assert row["compromise"] == pytest.approx(ref["mean"], rel=1e-12)
        assert row["confirmation half width"] == pytest.approx(half, rel=1e-10)
