"""Slider-crank kinematics [K1]–[K4], forces [F1]–[F3] and multi-cylinder layouts (physics §5)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from engine_kernels.crank import combustion as cb
from engine_kernels.crank import connecting_rod, piston
from engine_kernels.crank import forces as crank_forces
from engine_kernels.crank import kinematics as crank
from engine_kernels.crank import multicylinder as crank_layout

RPM = math.pi / 30.0
# 12V150 (physics §5): bore 150 mm, rated 2600 rpm, 23 MPa max pressure; stroke 180 mm is the
# physics.md's stated assumption. λ, masses and the cycle settings below are our assumptions.
BORE = 0.150
RADIUS = 0.090
LAMBDA = 0.28
OMEGA = 2600.0 * RPM
PITCH = 0.180  # cylinder pitch a [m] (1.2 × the 150 mm bore; an assumption)
FIRING_ORDER_12V150 = np.array([1, 12, 9, 4, 5, 8, 11, 2, 3, 10, 7, 6])


def params_row(radius=RADIUS, lam=LAMBDA, omega=OMEGA, model=crank.MODEL_EXACT, cylinders=1):
    row = np.zeros(crank.N_PARAMS)
    row[crank.CRANK_RADIUS] = radius
    row[crank.ROD_RATIO] = lam
    row[crank.ANGULAR_SPEED] = omega
    row[crank.BORE] = BORE
    row[crank.RECIPROCATING_MASS] = 3.5
    row[crank.ROTATING_MASS] = 3.0
    row[crank.CRANKCASE_PRESSURE] = 101325.0
    row[crank.KINEMATICS_MODEL] = model
    row[crank.CYLINDERS] = cylinders
    return row


def cycle_12v150(m):
    """Pressure of the assumed 12V150 cycle: ε 14, boost 0.30 MPa, exhaust 0.25 MPa, k 1.35,
    heat release from 15° BTDC over 50°, Wiebe a = 6.908, m = 1, peak pressure 23 MPa."""
    row = np.zeros(cb.N_PARAMS)
    row[cb.BORE] = BORE
    row[cb.CRANK_RADIUS] = RADIUS
    row[cb.ROD_RATIO] = LAMBDA
    row[cb.COMPRESSION_RATIO] = 14.0
    row[cb.INTAKE_PRESSURE] = 0.30e6
    row[cb.EXHAUST_PRESSURE] = 0.25e6
    row[cb.POLYTROPIC_EXPONENT] = 1.35
    row[cb.COMBUSTION_START] = math.radians(-15.0)
    row[cb.COMBUSTION_DURATION] = math.radians(50.0)
    row[cb.WIEBE_EFFICIENCY] = 6.908
    row[cb.WIEBE_FORM] = 1.0
    row[cb.HEAT_INPUT_MODE] = cb.HEAT_MODE_PEAK_PRESSURE
    row[cb.PEAK_PRESSURE_TARGET] = 23.0e6
    out = np.empty((1, cb.N_OUT))
    pressure = np.empty((1, m))
    cb.cycle_pressure_batch(row[None, :], out, pressure)
    return pressure, out[0]


def volume_numpy(alpha, radius=RADIUS, lam=LAMBDA, eps=14.0):
    """Cylinder volume from the textbook form x = r(1 − cos α) + l(1 − √(1 − λ² sin²α))."""
    area = math.pi * BORE**2 / 4.0
    x = radius * (1 - np.cos(alpha)) + radius / lam * (1 - np.sqrt(1 - (lam * np.sin(alpha)) ** 2))
    return area * 2 * radius / (eps - 1) + area * x


def kinematics(rows, m=720, curves=True):
    params = np.ascontiguousarray(np.atleast_2d(rows))
    out = np.empty((params.shape[0], crank.N_KINEMATICS_OUT))
    cur = np.empty((params.shape[0], crank.N_KINEMATICS_CURVES, m if curves else 0))
    crank.crank_kinematics_batch(params, m, out, cur)
    return out, cur


def forces(rows, pressure, curves=True):
    params = np.ascontiguousarray(np.atleast_2d(rows))
    m = pressure.shape[1]
    out = np.empty((params.shape[0], crank_forces.N_FORCE_OUT))
    cur = np.empty((params.shape[0], crank_forces.N_FORCE_CURVES, m if curves else 0))
    crank_forces.crank_forces_batch(params, pressure, out, cur)
    return out, cur


def multicylinder(row, pressure, firing, axis, n_orders=24):
    out = np.empty((1, crank_layout.N_MULTI_OUT))
    harmonics = np.empty((1, n_orders))
    cur = np.empty((1, 1, pressure.shape[1]))
    positions = PITCH * np.arange(firing.size)[None, :]
    crank_layout.crank_multicylinder_batch(
        row[None, :], pressure, firing[None, :], axis[None, :], positions, out, harmonics, cur
    )
    return out[0], harmonics[0], cur[0, 0]


# --- kinematics -----------------------------------------------------------------------------


@settings(max_examples=40, deadline=None)
@given(st.floats(0.0, 2 * math.pi), st.floats(0.05, 0.45))
def test_exact_velocity_and_acceleration_match_finite_differences(alpha, lam):
    # Expected: 4th-order central differences of the exact displacement [K1] (error ~h⁴).
    r, h = 0.05, 1e-3
    x = [piston.piston_displacement_exact(r, lam, alpha + k * h) for k in (-2, -1, 0, 1, 2)]
    dx = (x[0] - 8 * x[1] + 8 * x[3] - x[4]) / (12 * h)
    ddx = (-x[0] + 16 * x[1] - 30 * x[2] + 16 * x[3] - x[4]) / (12 * h * h)
    omega = 300.0
    assert piston.piston_velocity_exact(r, lam, omega, alpha) == pytest.approx(
        omega * dx, abs=1e-9 * r * omega
    )
    assert piston.piston_acceleration_exact(r, lam, omega, alpha) == pytest.approx(
        omega**2 * ddx, abs=1e-6 * r * omega**2
    )


def test_exact_displacement_is_the_textbook_geometry():
    # Expected: x = r(1 − cos α) + l(1 − cos β) with l = r/λ, evaluated directly in numpy.
    alpha = np.linspace(0, 2 * math.pi, 37)
    got = [piston.piston_displacement_exact(0.09, 0.3, a) for a in alpha]
    expected = 0.09 * (1 - np.cos(alpha)) + 0.3 * (1 - np.cos(np.arcsin(0.3 * np.sin(alpha))))
    np.testing.assert_allclose(got, expected, rtol=0, atol=1e-15)


@settings(max_examples=40, deadline=None)
@given(st.floats(0.0, 2 * math.pi), st.floats(0.05, 0.45))
def test_rod_rates_match_finite_differences(alpha, lam):
    # Expected: central differences of β(α) and β̇(α) (constant ω, d/dt = ω d/dα).
    omega, h = 200.0, 1e-4
    db = (connecting_rod.rod_angle(lam, alpha + h) - connecting_rod.rod_angle(lam, alpha - h)) / (
        2 * h
    )
    ddb = (
        connecting_rod.rod_angular_velocity(lam, omega, alpha + h)
        - connecting_rod.rod_angular_velocity(lam, omega, alpha - h)
    ) / (2 * h)
    assert connecting_rod.rod_angular_velocity(lam, omega, alpha) == pytest.approx(
        omega * db, abs=1e-6
    )
    assert connecting_rod.rod_angular_acceleration(lam, omega, alpha) == pytest.approx(
        omega * ddb, abs=1e-6 * omega**2
    )


def test_rod_extremes_match_brute_force_maxima():
    # Expected: maxima over a dense grid of the β, β̇, β̈ formulas written out in numpy.
    alpha = np.linspace(0, 2 * math.pi, 200_001)
    for lam in (0.2, 0.28, 0.4):
        omega = 250.0
        cos_beta = np.sqrt(1 - (lam * np.sin(alpha)) ** 2)
        beta_ddot = -lam * (1 - lam**2) * omega**2 * np.sin(alpha) / cos_beta**3
        assert connecting_rod.rod_angle_max(lam) == pytest.approx(
            np.arcsin(lam * np.sin(alpha)).max()
        )
        assert connecting_rod.rod_angular_velocity_max(lam, omega) == pytest.approx(
            (lam * omega * np.cos(alpha) / cos_beta).max()
        )
        assert connecting_rod.rod_angular_acceleration_max(lam, omega) == pytest.approx(
            np.abs(beta_ddot).max(), rel=1e-9
        )


def test_velocity_maximum_and_acceleration_minimum_against_brute_force():
    # Expected: dense-grid extremes of independent numpy derivatives of x(α) (exact model), and
    # the two-term closed forms: a_min = −rω²(1 − λ) for λ ≤ 1/4, −rω²(λ + 1/(8λ)) above.
    alpha = np.linspace(0, math.pi, 20_001)
    step = alpha[1] - alpha[0]
    for lam in (0.15, 0.25, 0.32, 0.4):
        rows = [params_row(lam=lam), params_row(lam=lam, model=crank.MODEL_TWO_TERM)]
        out, _ = kinematics(np.array(rows), curves=False)
        x = RADIUS * (1 - np.cos(alpha)) + RADIUS / lam * (
            1 - np.sqrt(1 - (lam * np.sin(alpha)) ** 2)
        )
        v = np.gradient(x, step, edge_order=2) * OMEGA
        a = np.gradient(v, step, edge_order=2) * OMEGA
        assert out[0, crank.KIN_MAX_PISTON_VELOCITY] == pytest.approx(v.max(), rel=1e-7)
        assert out[0, crank.KIN_CRANK_ANGLE_MAX_VELOCITY] == pytest.approx(
            alpha[v.argmax()], abs=2 * step
        )
        assert out[0, crank.KIN_MIN_PISTON_ACCELERATION] == pytest.approx(a.min(), rel=1e-6)
        a_min_two_term = -RADIUS * OMEGA**2 * ((1 - lam) if lam <= 0.25 else lam + 1 / (8 * lam))
        assert out[1, crank.KIN_MIN_PISTON_ACCELERATION] == pytest.approx(a_min_two_term)
        # TDC acceleration rω²(1 + λ) is the same in both models.
        np.testing.assert_allclose(
            out[:, crank.KIN_ACCELERATION_TDC], RADIUS * OMEGA**2 * (1 + lam), rtol=1e-14
        )
    # Mean piston speed cm = S n/30 with S = 0.18 m, n = 2600 rpm: 15.6 m/s.
    np.testing.assert_allclose(out[:, crank.KIN_MEAN_PISTON_SPEED], 0.18 * 2600 / 30)


def test_two_term_error_vanishes_with_lambda_cubed():
    # The neglected binomial term is r λ³ sin⁴α/8 (series of l(1 − cos β)), so the absolute
    # errors of x, ẋ, ẍ fall as λ³ at fixed r and as λ² relative to the retained λ term.
    lams = np.geomspace(0.01, 0.2, 7)
    out, _ = kinematics(np.array([params_row(lam=lam) for lam in lams]), m=1440, curves=False)
    for column in (
        crank.KIN_APPROX_ERROR_DISPLACEMENT,
        crank.KIN_APPROX_ERROR_VELOCITY,
        crank.KIN_APPROX_ERROR_ACCELERATION,
    ):
        error = out[:, column]
        assert np.all(np.diff(error) > 0)
        slope = np.polyfit(np.log(lams), np.log(error), 1)[0]
        assert slope == pytest.approx(3.0, abs=0.05)
        relative_slope = np.polyfit(np.log(lams), np.log(error / lams), 1)[0]
        assert relative_slope == pytest.approx(2.0, abs=0.05)
    # Leading term of the displacement error: max r λ³ sin⁴α/8 = r λ³/8 (at α = 90°).
    leading = RADIUS * lams**3 / 8
    np.testing.assert_allclose(out[:, crank.KIN_APPROX_ERROR_DISPLACEMENT] / leading, 1, atol=0.03)


def test_kinematic_curves_follow_the_chosen_model():
    # Expected: the two-term formulas [K2]–[K4] written out in numpy on the cycle grid.
    m = 720
    alpha = crank.CYCLE_ANGLE * np.arange(m) / m
    _, cur = kinematics(params_row(model=crank.MODEL_TWO_TERM), m=m)
    r, lam, w = RADIUS, LAMBDA, OMEGA
    np.testing.assert_allclose(
        cur[0, crank.KC_DISPLACEMENT],
        r * ((1 - np.cos(alpha)) + lam / 4 * (1 - np.cos(2 * alpha))),
        atol=1e-15,
    )
    np.testing.assert_allclose(
        cur[0, crank.KC_VELOCITY], r * w * (np.sin(alpha) + lam / 2 * np.sin(2 * alpha)), atol=1e-11
    )
    np.testing.assert_allclose(
        cur[0, crank.KC_ACCELERATION],
        r * w**2 * (np.cos(alpha) + lam * np.cos(2 * alpha)),
        atol=1e-8,
    )


# --- forces ---------------------------------------------------------------------------------


@settings(max_examples=60, deadline=None)
@given(st.floats(0.0, 4 * math.pi), st.floats(0.05, 0.45), st.floats(-1e5, 1e5))
def test_power_balance_torque_times_speed_equals_force_times_velocity(alpha, lam, force):
    # Law: T·r·ω = P·ẋ (virtual work of the frictionless slider-crank).
    r, omega = 0.07, 300.0
    beta = connecting_rod.rod_angle(lam, alpha)
    power_crank = crank_forces.tangential_force(force, alpha, beta) * r * omega
    power_piston = force * piston.piston_velocity_exact(r, lam, omega, alpha)
    assert power_crank == pytest.approx(power_piston, abs=1e-9 * abs(force) * r * omega + 1e-12)


def test_force_components_are_consistent_and_balance_power():
    # Laws: S² = P² + N² and S² = T² + Z² (components of the rod force); M ω = P ẋ per point.
    m = 1440
    pressure, _ = cycle_12v150(m)
    out, cur = forces(params_row(), pressure)
    _, kin = kinematics(params_row(), m=m)
    p, s = cur[0, crank_forces.FC_PISTON_FORCE], cur[0, crank_forces.FC_ROD_FORCE]
    scale = np.abs(s).max()
    np.testing.assert_allclose(
        s**2, p**2 + cur[0, crank_forces.FC_SIDE_FORCE] ** 2, atol=1e-9 * scale**2
    )
    np.testing.assert_allclose(
        s**2,
        cur[0, crank_forces.FC_TANGENTIAL_FORCE] ** 2 + cur[0, crank_forces.FC_RADIAL_FORCE] ** 2,
        atol=1e-9 * scale**2,
    )
    np.testing.assert_allclose(
        cur[0, crank_forces.FC_TORQUE] * OMEGA,
        p * kin[0, crank.KC_VELOCITY],
        atol=1e-9 * scale * RADIUS * OMEGA,
    )
    # Gas force [F1] from its definition, at the grid peak of the pressure curve.
    expected_peak = math.pi * BORE**2 / 4 * (pressure.max() - 101325.0)
    assert out[0, crank_forces.FORCE_MAX_GAS_FORCE] == pytest.approx(expected_peak, rel=1e-14)
    assert out[0, crank_forces.FORCE_MAX_TORQUE] == pytest.approx(
        cur[0, crank_forces.FC_TORQUE].max()
    )
    assert out[0, crank_forces.FORCE_MAX_SIDE_FORCE] == pytest.approx(
        np.abs(cur[0, crank_forces.FC_SIDE_FORCE]).max()
    )
    # [F2], [F3] amplitudes: mj r ω², λ mj r ω², mr r ω².
    first = 3.5 * RADIUS * OMEGA**2
    assert out[0, crank_forces.FORCE_FIRST_ORDER_AMPLITUDE] == pytest.approx(first)
    assert out[0, crank_forces.FORCE_SECOND_ORDER_AMPLITUDE] == pytest.approx(LAMBDA * first)
    assert out[0, crank_forces.FORCE_ROTATING_INERTIA] == pytest.approx(3.0 * RADIUS * OMEGA**2)


def test_two_term_inertia_force_is_first_plus_second_order():
    # [F2]: Pj = −mj r ω² (cos α + λ cos 2α); with p = p0 only inertia acts.
    m = 360
    alpha = crank.CYCLE_ANGLE * np.arange(m) / m
    pressure = np.full((1, m), 101325.0)
    _, cur = forces(params_row(model=crank.MODEL_TWO_TERM), pressure)
    expected = -3.5 * RADIUS * OMEGA**2 * (np.cos(alpha) + LAMBDA * np.cos(2 * alpha))
    np.testing.assert_allclose(cur[0, crank_forces.FC_INERTIA_FORCE], expected, atol=1e-9)
    split = [
        crank_forces.reciprocating_inertia_first_order(3.5, RADIUS, OMEGA, a)
        + crank_forces.reciprocating_inertia_second_order(3.5, RADIUS, LAMBDA, OMEGA, a)
        for a in alpha
    ]
    np.testing.assert_allclose(split, expected, atol=1e-9)
    np.testing.assert_allclose(cur[0, crank_forces.FC_GAS_FORCE], 0.0)


def test_force_driver_is_the_same_compiled_and_interpreted():
    # The prange driver run as plain Python (same kernels) must give the same rows.
    m = 96
    rng = np.random.default_rng(1)
    rows = np.array([params_row(lam=lam) for lam in (0.2, 0.25, 0.3)])
    rows[1, crank.KINEMATICS_MODEL] = crank.MODEL_TWO_TERM
    pressure = rng.uniform(1e5, 5e6, size=(3, m))
    out_jit, cur_jit = forces(rows, pressure)
    out_py = np.empty_like(out_jit)
    cur_py = np.empty_like(cur_jit)
    crank_forces.crank_forces_batch.py_func(rows, pressure, out_py, cur_py)
    np.testing.assert_allclose(out_jit, out_py, rtol=1e-13)
    np.testing.assert_allclose(cur_jit, cur_py, rtol=1e-12, atol=1e-9)


# --- multi-cylinder -------------------------------------------------------------------------


def firing_and_axes(order, bank_angle=None, even=False):
    order = np.asarray(order, dtype=np.int64)
    firing = np.empty(order.size)
    axis = np.zeros(order.size)
    if bank_angle is None or even:
        crank_layout.even_firing_angles(order, firing)
    else:
        crank_layout.v_crank_firing_angles(order, bank_angle, firing)
    if bank_angle is not None:
        crank_layout.v_axis_angles(order, bank_angle, axis)
    return firing, axis


def test_12v150_firing_intervals_follow_the_crank_geometry():
    # A 6-throw V12 with shared crankpins fires at alternating γ and 120° − γ (physics §5: even
    # only at 60°). Expected intervals: 90°/30° at a 90° bank; 60° at a 60° bank.
    order = FIRING_ORDER_12V150
    firing, axis = firing_and_axes(order, math.radians(90.0))
    intervals = np.degrees(np.diff(np.append(firing[order - 1], 4 * math.pi)))
    np.testing.assert_allclose(intervals, [90, 30] * 6, atol=1e-12)
    np.testing.assert_allclose(np.degrees(axis[order - 1]), [-45, 45] * 6)
    firing60, _ = firing_and_axes(order, math.radians(60.0))
    even, _ = firing_and_axes(order, math.radians(60.0), even=True)
    np.testing.assert_allclose(firing60, even, atol=1e-12)


@pytest.mark.parametrize("bank_deg", [90.0, 60.0])
def test_12v150_mean_torque_equals_cycle_work(bank_deg):
    # Energy check: mean torque = z ∮p dV/(4π) (four-stroke); the inertia torque averages out.
    # Expected ∮p dV from the test's own volume formula, trapezoid round the closed p–V loop.
    m = 2880
    pressure, cycle = cycle_12v150(m)
    alpha = crank.CYCLE_ANGLE * np.arange(m + 1) / m
    p_loop = np.append(pressure[0], pressure[0, 0])
    work = np.trapezoid(p_loop, volume_numpy(alpha))
    firing, axis = firing_and_axes(FIRING_ORDER_12V150, math.radians(bank_deg))
    out, harmonics, total = multicylinder(params_row(cylinders=12), pressure, firing, axis)
    expected = 12 * work / (4 * math.pi)
    assert out[crank_layout.MULTI_MEAN_TORQUE] == pytest.approx(expected, rel=2e-5)
    assert cycle[cb.OUT_CYCLE_WORK] == pytest.approx(work, rel=2e-5)
    assert out[crank_layout.MULTI_MEAN_POWER] == pytest.approx(expected * OMEGA, rel=2e-5)
    assert out[crank_layout.MULTI_TORQUE_PEAK_TO_PEAK] == pytest.approx(np.ptp(total))
    # Harmonic orders against numpy's FFT of the summed torque (harmonic q = order q/2).
    spectrum = 2 * np.abs(np.fft.rfft(total)) / m
    np.testing.assert_allclose(harmonics, spectrum[1:25], rtol=1e-9, atol=1e-9 * expected)
    if bank_deg == 60.0:
        # Even firing every 60° repeats the torque 12 times per cycle: only orders 6, 12 remain.
        keep = np.zeros(24, dtype=bool)
        keep[[11, 23]] = True
        assert np.all(harmonics[~keep] < 1e-9 * expected)
        assert np.all(harmonics[keep] > 1e-3 * expected)
    # Both layouts are two inline-six banks: no free first- or second-order force.
    assert out[crank_layout.MULTI_FREE_FIRST_ORDER_FORCE] < 1e-9 * 3.5 * RADIUS * OMEGA**2
    assert out[crank_layout.MULTI_FREE_SECOND_ORDER_FORCE] < 1e-9 * 3.5 * RADIUS * OMEGA**2


def test_free_forces_of_classic_layouts():
    # Closed forms with F = mj r ω²: inline-6 → 0, 0; inline-4 → 0, 4λF;
    # 90° V-twin on one crankpin → rotating first order of constant magnitude F and a
    # second order √2 λF (e.g. Taylor, The Internal-Combustion Engine in Theory and Practice,
    # vol. 2, ch. 8).
    f = 3.5 * RADIUS * OMEGA**2
    cases = [
        ([1, 5, 3, 6, 2, 4], None, 0.0, 0.0),
        ([1, 3, 4, 2], None, 0.0, 4 * LAMBDA * f),
        ([1, 2], math.radians(90.0), f, math.sqrt(2) * LAMBDA * f),
    ]
    for order, bank, first, second in cases:
        firing, axis = firing_and_axes(order, bank)
        z = len(order)
        got1 = crank_layout.free_reciprocating_force(3.5, RADIUS, LAMBDA, OMEGA, firing, axis, z, 1)
        got2 = crank_layout.free_reciprocating_force(3.5, RADIUS, LAMBDA, OMEGA, firing, axis, z, 2)
        assert got1 == pytest.approx(first, abs=1e-9 * f)
        assert got2 == pytest.approx(second, abs=1e-9 * f)


def test_free_moments_of_classic_inline_layouts():
    # Closed forms with F = mj r ω² and cylinder pitch a, moments about the middle of the
    # crankshaft: inline-3 (120° throws) → √3·aF and √3·aλF; inline-4 (flat crank) and
    # inline-6 → 0, 0 (mirror-symmetric crankshafts); inline-5 (72° throws, 1-2-4-5-3) →
    # 0.449·aF and 4.98·aλF (Taylor, The Internal-Combustion Engine in Theory and Practice,
    # vol. 2, ch. 8, table of couples, quoted to 3 digits).
    f = 3.5 * RADIUS * OMEGA**2
    cases = [
        ([1, 3, 2], math.sqrt(3), math.sqrt(3), 1e-9),
        ([1, 3, 4, 2], 0.0, 0.0, 1e-9),
        ([1, 5, 3, 6, 2, 4], 0.0, 0.0, 1e-9),
        ([1, 2, 4, 5, 3], 0.449, 4.98, 5e-3),
    ]
    for order, first, second, rel in cases:
        firing, axis = firing_and_axes(order)
        z = len(order)
        positions = PITCH * np.arange(z)
        moments = [
            crank_layout.free_reciprocating_moment(
                3.5, RADIUS, LAMBDA, OMEGA, firing, axis, positions, z, k
            )
            for k in (1, 2)
        ]
        assert moments[0] == pytest.approx(first * PITCH * f, rel=rel, abs=1e-9 * PITCH * f)
        assert moments[1] == pytest.approx(
            second * PITCH * LAMBDA * f, rel=rel, abs=1e-9 * PITCH * f
        )


@settings(max_examples=30, deadline=None)
@given(
    st.lists(st.floats(0.0, 4 * math.pi), min_size=2, max_size=8),
    st.floats(0.0, math.pi),
    st.integers(1, 2),
)
def test_free_moment_is_the_brute_force_maximum(firing, bank, order):
    # Expected: sum the moments of the cylinders' forces about the middle of the shaft at
    # every angle of a dense grid and take the largest magnitude.
    z = len(firing)
    firing = np.array(firing)
    axis = bank * (np.arange(z) % 2 - 0.5)
    positions = PITCH * np.arange(z) + 0.01 * np.arange(z) ** 2
    arms = positions - positions.mean()
    alpha = np.linspace(0, 2 * math.pi, 20_001)[:, None]
    scale = 3.5 * RADIUS * OMEGA**2 * LAMBDA ** (order - 1)
    force = -scale * np.cos(order * (alpha - firing))
    # moment of force F e (e in the x-y plane) at axial position w: w ẑ × F e = w F (−e_y, e_x)
    mx = (-arms * force * np.cos(axis)).sum(axis=1)
    my = (arms * force * np.sin(axis)).sum(axis=1)
    brute = np.hypot(mx, my).max()
    got = crank_layout.free_reciprocating_moment(
        3.5, RADIUS, LAMBDA, OMEGA, firing, axis, positions, z, order
    )
    assert got == pytest.approx(brute, rel=1e-6, abs=1e-9 * scale * PITCH)


@settings(max_examples=30, deadline=None)
@given(st.lists(st.floats(-10.0, 10.0), min_size=4, max_size=4))
def test_free_force_amplitude_is_the_brute_force_maximum(vectors):
    # Expected: max over a dense t grid of |A cos t + B sin t|.
    ax, ay, bx, by = vectors
    t = np.linspace(0, 2 * math.pi, 20_001)
    brute = np.hypot(ax * np.cos(t) + bx * np.sin(t), ay * np.cos(t) + by * np.sin(t)).max()
    got = crank_layout.free_force_amplitude(ax, ay, bx, by)
    assert got == pytest.approx(brute, rel=1e-6, abs=1e-9)


def test_multicylinder_shift_matches_direct_sum_of_shifted_cylinders():
    # Expected: torque of cylinder c evaluated directly at its own crank angle α − φ_c (firing
    # angles on the grid, so no interpolation error), summed in numpy.
    m = 720
    pressure, _ = cycle_12v150(m)
    firing, axis = firing_and_axes([1, 3, 4, 2])
    row = params_row(cylinders=4)
    _, cur = forces(row, pressure)
    single = cur[0, crank_forces.FC_TORQUE]
    shifts = np.rint(firing / (crank.CYCLE_ANGLE / m)).astype(int)
    expected = sum(np.roll(single, s) for s in shifts)
    _, _, total = multicylinder(row, pressure, firing, axis)
    np.testing.assert_allclose(total, expected, rtol=1e-12, atol=1e-9)


def test_kinematics_and_layout_drivers_are_the_same_compiled_and_interpreted():
    rows = np.array([params_row(lam=0.25, cylinders=4), params_row(lam=0.3, cylinders=4)])
    rows[1, crank.KINEMATICS_MODEL] = crank.MODEL_TWO_TERM
    out, cur = kinematics(rows, m=72)
    out_py, cur_py = np.empty_like(out), np.empty_like(cur)
    crank.crank_kinematics_batch.py_func(rows, 72, out_py, cur_py)
    np.testing.assert_allclose(out_py, out, rtol=1e-13)
    np.testing.assert_allclose(cur_py, cur, rtol=1e-12, atol=1e-9)
    pressure = np.random.default_rng(2).uniform(1e5, 5e6, size=(2, 72))
    firing, axis = firing_and_axes([1, 3, 4, 2])
    args = (rows, pressure, firing[None, :], axis[None, :], PITCH * np.arange(4.0)[None, :])
    results = []
    for driver in (
        crank_layout.crank_multicylinder_batch,
        crank_layout.crank_multicylinder_batch.py_func,
    ):
        multi_out = np.empty((2, crank_layout.N_MULTI_OUT))
        harmonics = np.empty((2, 8))
        curve = np.empty((2, 1, 0))
        driver(*args, multi_out, harmonics, curve)
        results.append((multi_out, harmonics))
    np.testing.assert_allclose(results[1][0], results[0][0], rtol=1e-12, atol=1e-9)
    np.testing.assert_allclose(results[1][1], results[0][1], rtol=1e-12, atol=1e-9)
