"""Multi-segment symmetric acceleration profile (physics §2, 12V150 reference set in §9)."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.integrate import quad, simpson

from engine_kernels.cam.multi_segment import (
    D_CLOSURE_RESIDUAL,
    D_EVENT_HALF_WIDTH,
    D_FILLET_MONOTONE,
    D_INPUT_VALID,
    D_NEGATIVE_SCALE,
    D_POSITIVE_SCALE,
    D_RAMP_FEASIBLE,
    D_RAW_NOSE_VELOCITY,
    D_UNSCALED_WORKING_LIFT,
    N_DIAG,
    SHAPE_FILLET,
    SHAPE_LIN,
    SHAPE_SIN_FULL,
    SHAPE_SIN_LEFT,
    multi_segment_cam,
    ramp_layout,
    segment_widths,
)

DEG = math.pi / 180.0
MM = 1e-3
# physics §9, 12V150 exhaust cam, initial design.
WIDTHS = np.array([4.5, 11.0, 4.5, 5.0, 22.0, 23.0]) * DEG
SHAPES = np.array(
    [SHAPE_LIN, SHAPE_SIN_FULL, SHAPE_LIN, SHAPE_SIN_LEFT, SHAPE_FILLET, SHAPE_SIN_LEFT],
    dtype=np.int64,
)
ACCELS = np.array([55.0, 55.0, 0.0, -12.5, -22.5, -24.5]) * MM
AMPS = np.array([0.0, 12.5, 0.0, 7.5, 0.0, 5.5]) * MM
HALF_EVENT = 70.0 * DEG
# A lash ramp inside the feasible band Hr/v <= Wr <= 2 Hr/v (assumed values, not in the source).
RAMP = (0.3 * MM, 20.0 * DEG, 1.2 * MM)


def _evaluate(
    theta,
    widths=WIDTHS,
    shapes=SHAPES,
    accels=ACCELS,
    amps=AMPS,
    ramp=(0.0, 0.0, 0.0),
    target=0.0,
    half_event=HALF_EVENT,
):
    theta = np.ascontiguousarray(theta, dtype=np.float64)
    out = np.empty((4, theta.size))
    diag = np.empty(N_DIAG)
    multi_segment_cam(theta, half_event, widths, shapes, accels, amps, *ramp, target, out, diag)
    return out, diag


def _joints(ramp, widths=WIDTHS):
    """Angles of every joint on the rising flank (ramp start, ramp knee, segment ends)."""
    height, width, velocity = ramp
    w1 = 2.0 * (width - height / velocity) if velocity > 0 else 0.0
    event = width + widths.sum()
    return np.concatenate(([-event, -event + w1], -widths.sum() + np.cumsum(np.r_[0, widths])))


def _reference_acceleration(sp, sn):
    """The physics §2 profile written out directly, as a function of s from the ramp end [rad]."""
    scale = np.array([sp] * 3 + [sn] * 3)
    a_end = ACCELS * scale
    amp = AMPS * scale * np.array([1, 1, 1, -1, -1, -1])
    starts = np.r_[0.0, np.cumsum(WIDTHS)]
    a_start = np.r_[0.0, a_end[:-1]]

    def seg(k, x):
        line = a_start[k] + (a_end[k] - a_start[k]) * x
        if k == 1:  # sin_full
            return line + amp[k] * math.sin(math.pi * x)
        if k in (3, 5):  # sin_left
            return line + amp[k] * (math.sin(math.pi * x / 2) - x)
        if k == 4:  # fillet: cubic Hermite, slopes of seg 4 (end) and seg 6 (start) per x
            d3 = a_end[3] - a_start[3]
            d5 = a_end[5] - a_start[5]
            m0 = (d3 - amp[3]) / WIDTHS[3] * WIDTHS[4]
            m1 = (d5 + amp[5] * (math.pi / 2 - 1)) / WIDTHS[5] * WIDTHS[4]
            y0, y1 = a_start[4], a_end[4]
            return (
                (2 * x**3 - 3 * x**2 + 1) * y0
                + (x**3 - 2 * x**2 + x) * m0
                + (-2 * x**3 + 3 * x**2) * y1
                + (x**3 - x**2) * m1
            )
        return line

    def accel(s):
        k = min(int(np.searchsorted(starts, s, side="right")) - 1, 5)
        return seg(k, (s - starts[k]) / WIDTHS[k])

    return accel, starts


def test_width_rule_reproduces_the_chosen_12v150_design():
    # physics §9: segment 2 going 11 -> 9 deg makes the fillet 22 -> 23 and segment 6 23 -> 24.
    nominal = np.array([4.5, 9.0, 4.5, 5.0, 22.0, 23.0]) * DEG
    out = np.empty(6)
    assert segment_widths(nominal, SHAPES, HALF_EVENT, out)
    np.testing.assert_allclose(out / DEG, [4.5, 9.0, 4.5, 5.0, 23.0, 24.0], atol=1e-12)


def test_width_rule_without_fillet_uses_the_last_segment_and_flags_negative_widths():
    out = np.empty(6)
    shapes = np.full(6, SHAPE_LIN, dtype=np.int64)
    nominal = np.array([4.5, 9.0, 4.5, 5.0, 22.0, 23.0]) * DEG
    assert segment_widths(nominal, shapes, HALF_EVENT, out)
    np.testing.assert_allclose(out / DEG, [4.5, 9.0, 4.5, 5.0, 22.0, 25.0], atol=1e-12)
    assert not segment_widths(nominal, shapes, 30.0 * DEG, out)  # last would be -13 deg


def test_12v150_unscaled_working_lift_matches_quadrature_of_the_spec_profile():
    # Independent: the physics §2 profile written out above, integrated by adaptive quadrature.
    # Closure fixes sn from ∫a = 0 over the working part; the nose lift is ∫(W - s) a(s) ds.
    half = WIDTHS.sum()
    pos, starts = _reference_acceleration(1.0, 0.0)
    neg, _ = _reference_acceleration(0.0, 1.0)
    pts = starts[1:-1]
    v_pos = quad(pos, 0.0, half, points=pts, epsabs=1e-14)[0]
    v_neg = quad(neg, 0.0, half, points=pts, epsabs=1e-14)[0]
    sn = -v_pos / v_neg
    full, _ = _reference_acceleration(1.0, sn)
    lift = quad(lambda s: (half - s) * full(s), 0.0, half, points=pts, epsabs=1e-15)[0]
    out, diag = _evaluate(np.array([0.0]))
    assert diag[D_NEGATIVE_SCALE] == pytest.approx(sn, rel=1e-10)
    assert diag[D_UNSCALED_WORKING_LIFT] == pytest.approx(lift, rel=1e-10)
    assert out[0, 0] == pytest.approx(lift, rel=1e-10)
    assert diag[D_RAW_NOSE_VELOCITY] == pytest.approx(v_pos + v_neg, rel=1e-10)
    # physics §9: "about 10.8 mm" for the source's scaled profiles.
    assert 10.0 * MM < lift < 11.5 * MM


@pytest.mark.parametrize("ramp", [(0.0, 0.0, 0.0), RAMP])
def test_closure_symmetry_and_base_circle(ramp):
    theta = np.linspace(-math.pi, math.pi, 4001)
    out, diag = _evaluate(theta, ramp=ramp)
    assert diag[D_INPUT_VALID] == 1.0
    assert diag[D_CLOSURE_RESIDUAL] == pytest.approx(0.0, abs=1e-15)
    nose = out[:, theta.size // 2]
    assert nose[1] == pytest.approx(0.0, abs=1e-15)
    np.testing.assert_allclose(out[0], out[0, ::-1], atol=1e-15)
    np.testing.assert_allclose(out[1], -out[1, ::-1], atol=1e-15)
    np.testing.assert_allclose(out[2], out[2, ::-1], atol=1e-15)
    # h''' is odd but jumps at the nose (segment 6 ends with da/dθ != 0), so skip θ = 0.
    jerk = np.delete(out[3], theta.size // 2)
    np.testing.assert_allclose(jerk, -jerk[::-1], atol=1e-12)
    assert diag[D_EVENT_HALF_WIDTH] == pytest.approx(HALF_EVENT + ramp[1], abs=1e-15)
    assert np.all(out[:, np.abs(theta) > diag[D_EVENT_HALF_WIDTH]] == 0.0)


def test_continuity_at_every_joint():
    eps = 1e-9
    joints = _joints(RAMP)
    theta = np.concatenate([joints - eps, joints + eps])
    out, _ = _evaluate(np.concatenate([theta, -theta]), ramp=RAMP)
    n = joints.size
    for half in (0, 2 * n):
        left = out[:, half : half + n]
        right = out[:, half + n : half + 2 * n]
        np.testing.assert_allclose(left[0], right[0], atol=1e-12)  # lift [m]
        np.testing.assert_allclose(left[1], right[1], atol=1e-10)  # velocity [m/rad]
        # Acceleration steps only at the ramp start and knee (physics §2: constant-acceleration
        # ramp); the working part and its joint with the ramp are continuous.
        np.testing.assert_allclose(left[2, 2:], right[2, 2:], atol=1e-8)
    velocity = RAMP[2]
    ramp_accel = velocity / (2.0 * (RAMP[1] - RAMP[0] / velocity))
    assert right[2, 0] - left[2, 0] == pytest.approx(ramp_accel, rel=1e-9)


def test_ramp_end_state_is_the_given_height_and_velocity():
    out, diag = _evaluate(np.array([-HALF_EVENT]), ramp=RAMP)
    assert diag[D_RAMP_FEASIBLE] == 1.0
    assert out[0, 0] == pytest.approx(RAMP[0], rel=1e-12)
    assert out[1, 0] == pytest.approx(RAMP[2], rel=1e-12)


@pytest.mark.parametrize("ramp", [(0.0, 0.0, 0.0), RAMP])
def test_derivatives_are_exact_between_joints(ramp):
    # Simpson's rule on 2001 points per smooth piece (pieces end just short of each joint):
    # each derivative must integrate to the increment of the quantity above it.
    joints = np.r_[_joints(ramp), 0.0]
    if ramp[1] == 0.0:
        joints = joints[2:]
    for a, b in itertools.pairwise(joints):
        for sign in (1.0, -1.0):
            theta = sign * np.linspace(a + 1e-12, b - 1e-12, 2001)
            out, _ = _evaluate(theta, ramp=ramp)
            for k, atol in ((0, 1e-14), (1, 1e-13), (2, 1e-11)):
                increment = out[k, -1] - out[k, 0]
                assert increment == pytest.approx(simpson(out[k + 1], x=theta), abs=atol)


def test_target_lift_without_ramp_is_a_uniform_scale():
    theta = np.linspace(-1.3, 1.3, 1001)
    plain, plain_diag = _evaluate(theta)
    target = 10.8 * MM  # physics §9
    scaled, diag = _evaluate(theta, target=target)
    factor = target / plain_diag[D_UNSCALED_WORKING_LIFT]
    np.testing.assert_allclose(scaled, factor * plain, rtol=1e-12, atol=1e-16)
    assert diag[D_POSITIVE_SCALE] == pytest.approx(factor, rel=1e-12)
    assert diag[D_NEGATIVE_SCALE] == pytest.approx(factor * plain_diag[D_NEGATIVE_SCALE], rel=1e-12)
    assert scaled[0, theta.size // 2] == pytest.approx(target, rel=1e-12)


def test_target_lift_with_ramp_solves_closure_and_lift_together():
    target = 10.8 * MM
    out, diag = _evaluate(np.array([-HALF_EVENT, 0.0]), ramp=RAMP, target=target)
    assert out[0, 1] - out[0, 0] == pytest.approx(target, rel=1e-12)
    assert out[1, 1] == pytest.approx(0.0, abs=1e-15)
    assert diag[D_POSITIVE_SCALE] != pytest.approx(diag[D_NEGATIVE_SCALE], rel=1e-3)


@settings(max_examples=30, deadline=None)
@given(
    st.floats(7.0, 11.0),
    st.floats(0.0, 20.0),
    st.floats(0.0, 10.0),
    st.floats(0.0, 8.0),
    st.floats(0.0, 0.5),
)
def test_closure_holds_for_any_segment_2_width_and_amplitudes(width2, amp2, amp4, amp6, target):
    widths = WIDTHS.copy()
    widths[1] = width2 * DEG
    amps = np.array([0.0, amp2, 0.0, amp4, 0.0, amp6]) * MM
    out, diag = _evaluate(
        np.array([-HALF_EVENT, 0.0]), widths=widths, amps=amps, ramp=RAMP, target=target * 2e-2
    )
    # Closure (physics §2): zero velocity at the nose whatever the factors; the half-event
    # stays fixed by the width rule.
    assert out[1, 1] == pytest.approx(0.0, abs=1e-15)
    assert diag[D_EVENT_HALF_WIDTH] == pytest.approx(HALF_EVENT + RAMP[1], abs=1e-15)


@settings(max_examples=50, deadline=None)
@given(st.floats(0.0, 1e-3), st.floats(0.0, 0.6), st.floats(1e-4, 5e-3))
def test_ramp_layout_feasibility_band(height, width, velocity):
    w1, actual, used, feasible = ramp_layout(height, width, velocity)
    # physics §2: feasible iff Hr/v <= Wr <= 2 Hr/v (tested away from the band edges).
    lo, hi = height / velocity, 2.0 * height / velocity
    if lo * (1 + 1e-9) < width < hi * (1 - 1e-9):
        assert feasible
    elif width < lo * (1 - 1e-9) or width > hi * (1 + 1e-9):
        assert not feasible
    assert 0.0 <= w1 <= width
    assert used == velocity
    # Closed form of constant acceleration v/w1 over w1, then constant velocity.
    assert actual == pytest.approx(0.5 * velocity * w1 + velocity * (width - w1), rel=1e-12)
    if feasible:
        assert actual == pytest.approx(height, rel=1e-9, abs=1e-15)


def test_infeasible_ramp_is_reported_not_raised():
    ramp = (0.3 * MM, 40.0 * DEG, 1.2 * MM)  # Wr > 2 Hr/v
    out, diag = _evaluate(np.linspace(-1.5, 1.5, 301), ramp=ramp)
    assert diag[D_RAMP_FEASIBLE] == 0.0
    assert diag[D_INPUT_VALID] == 1.0
    assert np.all(np.isfinite(out))


def test_fillet_monotone_flag_detects_an_overshoot():
    theta = np.linspace(-HALF_EVENT, 0.0, 20001)
    fillet = (theta > -HALF_EVENT + WIDTHS[:4].sum()) & (theta < -WIDTHS[5])
    out, diag = _evaluate(theta)
    accel = out[2, fillet]
    assert diag[D_FILLET_MONOTONE] == 1.0
    assert np.all(np.diff(accel) <= 1e-15)  # brute force: the fillet really is monotone
    # A large segment-4 bulge ends with da/dθ > 0 while the fillet must fall: overshoot.
    amps = AMPS.copy()
    amps[3] = 30.0 * MM
    out, diag = _evaluate(theta, amps=amps)
    accel = out[2, fillet]
    assert diag[D_FILLET_MONOTONE] == 0.0
    assert accel.max() > accel[0] + 1e-6


def test_invalid_shape_gives_nan_and_flag():
    shapes = SHAPES.copy()
    shapes[2] = 9
    out, diag = _evaluate(np.array([-0.5, 0.0]), shapes=shapes)
    assert diag[D_INPUT_VALID] == 0.0
    assert np.all(np.isnan(out))
