"""Single-zone polytropic cycle with Wiebe heat release (physics §5, cylinder pressure)."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st
from scipy.integrate import solve_ivp

from engine_kernels.crank import combustion as cb

BORE, RADIUS, LAMBDA, EPS, K = 0.150, 0.090, 0.28, 14.0, 1.35
P_A, P_EX = 0.30e6, 0.25e6
AREA = math.pi * BORE**2 / 4
V_D = 2 * RADIUS * AREA


def params_row(heat=12_000.0, start_deg=-15.0, duration_deg=50.0, form=1.0):
    row = np.zeros(cb.N_PARAMS)
    row[cb.BORE] = BORE
    row[cb.CRANK_RADIUS] = RADIUS
    row[cb.ROD_RATIO] = LAMBDA
    row[cb.COMPRESSION_RATIO] = EPS
    row[cb.INTAKE_PRESSURE] = P_A
    row[cb.EXHAUST_PRESSURE] = P_EX
    row[cb.POLYTROPIC_EXPONENT] = K
    row[cb.COMBUSTION_START] = math.radians(start_deg)
    row[cb.COMBUSTION_DURATION] = math.radians(duration_deg)
    row[cb.WIEBE_EFFICIENCY] = 6.908
    row[cb.WIEBE_FORM] = form
    row[cb.HEAT_INPUT_MODE] = cb.HEAT_MODE_ENERGY
    row[cb.HEAT_RELEASED] = heat
    row[cb.PEAK_PRESSURE_TARGET] = 23.0e6
    return row


def run(rows, m=1440):
    params = np.ascontiguousarray(np.atleast_2d(rows))
    out = np.empty((params.shape[0], cb.N_OUT))
    pressure = np.empty((params.shape[0], m))
    cb.cycle_pressure_batch(params, out, pressure)
    return out, pressure


def grid(m):
    return 4 * math.pi * np.arange(m) / m


def volume(alpha):
    """V(α) and dV/dα from x = r(1 − cos α) + l(1 − cos β), written out independently."""
    s = np.sin(alpha)
    cos_beta = np.sqrt(1 - (LAMBDA * s) ** 2)
    x = RADIUS * (1 - np.cos(alpha)) + RADIUS / LAMBDA * (1 - cos_beta)
    dx = RADIUS * (s + LAMBDA * s * np.cos(alpha) / cos_beta)
    return V_D / (EPS - 1) + AREA * x, AREA * dx


def test_motoring_cycle_is_polytropic():
    # No heat: p V^k = p_a V_bdc^k on the closed part, p_tdc = p_a ε^k, and the only work is
    # the gas exchange (p_a − p_ex) V_d.
    m = 1440
    out, pressure = run(params_row(heat=0.0), m)
    alpha = grid(m)
    closed = (alpha >= math.pi) & (alpha <= 3 * math.pi)
    v, _ = volume(alpha)
    v_bdc = V_D * EPS / (EPS - 1)
    np.testing.assert_allclose(pressure[0, closed] * v[closed] ** K, P_A * v_bdc**K, rtol=1e-12)
    np.testing.assert_allclose(pressure[0, alpha < math.pi], P_A)
    np.testing.assert_allclose(pressure[0, alpha > 3 * math.pi], P_EX)
    assert pressure[0, m // 2] == pytest.approx(P_A * EPS**K, rel=1e-12)
    assert out[0, cb.OUT_COMPRESSION_PRESSURE] == pytest.approx(P_A * EPS**K, rel=1e-14)
    assert out[0, cb.OUT_CYCLE_WORK] == pytest.approx((P_A - P_EX) * V_D, rel=1e-10)


@pytest.mark.parametrize(("start_deg", "duration_deg", "form"), [(-15, 50, 1.0), (-5, 70, 2.0)])
def test_pressure_matches_an_independent_ode_solution(start_deg, duration_deg, form):
    # Expected: scipy solve_ivp (DOP853, rtol 1e-12) of dp/dα = (−k p V' + (k − 1) Q x_b')/V with
    # the Wiebe rate written out here.
    heat, a = 12_000.0, 6.908
    start = 2 * math.pi + math.radians(start_deg)
    duration = math.radians(duration_deg)

    def rate(alpha):
        tau = (alpha - start) / duration
        if tau <= 0 or tau >= 1:
            return 0.0
        return (
            a
            * (form + 1)
            / duration
            * tau**form
            * math.exp(-a * tau ** (form + 1))
            / (1 - math.exp(-a))
        )

    def rhs(alpha, p):
        v, dv = volume(np.array(alpha))
        return (-K * p * dv + (K - 1) * heat * rate(alpha)) / v

    # Integrate piecewise between the kinks of the heat release (start and end of combustion).
    m = 720
    alpha = grid(m)
    mask = (alpha >= math.pi) & (alpha <= 3 * math.pi)
    closed = alpha[mask]
    breaks = [math.pi, start, start + duration, 3 * math.pi]
    expected = np.empty(closed.size)
    p0 = P_A
    for lo, hi in itertools.pairwise(breaks):
        inside = (closed >= lo) & (closed <= hi)
        piece = solve_ivp(
            rhs,
            (lo, hi),
            [p0],
            method="DOP853",
            t_eval=closed[inside],
            dense_output=True,
            rtol=1e-12,
            atol=1e-3,
        )
        expected[inside] = piece.y[0]
        p0 = piece.sol(hi)[0]
    out, pressure = run(params_row(heat, start_deg, duration_deg, form), m)
    np.testing.assert_allclose(pressure[0, mask], expected, rtol=1e-8)
    assert out[0, cb.OUT_EXPANSION_END_PRESSURE] == pytest.approx(p0, rel=1e-8)
    assert out[0, cb.OUT_HEAT_RELEASED] == pytest.approx(heat, rel=1e-12)


def test_cycle_work_matches_loop_integral():
    # Expected: ∮p dV by the trapezoid rule round the closed p–V loop on a fine grid.
    m = 5760
    out, pressure = run(params_row(), m)
    alpha = 4 * math.pi * np.arange(m + 1) / m
    v, _ = volume(alpha)
    work = np.trapezoid(np.append(pressure[0], pressure[0, 0]), v)
    assert out[0, cb.OUT_CYCLE_WORK] == pytest.approx(work, rel=1e-5)
    assert out[0, cb.OUT_IMEP] == pytest.approx(work / V_D, rel=1e-5)


@pytest.mark.parametrize(
    ("duration_deg", "efficiency", "form"), [(50.0, 6.908, 1.0), (0.893, 65.985, 8.8516)]
)
def test_peak_pressure_mode_hits_the_target_between_the_grid_points(
    duration_deg: float, efficiency: float, form: float
) -> None:
    # The heat the target allows is found on a 2° grid; brute force: that heat in energy mode
    # on a 0.005° grid peaks at the target (to its sampling, 1e-8), at the located angle. The
    # second law burns within a 0.89° combustion (an audit's point: the 1° grid's heat and
    # work were 0.9 % and 31 % off); both must not depend on the grid.
    row = params_row(duration_deg=duration_deg, form=form)
    row[cb.WIEBE_EFFICIENCY] = efficiency
    row[cb.HEAT_INPUT_MODE] = cb.HEAT_MODE_PEAK_PRESSURE
    out, pressure = run(row, m=360)
    assert out[0, cb.OUT_PEAK_PRESSURE] == pytest.approx(23.0e6, rel=1e-12)
    assert pressure.max() <= 23.0e6 * (1 + 1e-12)
    heat = out[0, cb.OUT_HEAT_RELEASED]
    fine_row = params_row(heat=heat, duration_deg=duration_deg, form=form)
    fine_row[cb.WIEBE_EFFICIENCY] = efficiency
    fine_out, fine = run(fine_row, m=144_000)
    assert fine.max() == pytest.approx(23.0e6, rel=1e-8)
    peak = grid(144_000)[np.argmax(fine[0])] - 2 * math.pi
    assert out[0, cb.OUT_PEAK_PRESSURE_ANGLE] == pytest.approx(peak, abs=math.radians(0.01))
    # the same heat, work and IMEP on a 2° and a 0.25° grid (to the quadrature, ~5e-9)
    again, _ = run(row, m=2880)
    angle = cb.OUT_PEAK_PRESSURE_ANGLE
    assert again[0, angle] == pytest.approx(out[0, angle], abs=1e-8)  # located to 1e-9 rad
    np.testing.assert_allclose(np.delete(again[0], angle), np.delete(out[0], angle), rtol=1e-7)
    np.testing.assert_allclose(fine_out[0, cb.OUT_CYCLE_WORK], out[0, cb.OUT_CYCLE_WORK], rtol=1e-7)


def test_unreachable_peak_target_gives_nan():
    # Motoring pressure p_a ε^k = 10.6 MPa already exceeds a 5 MPa target.
    row = params_row()
    row[cb.HEAT_INPUT_MODE] = cb.HEAT_MODE_PEAK_PRESSURE
    row[cb.PEAK_PRESSURE_TARGET] = 5.0e6
    out, pressure = run(row)
    assert math.isnan(out[0, cb.OUT_PEAK_PRESSURE])
    assert math.isnan(out[0, cb.OUT_CYCLE_WORK])
    assert np.isnan(pressure[0, 720])


@settings(max_examples=60, deadline=None)
@given(st.floats(0.001, 0.999), st.floats(0.0, 10.0), st.floats(0.01, 30.0))
def test_wiebe_angle_inverts_the_burned_fraction(tau, form, a):
    # The quadrature runs over the burned fraction: the angle of a fraction must be the one
    # that burns it (round trip through the closed-form fraction, Heywood §9.2).
    # Where 1 − x_b is below ~1e-6 the angle of a fraction is ill-conditioned (a whole tail
    # of the burn within the last bits of x_b); the quadrature's weight there is as small.
    duration = 0.7
    fraction = cb.wiebe_burned_fraction(tau * duration, duration, a, form)
    assume(1.0 - fraction > 1e-6)
    assert cb.wiebe_angle(fraction, duration, a, form) == pytest.approx(
        tau * duration, rel=1e-7, abs=1e-12
    )
    assert cb.wiebe_burned_fraction(-0.1, duration, a, form) == 0.0
    assert cb.wiebe_burned_fraction(duration, duration, a, form) == 1.0
    assert cb.wiebe_angle(0.0, duration, a, form) == 0.0
    assert cb.wiebe_angle(1.0, duration, a, form) == pytest.approx(duration, rel=1e-7)


def test_driver_is_the_same_compiled_and_interpreted():
    rows = np.array([params_row(), params_row(heat=8000.0, form=0.5)])
    out, pressure = run(rows, 240)
    out_py = np.empty_like(out)
    pressure_py = np.empty_like(pressure)
    cb.cycle_pressure_batch.py_func(rows, out_py, pressure_py)
    np.testing.assert_allclose(out_py, out, rtol=1e-12)
    np.testing.assert_allclose(pressure_py, pressure, rtol=1e-12)
