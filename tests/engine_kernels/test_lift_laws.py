"""Normalised rise laws and the rise-return cam built from them (physics §2)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from numpy.polynomial import Polynomial
from scipy.integrate import quad

from engine_kernels.cam.lift_laws import (
    LAW_CYCLOIDAL,
    LAW_HARMONIC,
    LAW_MODIFIED_SINE,
    LAW_MODIFIED_TRAPEZOID,
    LAW_POLY345,
    LAW_POLY4567,
    LAW_POLYDYNE,
    LAW_SIX_SEGMENT,
    NCOEF,
    rise_law,
    rise_return_cam,
)

STANDARD_LAWS = (
    LAW_CYCLOIDAL,
    LAW_HARMONIC,
    LAW_MODIFIED_SINE,
    LAW_MODIFIED_TRAPEZOID,
    LAW_POLY345,
    LAW_POLY4567,
)
NO_COEFFS = np.zeros(NCOEF)
# Joints of the piecewise laws (Norton, Cam Design and Manufacturing Handbook).
BREAKS = (0.125, 0.375, 0.5, 0.625, 0.875)


def _coeffs(*values):
    out = np.zeros(NCOEF)
    out[: len(values)] = values
    return out


# The 3-4-5 and 4-5-6-7 polynomials in power form (Norton, Cam Design and Manufacturing
# Handbook).
POLY345 = _coeffs(0, 0, 0, 10, -15, 6)
POLY4567 = _coeffs(0, 0, 0, 0, 35, -84, 70, -20)
LAWS_WITH_COEFFS = [(law, NO_COEFFS) for law in STANDARD_LAWS] + [
    (LAW_POLYDYNE, POLY345),
    (LAW_POLYDYNE, POLY4567),
]


def _peak_of_polynomial_acceleration(coeffs):
    """max|f''| on [0, 1] from the roots of f''' (closed form of a polynomial law)."""
    f2 = Polynomial(coeffs).deriv(2)
    roots = f2.deriv().roots()
    candidates = [0.0, 1.0] + [r.real for r in roots if abs(r.imag) < 1e-12 and 0 <= r.real <= 1]
    return max(abs(f2(x)) for x in candidates)


def _max_abs_f2(law, coeffs=NO_COEFFS):
    xs = np.linspace(0.0, 1.0, 100_001)
    return max(abs(rise_law(law, x, coeffs)[2]) for x in xs)


@pytest.mark.parametrize(
    ("law", "expected", "tol"),
    [
        (LAW_CYCLOIDAL, 2.0 * math.pi, 1e-9),  # physics §2: Ca = 2π
        (LAW_HARMONIC, math.pi**2 / 2.0, 1e-9),  # physics §2: Ca = π²/2
        (LAW_POLY345, 10.0 / math.sqrt(3.0), 1e-8),  # physics §2: Ca = 10/√3
        (LAW_MODIFIED_TRAPEZOID, 4.888, 5e-4),  # physics §2, rounded to 3 dp
        (LAW_MODIFIED_SINE, 5.528, 5e-4),  # physics §2, rounded to 3 dp
        # closed form: f''' = 0 at x = (5 - √5)/10 for the 4-5-6-7 polynomial
        (LAW_POLY4567, _peak_of_polynomial_acceleration(POLY4567), 1e-8),
    ],
)
def test_peak_acceleration_factor(law, expected, tol):
    assert _max_abs_f2(law) == pytest.approx(expected, abs=tol)


@pytest.mark.parametrize(("law", "coeffs"), LAWS_WITH_COEFFS)
def test_end_conditions(law, coeffs):
    # Definition of a normalised rise: f(0) = 0, f(1) = 1, at rest at both ends.
    f0, v0, _, _ = rise_law(law, 0.0, coeffs)
    f1, v1, _, _ = rise_law(law, 1.0, coeffs)
    assert f0 == pytest.approx(0.0, abs=1e-15)
    assert f1 == pytest.approx(1.0, abs=1e-14)
    assert v0 == pytest.approx(0.0, abs=1e-14)
    assert v1 == pytest.approx(0.0, abs=1e-13)


@pytest.mark.parametrize(("law", "coeffs"), LAWS_WITH_COEFFS)
@pytest.mark.parametrize("order", [0, 1, 2])
def test_each_derivative_integrates_to_the_previous(law, coeffs, order):
    # Exact integration (adaptive quadrature split at the law's joints): the derivative of
    # order k + 1 must integrate to the increment of order k everywhere, across the joints.
    def g(x):
        return rise_law(law, x, coeffs)[order + 1]

    start = rise_law(law, 0.0, coeffs)[order]
    for x in (0.1, 0.3, 0.45, 0.6, 0.8, 0.95, 1.0):
        inner = [b for b in BREAKS if b < x]
        integral, _ = quad(g, 0.0, x, points=inner or None, epsabs=1e-11, epsrel=1e-11, limit=200)
        value = rise_law(law, x, coeffs)[order]
        assert value - start == pytest.approx(integral, abs=1e-9 * max(1.0, abs(value)))


@settings(max_examples=60, deadline=None)
@given(
    st.sampled_from(STANDARD_LAWS),
    st.floats(0.0, 1.0),
    st.floats(0.0, 1.0),
)
def test_standard_laws_rise_monotonically_within_zero_and_one(law, xa, xb):
    # Up to the roundoff of the power forms (coefficients up to 84: a few 1e-15).
    roundoff = 1e-14
    lo, hi = min(xa, xb), max(xa, xb)
    f_lo = rise_law(law, lo, NO_COEFFS)[0]
    f_hi = rise_law(law, hi, NO_COEFFS)[0]
    assert -roundoff <= f_lo <= f_hi + roundoff
    assert f_hi <= 1.0 + roundoff
    assert rise_law(law, lo, NO_COEFFS)[1] >= -1e-13


@settings(max_examples=40, deadline=None)
@given(st.sampled_from(STANDARD_LAWS), st.floats(0.0, 1.0))
def test_standard_laws_are_point_symmetric(law, x):
    # All six standard laws satisfy f(1 - x) = 1 - f(x) (symmetric double-dwell rises).
    f, f1, f2, f3 = rise_law(law, x, NO_COEFFS)
    g, g1, g2, g3 = rise_law(law, 1.0 - x, NO_COEFFS)
    assert g == pytest.approx(1.0 - f, abs=1e-13)
    assert g1 == pytest.approx(f1, abs=1e-12)
    assert g2 == pytest.approx(-f2, abs=1e-11)
    assert g3 == pytest.approx(f3, abs=1e-9)


@settings(max_examples=40, deadline=None)
@given(
    st.lists(st.floats(-50.0, 50.0), min_size=NCOEF, max_size=NCOEF),
    st.floats(0.0, 1.0),
)
def test_polydyne_matches_numpy_polynomial(values, x):
    # Independent evaluation of f = Σ c_k x^k and its derivatives by numpy.polynomial.
    coeffs = np.array(values)
    p = Polynomial(coeffs)
    got = rise_law(LAW_POLYDYNE, x, coeffs)
    for k in range(4):
        expected = p.deriv(k)(x) if k else p(x)
        scale = np.abs(p.deriv(k).coef).sum() + 1.0
        assert got[k] == pytest.approx(expected, abs=1e-12 * scale)


def test_polydyne_with_345_coefficients_equals_the_345_law():
    for x in np.linspace(0.0, 1.0, 11):
        expected = rise_law(LAW_POLY345, x, NO_COEFFS)
        assert rise_law(LAW_POLYDYNE, x, POLY345) == pytest.approx(expected, abs=1e-12)


def test_unknown_law_is_nan():
    assert all(math.isnan(v) for v in rise_law(LAW_SIX_SEGMENT, 0.5, NO_COEFFS))


def test_rise_return_cam_scales_mirrors_and_dwells():
    lift, beta = 0.01, 1.2
    theta = np.linspace(-2.0, 2.0, 801)
    out = np.empty((4, theta.size))
    rise_return_cam(LAW_CYCLOIDAL, lift, beta, NO_COEFFS, theta, out)
    # Chain rule on h = H f((θ + β)/β) for the rise (physics §2).
    for j in np.flatnonzero((theta >= -beta) & (theta <= 0.0)):
        f, f1, f2, f3 = rise_law(LAW_CYCLOIDAL, (theta[j] + beta) / beta, NO_COEFFS)
        expected = [lift * f, lift * f1 / beta, lift * f2 / beta**2, lift * f3 / beta**3]
        assert out[:, j] == pytest.approx(expected, abs=1e-15)
    # Mirror: h, h'' even; h', h''' odd (the grid is symmetric about the nose).
    np.testing.assert_allclose(out[0], out[0, ::-1], atol=1e-16)
    np.testing.assert_allclose(out[1], -out[1, ::-1], atol=1e-15)
    np.testing.assert_allclose(out[2], out[2, ::-1], atol=1e-15)
    outside = np.abs(theta) > beta
    assert np.all(out[:, outside] == 0.0)
    # Derivatives per rad of cam angle: central differences of the curves themselves.
    step = theta[1] - theta[0]
    inner = slice(2, -2)
    np.testing.assert_allclose(
        np.gradient(out[0], step)[inner], out[1][inner], atol=2e-4 * lift / beta
    )
