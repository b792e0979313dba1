"""Reed valve natural frequencies [B1], [B2], mode shapes and resonance margins (physics §6)."""

from __future__ import annotations

import math

import mpmath
import numpy as np
import pytest

from engine_kernels import reed

RPM = math.pi / 30.0
# physics §6 reference reed and the 1200–9000 rpm four-stroke band.
LENGTH, WIDTH, THICKNESS = 35e-3, 11.5e-3, 0.3e-3
MODULUS, DENSITY = 2.08e11, 7800.0


def params_row(length=LENGTH, n_min=1200.0, n_max=9000.0, openings=0.5):
    return np.array(
        [length, WIDTH, THICKNESS, MODULUS, DENSITY, n_min * RPM, n_max * RPM, openings]
    )


def run(rows, n_modes=6, n_shapes=0, n_points=0):
    params = np.ascontiguousarray(np.atleast_2d(rows))
    n = params.shape[0]
    out = np.empty((n, reed.N_OUT))
    modes = np.empty((n, reed.N_MODE_OUT, n_modes))
    shapes = np.empty((n, n_shapes, n_points))
    reed.reed_batch(params, out, modes, shapes)
    return out, modes, shapes


def mp_root(n):
    """Root of cos X cosh X + 1 = 0 near (n − ½)π with mpmath at 40 digits."""
    with mpmath.workdps(40):
        return mpmath.findroot(lambda x: mpmath.cos(x) * mpmath.cosh(x) + 1, (n - 0.5) * mpmath.pi)


def test_roots_match_high_precision_solution():
    # Expected: mpmath findroot at 40 digits on the original form cos X cosh X = −1.
    roots = np.empty(12)
    reed.cantilever_roots(roots)
    for n in range(1, 13):
        assert roots[n - 1] == pytest.approx(float(mp_root(n)), rel=2e-16)
    # physics §6 / Blevins Table 4.2 values to 6 decimals.
    np.testing.assert_allclose(roots[:4], [1.875104, 4.694091, 7.854757, 10.995541], atol=1e-6)


@pytest.mark.parametrize("n", [3, 4, 5, 6, 7, 8])
def test_roots_follow_the_asymptotic_expansion(n):
    # cos X = −sech X near X = (n − ½)π gives X_n ≈ (n − ½)π + (−1)^(n+1)·2 e^(−(n − ½)π),
    # with a relative error of that correction of order e^(−(n − ½)π).
    base = (n - 0.5) * math.pi
    correction = (-1) ** (n + 1) * 2 * math.exp(-base)
    got = reed.cantilever_root(n) - base
    assert got == pytest.approx(correction, rel=10 * math.exp(-base) + 1e-6)


def test_high_modes_do_not_overflow():
    # For large n, 1/cosh X underflows and X_n = (n − ½)π to machine precision.
    for n in (50, 300, 10_000):
        assert reed.cantilever_root(n) == pytest.approx((n - 0.5) * math.pi, rel=1e-15)


def classic_shape(root, xi):
    """w(ξ) = cosh − cos − σ(sinh − sin), σ = (cos X + cosh X)/(sin X + sinh X), in mpmath."""
    with mpmath.workdps(50):
        x = mpmath.mpf(root)
        sigma = (mpmath.cos(x) + mpmath.cosh(x)) / (mpmath.sin(x) + mpmath.sinh(x))
        z = x * xi
        return float(mpmath.cosh(z) - mpmath.cos(z) - sigma * (mpmath.sinh(z) - mpmath.sin(z)))


def test_mode_shapes_match_the_classic_formula():
    # Expected: the textbook clamped–free shape evaluated in 50-digit arithmetic.
    for n in range(1, 7):
        root = reed.cantilever_root(n)
        for xi in (0.1, 0.37, 0.5, 0.81, 1.0):
            got = reed.cantilever_mode_shape(root, xi, 0)
            assert got == pytest.approx(classic_shape(root, xi), abs=1e-12)
    # Classic normalisation: |w(1)| = 2 (Blevins Table 4.2).
    for n in range(1, 7):
        assert abs(reed.cantilever_mode_shape(reed.cantilever_root(n), 1.0, 0)) == pytest.approx(2)


@pytest.mark.parametrize("n", [1, 2, 3, 5, 8, 20, 60])
def test_mode_shapes_satisfy_clamped_free_boundary_conditions(n):
    # w(0) = w'(0) = 0 (clamped), w''(1) = w'''(1) = 0 (free), relative to the derivative scale
    # X^j; the analytic derivatives are checked against finite differences of the shape.
    root = reed.cantilever_root(n)
    for derivative, xi in ((0, 0.0), (1, 0.0), (2, 1.0), (3, 1.0)):
        value = reed.cantilever_mode_shape(root, xi, derivative)
        assert abs(value) < 1e-12 * root**derivative
    h = 1e-6 / root
    for derivative in range(3):
        for xi in (0.2, 0.55, 0.9):
            fd = (
                reed.cantilever_mode_shape(root, xi + h, derivative)
                - reed.cantilever_mode_shape(root, xi - h, derivative)
            ) / (2 * h)
            exact = reed.cantilever_mode_shape(root, xi, derivative + 1)
            assert exact == pytest.approx(fd, abs=1e-6 * root ** (derivative + 1))


def test_mode_shapes_are_orthogonal():
    # Law: ∫₀¹ w_i w_j dξ = 0 for i ≠ j (self-adjoint clamped–free problem).
    _, _, shapes = run(params_row(), n_shapes=5, n_points=4001)
    xi = np.linspace(0, 1, 4001)
    gram = np.array([[np.trapezoid(a * b, xi) for b in shapes[0]] for a in shapes[0]])
    diagonal = np.sqrt(np.outer(np.diag(gram), np.diag(gram)))
    np.testing.assert_allclose(gram / diagonal, np.eye(5), atol=1e-5)
    np.testing.assert_allclose(shapes[0, :, -1], 1.0)
    np.testing.assert_allclose(shapes[0, :, 0], 0.0, atol=1e-14)


def test_reference_reed_first_frequency_and_resonant_harmonic():
    # Expected: [B2] written out with I = b h³/12, A = b h, X₁ from mpmath.
    x1 = float(mp_root(1))
    inertia, area = WIDTH * THICKNESS**3 / 12, WIDTH * THICKNESS
    f1 = x1**2 / (2 * math.pi * LENGTH**2) * math.sqrt(MODULUS * inertia / (DENSITY * area))
    assert f"{f1:.4g}" == "204.3"
    out, modes, _ = run(params_row())
    row = out[0]
    assert row[reed.OUT_FIRST_FREQUENCY] == pytest.approx(f1, rel=1e-14)
    # Band n/120: 1200–9000 rpm → 10–75 Hz; f1 is above it.
    assert row[reed.OUT_BAND_MIN] == pytest.approx(10.0)
    assert row[reed.OUT_BAND_MAX] == pytest.approx(75.0)
    assert row[reed.OUT_FIRST_MARGIN] == pytest.approx(f1 - 75.0)
    assert row[reed.OUT_FIRST_MARGIN_RATIO] == pytest.approx((f1 - 75.0) / f1)
    # Lowest harmonic reaching f1: k = ⌈f1/75⌉ = 3, engine order k e = 1.5 (e = 1/2), at
    # n = 120 f1/3 rpm (≈ 8172 rpm).
    assert row[reed.OUT_HARMONIC_ORDER] == 1.5
    assert row[reed.OUT_RESONANCE_SPEED] == pytest.approx(120 * f1 / 3 * RPM)
    # Higher modes scale as X_n²; static stiffness 3EI/l³ and mass ρ b h l by definition.
    ratios = modes[0, reed.MODE_FREQUENCY] / f1
    expected = [(float(mp_root(n)) / x1) ** 2 for n in range(1, 7)]
    np.testing.assert_allclose(ratios, expected, rtol=1e-14)
    assert row[reed.OUT_TIP_STIFFNESS] == pytest.approx(3 * MODULUS * inertia / LENGTH**3)
    assert row[reed.OUT_MASS] == pytest.approx(DENSITY * area * LENGTH)


def test_margins_inside_and_below_the_band():
    # Length chosen from [B2] so that f1 = 40 Hz (inside 10–75 Hz) or 5 Hz (below the band).
    x1 = float(mp_root(1))
    stiffness = math.sqrt(MODULUS * THICKNESS**2 / (12 * DENSITY))

    def length_for(f):
        return math.sqrt(x1**2 * stiffness / (2 * math.pi * f))

    out, _, _ = run(np.array([params_row(length_for(40.0)), params_row(length_for(5.0))]))
    inside, below = out
    assert inside[reed.OUT_FIRST_FREQUENCY] == pytest.approx(40.0)
    assert inside[reed.OUT_FIRST_MARGIN] == pytest.approx(-30.0)  # 30 Hz from the 10 Hz edge
    assert inside[reed.OUT_HARMONIC_ORDER] == 0.5  # the event frequency: engine order e = 1/2
    assert inside[reed.OUT_RESONANCE_SPEED] == pytest.approx(120 * 40.0 * RPM)
    assert below[reed.OUT_FIRST_MARGIN] == pytest.approx(5.0)
    assert math.isnan(below[reed.OUT_HARMONIC_ORDER])
    assert math.isnan(below[reed.OUT_RESONANCE_SPEED])


def test_two_stroke_band_is_twice_the_four_stroke_band():
    # One opening per revolution: n/60 Hz.
    out, _, _ = run(np.array([params_row(openings=0.5), params_row(openings=1.0)]))
    np.testing.assert_allclose(out[1, [reed.OUT_BAND_MIN, reed.OUT_BAND_MAX]], [20.0, 150.0])
    np.testing.assert_allclose(out[0, [reed.OUT_BAND_MIN, reed.OUT_BAND_MAX]], [10.0, 75.0])


def test_driver_is_the_same_compiled_and_interpreted():
    rows = np.array([params_row(), params_row(length=20e-3)])
    out, modes, shapes = run(rows, n_modes=4, n_shapes=2, n_points=11)
    out_py, modes_py, shapes_py = np.empty_like(out), np.empty_like(modes), np.empty_like(shapes)
    reed.reed_batch.py_func(rows, out_py, modes_py, shapes_py)
    np.testing.assert_allclose(out_py, out, rtol=1e-14)
    np.testing.assert_allclose(modes_py, modes, rtol=1e-14)
    np.testing.assert_allclose(shapes_py, shapes, rtol=1e-12, atol=1e-15)
