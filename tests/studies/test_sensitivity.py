"""Variance decomposition and Sobol indices of a full factorial (studies.analysis.sensitivity).

Expected values: an independent projection on the grid (explicit functional-ANOVA effects by
broadcasting, whose residual must carry exactly the higher-order remainder); the Ishigami
function's closed-form indices (Ishigami & Homma 1990; Sobol' & Levitan 1999), which the grid
estimates converge to at the midpoint rule's second order; and a Saltelli/Jansen Monte-Carlo
estimate on the continuous inputs within four standard errors.
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from studies.analysis import sensitivity
from studies.analysis.sensitivity import decompose, squares
from studies.common import blocks
from studies.common.blocks import BLOCK

A, B = 7.0, 0.1  # Ishigami constants
VARIANCE = A**2 / 8 + B * np.pi**4 / 5 + B**2 * np.pi**8 / 18 + 0.5
V1 = 0.5 * (1 + B * np.pi**4 / 5) ** 2
VT3 = 8 * B**2 * np.pi**8 / 225
FIRST = np.array([V1, A**2 / 8, 0.0]) / VARIANCE
TOTAL = np.array([V1 + VT3, A**2 / 8, VT3]) / VARIANCE


def ishigami(x1: np.ndarray, x2: np.ndarray, x3: np.ndarray) -> np.ndarray:
    return np.sin(x1) + A * np.sin(x2) ** 2 + B * x3**4 * np.sin(x1)


def ishigami_grid(n: int) -> np.ndarray:
    """The Ishigami function on n midpoints per axis of [-π, π]³ (a uniform full factorial)."""
    x = -np.pi + (np.arange(n) + 0.5) * 2 * np.pi / n
    return ishigami(*np.meshgrid(x, x, x, indexing="ij"))


def test_main_pair_and_remainder_add_up_to_the_total() -> None:
    rng = np.random.default_rng(3)
    shape = (3, 4, 2, 5)
    y = 100.0 + rng.normal(size=shape) + np.add.outer(np.arange(3), np.arange(4))[..., None, None]
    dec = decompose(y, ("a", "b", "c", "d"))
    # Independent projection: effects by broadcasting over the full grid.
    grand = y.mean()
    axes = range(y.ndim)
    main = [y.mean(axis=tuple(k for k in axes if k != a), keepdims=True) - grand for a in axes]
    fitted = grand + sum(main)
    for (a, b), ss in zip(itertools.combinations(axes, 2), dec.pair, strict=True):
        cell = y.mean(axis=tuple(k for k in axes if k not in (a, b)), keepdims=True)
        effect = cell - main[a] - main[b] - grand
        assert ss == pytest.approx(float(np.sum(np.broadcast_to(effect, y.shape) ** 2)), rel=1e-9)
        fitted = fitted + effect
    for a, ss in enumerate(dec.main):
        assert ss == pytest.approx(float(np.sum(np.broadcast_to(main[a], y.shape) ** 2)), rel=1e-9)
    residual = float(np.sum((y - fitted) ** 2))
    assert dec.remainder == pytest.approx(residual, rel=1e-9)
    parts = dec.main.sum() + dec.pair.sum() + dec.remainder
    assert parts == pytest.approx(dec.total, rel=1e-12)
    assert dec.total == pytest.approx(float(np.sum((y - grand) ** 2)), rel=1e-12)


def test_ishigami_indices_converge_to_the_closed_forms_at_second_order() -> None:
    estimates = {n: decompose(ishigami_grid(n), ("x1", "x2", "x3")) for n in (32, 64)}
    for name, exact in (("first_order", FIRST), ("total_effect", TOTAL)):
        coarse, fine = getattr(estimates[32], name), getattr(estimates[64], name)
        error = np.abs(fine - exact)
        # Richardson: for a second-order rule the error of the fine grid is ~|fine - coarse|/3.
        assert (error <= 1.5 * np.abs(fine - coarse) / 3 + 1e-12).all()
        moving = np.abs(coarse - exact) > 1e-9  # S3 = 0 holds exactly on any symmetric grid
        ratio = np.abs(coarse - exact)[moving] / error[moving]
        assert ((ratio > 3.5) & (ratio < 4.5)).all()
        assert error.max() < 1e-3


def test_ishigami_grid_agrees_with_a_saltelli_monte_carlo_estimate() -> None:
    rng = np.random.default_rng(11)
    n = 200_000
    a = rng.uniform(-np.pi, np.pi, (n, 3))
    b = rng.uniform(-np.pi, np.pi, (n, 3))
    fa, fb = ishigami(*a.T), ishigami(*b.T)
    variance = np.var(np.concatenate([fa, fb]))
    grid = decompose(ishigami_grid(64), ("x1", "x2", "x3"))
    discretisation = 1e-3  # the grid's error against the closed forms (test above)
    for i in range(3):
        ab = a.copy()
        ab[:, i] = b[:, i]
        fab = ishigami(*ab.T)
        first_terms = fb * (fab - fa) / variance  # Saltelli et al. 2010, eq. (b)
        total_terms = 0.5 * (fa - fab) ** 2 / variance  # Jansen 1999
        for terms, estimate in (
            (first_terms, grid.first_order[i]),
            (total_terms, grid.total_effect[i]),
        ):
            error = terms.std(ddof=1) / np.sqrt(n)
            assert abs(terms.mean() - estimate) <= 4 * error + discretisation


def test_sums_of_squares_by_slabs_equal_the_whole_array_sums() -> None:
    # Reference: the sums over the whole array (what squares() does below BLOCK values);
    # above it, slabs are summed separately: equal to the last bits (1e-12 relative).
    d = np.random.default_rng(7).normal(3.0, 2.0, (70, 60, 300))
    assert d.size > BLOCK
    assert squares(d) == pytest.approx(float(np.sum(d * d)), rel=1e-12)
    for axis in range(d.ndim):
        whole = float(np.sum((d - d.mean(axis=axis, keepdims=True)) ** 2))
        assert squares(d, axis) == pytest.approx(whole, rel=1e-12)
    small = d[:5, :5, :5]
    assert squares(small, 1) == float(np.sum((small - small.mean(axis=1, keepdims=True)) ** 2))


@pytest.mark.parametrize("shape", [(7, 5, 6, 4), (3, 40), (9, 2, 3)])
def test_the_decomposition_over_slabs_is_the_whole_grid_one(
    shape: tuple[int, ...], monkeypatch
) -> None:
    # Reference: the decomposition of the whole centred grid (below BLOCK values). With BLOCK
    # lowered the grid is centred and summed a slab of a few rows at a time, the mean along
    # the first axis kept for a second pass: every field equal within 1e-12 of the total. A
    # large offset (1e6 + effects of order 1) checks that the slabs are centred.
    rng = np.random.default_rng(sum(shape))
    axes = np.meshgrid(*(np.linspace(-1, 1, n) for n in shape), indexing="ij")
    grid = 1e6 + sum(np.sin(3 * x) for x in axes) + axes[0] * axes[-1] + rng.normal(0, 0.1, shape)
    factors = tuple(f"f{i}" for i in range(len(shape)))
    whole = decompose(grid, factors)
    monkeypatch.setattr(sensitivity, "BLOCK", 20)
    monkeypatch.setattr(blocks, "BLOCK", 20)
    slabs = decompose(grid, factors)
    scale = whole.total
    assert slabs.total == pytest.approx(whole.total, rel=1e-12)
    for field, atol in (("main", scale), ("pair", scale), ("first_order", 1), ("total_effect", 1)):
        np.testing.assert_allclose(
            getattr(slabs, field), getattr(whole, field), rtol=1e-12, atol=1e-12 * atol
        )
    assert slabs.remainder == pytest.approx(whole.remainder, abs=1e-12 * scale)
