"""RK4 helpers: stability bound, spectral radius, sub-step count, cubic Hermite dense output."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from engine_kernels.valvetrain import rk4


def amplification(z):
    """RK4 stability function R(z) = 1 + z + z^2/2 + z^3/6 + z^4/24 (Hairer & Wanner II)."""
    return np.abs(1 + z + z**2 / 2 + z**3 / 6 + z**4 / 24)


def test_amplification_kernel_matches_closed_form():
    z = np.array([-2.7 + 0.3j, -0.5 + 2.0j, 0.1 - 1.0j, -1.0 + 0.0j])
    got = [rk4.rk4_amplification(c.real, c.imag) for c in z]
    np.testing.assert_allclose(got, amplification(z), rtol=1e-14)


def test_axis_limits_are_on_the_stability_boundary():
    # Closed form: |R(i 2 sqrt 2)| = 1 and R(-2.785293563405282) = 1 (real root of R = 1).
    assert amplification(1j * rk4.RK4_IMAGINARY_AXIS_LIMIT) == pytest.approx(1.0, abs=1e-12)
    assert amplification(-rk4.RK4_REAL_AXIS_LIMIT) == pytest.approx(1.0, abs=1e-12)


def test_stability_bound_holds_in_every_left_half_plane_direction():
    # Brute force over the closed-form stability function: inside |z| <= 2.6 with Re z <= 0
    # RK4 never amplifies; the bound is tight (some direction fails just past 2.62).
    angle = np.radians(np.linspace(90.0, 270.0, 721))
    radius = np.linspace(0.0, rk4.RK4_STABILITY_BOUND, 400)
    z = radius[:, None] * np.exp(1j * angle[None, :])
    assert amplification(z).max() <= 1.0 + 1e-12
    assert amplification(2.63 * np.exp(1j * np.radians(123.0))) > 1.0


@settings(max_examples=60, deadline=None)
@given(
    st.floats(min_value=1e-3, max_value=10.0),
    st.floats(min_value=0.0, max_value=1e5),
    st.floats(min_value=0.0, max_value=1e10),
)
def test_spectral_radius_matches_polynomial_roots(mass, damping, stiffness):
    # Independent: numpy's companion-matrix roots of M l^2 + c l + K.
    expected = np.abs(np.roots([mass, damping, stiffness])).max()
    got = rk4.oscillator_spectral_radius(mass, damping, stiffness)
    assert got == pytest.approx(expected, rel=1e-6)


@settings(max_examples=60, deadline=None)
@given(st.floats(min_value=1e-7, max_value=1e-2), st.floats(min_value=1.0, max_value=1e7))
def test_stable_substeps_is_the_smallest_count_that_keeps_the_bound(step, radius):
    n = rk4.stable_substeps(step, radius, rk4.RK4_STABILITY_BOUND)
    assert n >= 1
    assert step / n * radius <= rk4.RK4_STABILITY_BOUND * (1 + 1e-12)
    if n > 1:
        assert step / (n - 1) * radius > rk4.RK4_STABILITY_BOUND


@settings(max_examples=60, deadline=None)
@given(
    st.lists(st.floats(min_value=-10.0, max_value=10.0), min_size=4, max_size=4),
    st.floats(min_value=0.01, max_value=3.0),
    st.floats(min_value=0.0, max_value=1.0),
)
def test_hermite_reproduces_cubics(coefficients, width, s):
    # A cubic Hermite interpolant is exact for every cubic polynomial (de Boor, ch. IV).
    poly = np.polynomial.Polynomial(coefficients)
    slope = poly.deriv()
    args = (poly(0.0), slope(0.0), poly(width), slope(width), width, s)
    assert rk4.hermite_value(*args) == pytest.approx(poly(s * width), abs=1e-9)
    assert rk4.hermite_slope(*args) == pytest.approx(slope(s * width), abs=1e-8)


def test_rk4_on_the_bound_does_not_grow():
    # y' = lambda y with |h lambda| at the bound, integrated step by step: never grows.
    for angle in np.radians([90.0, 123.0, 150.0, 180.0]):
        z = rk4.RK4_STABILITY_BOUND * complex(math.cos(angle), math.sin(angle))
        y = 1.0 + 0.0j
        for _ in range(200):
            k1 = z * y
            k2 = z * (y + 0.5 * k1)
            k3 = z * (y + 0.5 * k2)
            k4 = z * (y + k3)
            y = y + (k1 + 2 * k2 + 2 * k3 + k4) / 6
        assert abs(y) <= 1.0 + 1e-9
