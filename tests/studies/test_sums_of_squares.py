"""Sums of squares from level sums (studies.analysis.sums_of_squares) and the ANOVA built on them.

Expected values: statsmodels ``ols`` + ``anova_lm(typ=1)`` (an independent least-squares
ANOVA) on random responses over every catalogue orthogonal array and over full factorials of
2–5 factors, complete and with dropped runs; and exact rational arithmetic (``fractions``) on
the very same doubles for ill-conditioned data (a 10¹² offset).
"""

from __future__ import annotations

import itertools
import json
from fractions import Fraction

import numpy as np
import pandas as pd
import pytest
import xarray as xr
from statsmodels.formula.api import ols
from statsmodels.stats.anova import anova_lm

from studies.analysis import sums_of_squares
from studies.analysis.analyze import anova
from studies.analysis.sums_of_squares import is_balanced, term_sums_of_squares
from studies.common import blocks
from studies.define.designs import list_orthogonal_arrays
from studies.define.designs.orthogonal_arrays import orthogonal_array


def dataset(levels: np.ndarray, y: np.ndarray, factors: int) -> xr.Dataset:
    """Results Dataset: the first ``factors`` columns are factors, the rest error columns."""
    names = [f"f{i}" for i in range(levels.shape[1])]
    coords = {f"{n}_level": ("run", levels[:, i].astype(np.int32)) for i, n in enumerate(names)}
    ds = xr.Dataset({"y": ("run", y, {"units": "MPa"})}, coords=coords)
    ds.attrs = {
        "factors": json.dumps(names[:factors]),
        "error_columns": json.dumps(names[factors:]),
    }
    return ds


def statsmodels_ss(levels: np.ndarray, y: np.ndarray, factors: int) -> pd.DataFrame:
    frame = pd.DataFrame({f"x{i}": levels[:, i] for i in range(factors)})
    frame["y"] = y
    formula = "y ~ " + " + ".join(f"C(x{i})" for i in range(factors))
    return anova_lm(ols(formula, data=frame.dropna()).fit(), typ=1)


def assert_matches(levels: np.ndarray, y: np.ndarray, factors: int) -> None:
    table = anova(dataset(levels, y, factors), "y", pool=[])
    ref = statsmodels_ss(levels, y, factors)
    total = ref["sum_sq"].sum()
    for i in range(factors):
        row = ref.loc[f"C(x{i})"]
        assert table.loc[f"f{i}", "dof"] == row["df"]
        # absolute to the total: a term with (near) zero SS is exact only to round-off
        assert table.loc[f"f{i}", "SS"] == pytest.approx(row["sum_sq"], rel=1e-9, abs=1e-11 * total)
    assert table.loc["error", "dof"] == ref.loc["Residual", "df"]
    assert table.loc["error", "SS"] == pytest.approx(
        ref.loc["Residual", "sum_sq"], rel=1e-9, abs=1e-11 * total
    )
    assert table.loc["total", "SS"] == pytest.approx(total, rel=1e-12)


ARRAYS = [info.name for info in list_orthogonal_arrays()]


@pytest.mark.parametrize("name", ARRAYS)
@pytest.mark.parametrize("dropped", [0, 1])
def test_every_catalogue_array_matches_statsmodels(name: str, dropped: int) -> None:
    rng = np.random.default_rng(abs(hash((name, dropped))) % 2**32)
    levels = orthogonal_array(name)
    factors = max(1, levels.shape[1] - 2)  # two empty columns left for the error
    y = rng.normal(500.0, 30.0, size=levels.shape[0])
    y[rng.choice(y.size, dropped, replace=False)] = np.nan
    assert is_balanced([levels[:, i] for i in range(levels.shape[1])])
    assert_matches(levels, y, factors)


@pytest.mark.parametrize("counts", [(3, 4), (2, 3, 4), (3, 2, 2, 3), (2, 3, 2, 2, 3)])
@pytest.mark.parametrize("dropped", [0, 5])
@pytest.mark.parametrize("block", [None, 7])  # 7: the sums accumulated over blocks of runs
def test_full_factorials_match_statsmodels(
    counts: tuple[int, ...], dropped: int, block: int | None, monkeypatch
) -> None:
    if block:
        monkeypatch.setattr(blocks, "BLOCK", block)
    rng = np.random.default_rng(len(counts) * 10 + dropped)
    levels = np.array(list(itertools.product(*(range(c) for c in counts))))
    # additive effects, an interaction and noise, so no sum of squares is trivially zero
    y = sum(rng.normal(0, 1, c)[levels[:, i]] for i, c in enumerate(counts))
    y = y + 0.3 * levels[:, 0] * levels[:, 1] + rng.normal(0, 0.1, levels.shape[0])
    y[rng.choice(y.size, dropped, replace=False)] = np.nan
    assert_matches(levels, y, len(counts))


@pytest.mark.parametrize("block", [None, 2])
def test_unbalanced_terms_are_detected(block: int | None, monkeypatch) -> None:
    if block:
        monkeypatch.setattr(blocks, "BLOCK", block)
    full = np.array(list(itertools.product(range(3), range(3))))
    assert is_balanced([full[:, 0], full[:, 1]])
    assert not is_balanced([full[1:, 0], full[1:, 1]])


def exact_main_effect(codes: np.ndarray, y: np.ndarray) -> tuple[Fraction, Fraction]:
    """Between-level and total sums of squares in rational arithmetic on the doubles."""
    values = [Fraction(v) for v in y]
    mean = sum(values, Fraction(0)) / len(values)
    total = sum(((v - mean) ** 2 for v in values), Fraction(0))
    between = Fraction(0)
    for level in np.unique(codes):
        group = [values[i] for i in np.flatnonzero(codes == level)]
        k = sum(group, Fraction(0)) / len(group)
        between += len(group) * (k - mean) ** 2
    return between, total


@pytest.mark.parametrize("replicates", [21, 201, 2001])
def test_large_offset_is_exact(replicates: int) -> None:
    # One factor, 9 levels, values 1e12 + {0.2 … 0.6}: an uncentred fit loses ~4 digits here.
    rng = np.random.default_rng(replicates)
    codes = np.repeat(np.arange(9), replicates)
    y = 1e12 + rng.choice(np.linspace(0.2, 0.6, 9), size=codes.size)
    ss, dof, total = term_sums_of_squares(y, [codes])
    between, exact_total = exact_main_effect(codes, y)
    assert dof[0] == 8
    assert ss[0] == pytest.approx(float(between), rel=1e-9)
    assert total == pytest.approx(float(exact_total), rel=1e-9)
    # ...and through the unbalanced path (one run dropped): F against exact arithmetic.
    keep = np.arange(codes.size) != 0
    ss, dof, total = term_sums_of_squares(y[keep], [codes[keep]])
    between, exact_total = exact_main_effect(codes[keep], y[keep])
    exact_f = (between / 8) / ((exact_total - between) / (keep.sum() - 9))
    f = (ss[0] / 8) / ((total - ss[0]) / (keep.sum() - 9))
    assert f == pytest.approx(float(exact_f), rel=1e-9)


def test_normal_equations_in_blocks_equal_the_dense_design_matrix(monkeypatch) -> None:
    # Brute force: the intercept + treatment-dummy matrix X built densely, XᵀX and Xᵀd, against
    # the level-sum accumulation over blocks of 1000 runs (a level absent from the data, and
    # terms whose levels do not start at 0).
    rng = np.random.default_rng(2611)
    n = 5_300
    terms = [rng.integers(0, 5, n), rng.integers(2, 7, n), np.where(rng.random(n) < 0.5, 0, 3)]
    d = rng.normal(size=n)
    d -= d.mean()
    monkeypatch.setattr(blocks, "BLOCK", 1000)
    gram, rhs, owner = sums_of_squares.normal_equations(sums_of_squares.Centred(d), terms)
    columns = [np.ones(n)]
    for t in terms:
        columns += [(t == level).astype(float) for level in np.unique(t)[1:]]
    x = np.stack(columns, axis=1)
    np.testing.assert_array_equal(gram, x.T @ x)  # counts: exact in any order
    np.testing.assert_allclose(rhs, x.T @ d, rtol=1e-12, atol=1e-12 * np.abs(d).sum())
    assert owner.tolist() == [-1, 0, 0, 0, 0, 1, 1, 1, 1, 2]


def test_a_complete_full_factorial_said_balanced_gets_the_counted_answer() -> None:
    # The analysis tells a complete full factorial's ANOVA that it is balanced (it is, by
    # construction) instead of counting every pair of factors per response: same numbers.
    rng = np.random.default_rng(77)
    levels = np.array(list(itertools.product(range(3), range(4), range(2))))
    y = rng.normal(size=levels.shape[0]) + levels[:, 0]
    codes = [levels[:, i] for i in range(3)]
    assert is_balanced(codes)
    counted = term_sums_of_squares(y, codes)
    said = term_sums_of_squares(y, codes, balanced=True)
    for a, b in zip(counted, said, strict=True):
        np.testing.assert_array_equal(a, b)
