"""Rocker kinematics [R1]–[R6]: reference angles, lift ratio, brute-force geometric oracle."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from numpy.polynomial import polynomial as poly

from engine_kernels.valvetrain import rocker, rocker_batches

MM = 1e-3
# physics §3 reference geometry (125 cc motorcycle): r0, rs, la, lc, lb, rho_b, z, lash [mm].
GEOMETRY = np.array([12.5, 30.0, 39.61, 30.28, 33.28, 10.0, 1.65, 0.05]) * MM
TARGET_VALVE_LIFT = 7.815 * MM
EVENT_HALF_ANGLE = math.radians(80.0)
# h(u) = H (1 - u^2)^3 (1 + 2u^2), u = phi/beta: symmetric, C2 at the event ends, and convex
# (min r0 + h + h'' = 3.3 mm) over +-80 deg at 6.30 mm of tappet lift.
LAW = np.array([1.0, 0.0, -1.0, 0.0, -3.0, 0.0, 5.0, 0.0, -2.0])


def synthetic_law(phi, height, half_angle):
    """Closed-form flat-tappet law and its first two derivatives per rad."""
    u = phi / half_angle
    inside = np.abs(u) < 1.0
    return tuple(
        np.where(inside, height * poly.polyval(u, poly.polyder(LAW, d)) / half_angle**d, 0.0)
        for d in range(3)
    )


def chain(side, theta, height=None, half_angle=EVENT_HALF_ANGLE, step_deg=0.25):
    if height is None:
        height = rocker.tappet_lift_for_valve_lift(TARGET_VALVE_LIFT, GEOMETRY)
    phi = np.radians(np.arange(-120.0, 120.0 + step_deg / 2, step_deg))
    h, dh, ddh = synthetic_law(phi, height, half_angle)
    out = np.empty((6, theta.size))
    status = rocker.rocker_valve_lift(phi, h, dh, ddh, GEOMETRY, side, theta, out)
    return status, out


def brute_force(side, theta, height):
    """Independent oracle: the cam as the envelope of its tappet lines, rotated, and the rocker
    angle at which the pad circle clears every outline vertex.

    Returns the rocker angle W(theta) and the tappet angle of the touching vertex.
    """
    r0, rs, la, lc = GEOMETRY[:4]
    fine = np.radians(np.arange(-180.0, 180.0, 0.05))
    h = synthetic_law(fine, height, EVENT_HALF_ANGLE)[0]
    # Tappet line for table angle phi: x . n(-phi) = r0 + h (the cam turns counter-clockwise).
    normal = np.stack([np.cos(-fine), np.sin(-fine)], axis=1)
    support = r0 + h
    nxt, snxt = np.roll(normal, -1, axis=0), np.roll(support, -1)
    det = normal[:, 0] * nxt[:, 1] - normal[:, 1] * nxt[:, 0]
    vx = (support * nxt[:, 1] - snxt * normal[:, 1]) / det
    vy = (normal[:, 0] * snxt - nxt[:, 0] * support) / det
    vertex_phi = fine + np.radians(0.025)
    # Nose contact: pad centre on both circles |A| = r0 + rs + H and |A - O| = la, O = (lc, 0).
    nose_r = r0 + rs + height
    ax = (nose_r**2 - la**2 + lc**2) / (2.0 * lc)
    nose_rotation = math.atan2(side * math.sqrt(nose_r**2 - ax**2), ax)
    angle = np.empty(theta.size)
    touching = np.empty(theta.size)
    for q, t in enumerate(theta + nose_rotation):
        qx = math.cos(t) * vx - math.sin(t) * vy - lc
        qy = math.sin(t) * vx + math.cos(t) * vy
        dist = np.hypot(qx, qy)
        cosine = (la**2 + dist**2 - rs**2) / (2.0 * la * dist)
        # Pad centre A(W) = O + la (-cos W, side sin W) leaves the rs-disc of a vertex at
        # W = alpha + acos(cosine); the rocker sits at the largest such exit angle.
        exit_angle = np.arctan2(side * qy, -qx) + np.arccos(np.clip(cosine, -1.0, 1.0))
        exit_angle[np.abs(cosine) > 1.0] = -np.inf
        best = np.argmax(exit_angle)
        angle[q] = exit_angle[best]
        # Vertex index of the touch refined by a parabola through the three best exit angles.
        left, mid, right = exit_angle[best - 1 : best + 2]
        offset = 0.5 * (left - right) / (left - 2.0 * mid + right)
        touching[q] = vertex_phi[best] + offset * np.radians(0.05)
    return angle, touching


def valve_lift_from_angle(angle):
    """[R6] written out with numpy (stem-tip geometry of physics §3)."""
    r0, rs, la, lc, lb, ball, z, lash = GEOMETRY
    base = math.acos((la**2 + lc**2 - (r0 + rs) ** 2) / (2 * la * lc))
    beta0 = math.asin((lash + ball + z) / lb)
    return np.maximum(lb * (math.sin(beta0) - np.sin(beta0 - (angle - base))) - lash, 0.0)


def test_reference_angles():
    # physics §3 reference values: W0 = 73.543 deg, beta0 = 20.583 deg.
    r0, rs, la, lc, lb, ball, z, lash = GEOMETRY
    w0 = rocker.base_circle_rocker_angle(r0, rs, la, lc)
    beta0 = rocker.valve_arm_base_angle(lb, ball, z, lash)
    assert math.degrees(w0) == pytest.approx(73.543, abs=5e-4)
    assert math.degrees(beta0) == pytest.approx(20.583, abs=5e-4)


def test_tappet_lift_for_reference_valve_lift():
    # physics §3: 7.815 mm of theoretical valve lift is "about 6.30 mm" of tappet lift.
    assert rocker.tappet_lift_for_valve_lift(TARGET_VALVE_LIFT, GEOMETRY) == pytest.approx(
        6.30 * MM, abs=0.01 * MM
    )


@pytest.mark.parametrize(("tappet_lift", "expected"), [(0.0, 1.15), (6.30 * MM, 1.35)])
def test_lift_ratio_base_circle_and_nose(tappet_lift, expected):
    # physics §3: dY/dh is "about 1.15 on the base circle and 1.35 at the nose" (h' = 0 there).
    r0, rs, la, lc, lb, ball, z, lash = GEOMETRY
    w0 = rocker.base_circle_rocker_angle(r0, rs, la, lc)
    beta0 = rocker.valve_arm_base_angle(lb, ball, z, lash)

    def raw_lift(h):
        w = rocker.rocker_angle(la, lc, rocker.pad_centre_distance(r0, rs, h, 0.0))
        return rocker.valve_lift_from_rocker_angle(w, w0, beta0, lb, lash)

    step = 1e-6
    ratio = (raw_lift(tappet_lift + step) - raw_lift(tappet_lift - step)) / (2 * step)
    assert ratio == pytest.approx(expected, abs=0.01)


@settings(max_examples=30, deadline=None)
@given(st.floats(min_value=0.5, max_value=9.0))
def test_nose_lift_round_trip(valve_lift_mm):
    # Closed form: the chain at the nose (h' = 0) must return the valve lift it was scaled to.
    height = rocker.tappet_lift_for_valve_lift(valve_lift_mm * MM, GEOMETRY)
    theta = np.array([-0.01, 0.0, 0.01])
    status, out = chain(rocker.PAD_AHEAD, theta, height=height, half_angle=math.radians(90.0))
    assert status == rocker.ROCKER_OK
    assert out[rocker.ROW_VALVE_LIFT, 1] == pytest.approx(valve_lift_mm * MM, rel=1e-12)


@pytest.mark.parametrize("side", [rocker.PAD_AHEAD, rocker.PAD_BEHIND])
def test_chain_matches_brute_force(side):
    # Oracle: brute-force geometric contact (polygon vertices every 0.05 deg of cam).
    theta = np.radians(np.arange(-100.0, 100.0 + 0.25, 0.5))
    height = rocker.tappet_lift_for_valve_lift(TARGET_VALVE_LIFT, GEOMETRY)
    status, out = chain(side, theta)
    assert status == rocker.ROCKER_OK
    angle, _ = brute_force(side, theta, height)
    np.testing.assert_allclose(out[rocker.ROW_ROCKER_ANGLE], angle, rtol=0, atol=1e-6)
    # Grid resolution: the lift changes by up to 0.12 mm per 0.5 deg; agreement is ~1e-8 m.
    np.testing.assert_allclose(
        out[rocker.ROW_VALVE_LIFT], valve_lift_from_angle(angle), rtol=0, atol=1e-7
    )


@pytest.mark.parametrize("side", [rocker.PAD_AHEAD, rocker.PAD_BEHIND])
def test_force_ratio_matches_cam_side_virtual_work(side):
    # Power balance (frictionless): cam torque F h' times omega = valve force times dY/dt, so
    # i = h'(phi_contact)/Y'(theta), with phi_contact and Y' taken from the brute-force oracle.
    # Both forces push, so i > 0 on either side (the pad behind gave -i until 2026-12-07).
    step = math.radians(0.1)
    theta = np.arange(math.radians(-75.0), math.radians(75.0), step)
    height = rocker.tappet_lift_for_valve_lift(TARGET_VALVE_LIFT, GEOMETRY)
    _, out = chain(side, theta)
    angle, touching = brute_force(side, theta, height)
    valve_velocity = np.gradient(valve_lift_from_angle(angle), step)
    tappet_velocity = synthetic_law(touching, height, EVENT_HALF_ANGLE)[1]
    usable = np.abs(valve_velocity) > 2.0 * MM
    usable[[0, -1]] = False
    assert usable.sum() > 500
    np.testing.assert_allclose(
        out[rocker.ROW_FORCE_RATIO][usable],
        tappet_velocity[usable] / valve_velocity[usable],
        rtol=2e-3,
    )


def test_symmetric_cam_asymmetry_sign():
    # Documented sign (module docstring): pad ahead of OcO -> shorter, steeper opening flank;
    # pad behind is the exact mirror image for a symmetric cam (geometric reflection).
    theta = np.radians(np.arange(-100.0, 100.0 + 0.25, 0.5))
    _, ahead = chain(rocker.PAD_AHEAD, theta)
    _, behind = chain(rocker.PAD_BEHIND, theta)
    lift = ahead[rocker.ROW_VALVE_LIFT]
    open_angles = theta[lift > 0.0]
    assert -open_angles[0] < open_angles[-1]
    velocity = ahead[rocker.ROW_VALVE_VELOCITY]
    assert velocity.max() > -velocity.min()
    np.testing.assert_allclose(behind[rocker.ROW_VALVE_LIFT], lift[::-1], rtol=0, atol=1e-12)


def test_concave_cam_is_reported_not_raised():
    # +-65 deg at 6.30 mm makes r0 + h + h'' negative (closed form of the law: min -4.0 mm).
    theta = np.radians(np.arange(-100.0, 100.0, 0.5))
    status, out = chain(rocker.PAD_AHEAD, theta, half_angle=math.radians(65.0))
    assert status & rocker.ROCKER_CONCAVE_CAM
    assert np.isfinite(out).all()


def test_batch_and_interpreted_agree_with_single():
    # Same kernel three ways: prange batch, compiled single case, plain Python.
    theta = np.radians(np.arange(-90.0, 90.0, 1.0))
    phi = np.radians(np.arange(-120.0, 120.0, 0.5))
    height = rocker.tappet_lift_for_valve_lift(TARGET_VALVE_LIFT, GEOMETRY)
    h, dh, ddh = synthetic_law(phi, height, EVENT_HALF_ANGLE)
    geometry = np.stack([GEOMETRY, GEOMETRY * np.array([1, 1, 1.02, 1, 0.98, 1, 1, 1.5])])
    out = np.empty((2, 6, theta.size))
    status = np.empty(2, dtype=np.int64)
    rocker_batches.rocker_valve_lift_batch(
        phi, h, dh, ddh, geometry, rocker.PAD_BEHIND, theta, out, status
    )
    for i in range(2):
        single = np.empty((6, theta.size))
        plain = np.empty((6, theta.size))
        code = rocker.rocker_valve_lift(
            phi, h, dh, ddh, geometry[i], rocker.PAD_BEHIND, theta, single
        )
        rocker.rocker_valve_lift.py_func(
            phi, h, dh, ddh, geometry[i], rocker.PAD_BEHIND, theta, plain
        )
        assert status[i] == code == rocker.ROCKER_OK
        np.testing.assert_allclose(out[i], single, rtol=1e-12, atol=1e-15)
        np.testing.assert_allclose(plain, single, rtol=1e-10, atol=1e-13)
