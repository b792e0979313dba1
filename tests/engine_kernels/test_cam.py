"""Cam curvature, lubrication and contact kernels (physics §2, [C1]-[C5])."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from engine_kernels.cam.contact import (
    contact_force,
    effective_modulus,
    entrainment_velocity,
    film_thickness_dowson_higginson,
    fullness_coefficient,
    hertz_line_contact_stress,
    lubrication_coefficient,
    radius_of_curvature,
    relative_film_thickness,
    spring_margin,
)
from engine_kernels.cam.lift_laws import LAW_CYCLOIDAL, LAW_HARMONIC, NCOEF, rise_return_cam
from engine_kernels.cam.multi_segment import (
    N_DIAG,
    SHAPE_FILLET,
    SHAPE_LIN,
    SHAPE_SIN_FULL,
    SHAPE_SIN_LEFT,
    multi_segment_cam,
)

DEG = math.pi / 180.0
MM = 1e-3
STEEL_E = 210e9
STEEL_NU = 0.3


def _cycloidal_cam(theta, lift, beta):
    out = np.empty((4, theta.size))
    rise_return_cam(LAW_CYCLOIDAL, lift, beta, np.zeros(NCOEF), theta, out)
    return out


def _spec_12v150_cam(theta):
    # physics §9 initial design, no ramp, closure only.
    out = np.empty((4, theta.size))
    multi_segment_cam(
        theta,
        70.0 * DEG,
        np.array([4.5, 11.0, 4.5, 5.0, 22.0, 23.0]) * DEG,
        np.array(
            [SHAPE_LIN, SHAPE_SIN_FULL, SHAPE_LIN, SHAPE_SIN_LEFT, SHAPE_FILLET, SHAPE_SIN_LEFT],
            dtype=np.int64,
        ),
        np.array([55.0, 55.0, 0.0, -12.5, -22.5, -24.5]) * MM,
        np.array([0.0, 12.5, 0.0, 7.5, 0.0, 5.5]) * MM,
        0.0,
        0.0,
        0.0,
        0.0,
        out,
        np.empty(N_DIAG),
    )
    return out


def _envelope_radius(theta, base_radius, curves):
    """Brute force: signed radius of the cam outline measured on the polygon of contact points.

    The tappet face at cam angle θ is the line x·n(θ) = r0 + h(θ), n = (cos θ, sin θ); the
    envelope of these lines is p(θ) = (r0 + h) n + h' t with t = dn/dθ. The radius is that of
    the circle through three consecutive points; it is negative where the outline runs
    backwards along t (the envelope folds: a cusped, concave cam)."""
    p_normal = base_radius + curves[0]
    n = np.stack([np.cos(theta), np.sin(theta)])
    t = np.stack([-np.sin(theta), np.cos(theta)])
    p = p_normal * n + curves[1] * t
    a, b, c = p[:, :-2], p[:, 1:-1], p[:, 2:]
    ab = np.linalg.norm(b - a, axis=0)
    bc = np.linalg.norm(c - b, axis=0)
    ca = np.linalg.norm(a - c, axis=0)
    cross = (b - a)[0] * (c - a)[1] - (b - a)[1] * (c - a)[0]
    radius = ab * bc * ca / (2.0 * np.abs(cross))
    forward = np.sign(np.sum((c - a) * t[:, 1:-1], axis=0))
    return forward * radius


def test_radius_of_curvature_matches_the_envelope_of_the_tappet_face():
    theta = np.linspace(-1.4, 1.4, 28001)
    base_radius = 20.5 * MM
    curves = _spec_12v150_cam(theta)
    rho = np.array([radius_of_curvature(base_radius, h, a) for h, a in curves[[0, 2]].T])
    brute = _envelope_radius(theta, base_radius, curves)
    # The three-point circle is only first-order accurate where the jerk jumps (segment
    # joints, event ends, nose), so leave out the points next to those.
    joints = np.cumsum([0.0, 4.5, 11.0, 4.5, 5.0, 22.0, 23.0]) * DEG - 70.0 * DEG
    joints = np.concatenate([joints, -joints])
    near = np.abs(theta[1:-1, None] - joints[None, :]).min(axis=1) < 2.5 * (theta[1] - theta[0])
    np.testing.assert_allclose(brute[~near], rho[1:-1][~near], rtol=1e-6)


def test_radius_of_curvature_is_negative_where_the_envelope_folds():
    theta = np.linspace(-0.6, 0.6, 120_001)
    base_radius = 0.5 * MM
    curves = _cycloidal_cam(theta, 10.0 * MM, 0.5)
    rho = np.array([radius_of_curvature(base_radius, h, a) for h, a in curves[[0, 2]].T])
    brute = _envelope_radius(theta, base_radius, curves)
    assert rho.min() < -0.1  # a cusped cam: r0 + h + h'' well below zero
    # Away from the folds (rho through 0) and from the jerk jumps at the nose and event ends.
    step = theta[1] - theta[0]
    inner = theta[1:-1]
    kinks = np.minimum(np.abs(inner), np.abs(np.abs(inner) - 0.5))
    safe = (np.abs(rho[1:-1]) > 2 * MM) & (kinks > 2.5 * step)
    np.testing.assert_allclose(brute[safe], rho[1:-1][safe], rtol=1e-4)


@settings(max_examples=50, deadline=None)
@given(st.floats(5e-3, 50e-3), st.floats(0.0, 20e-3), st.floats(-0.1, 0.1), st.floats(1.0, 700.0))
def test_lubrication_coefficient_and_entrainment_identities(base_radius, lift, accel, speed):
    rho = radius_of_curvature(base_radius, lift, accel)
    n = lubrication_coefficient(base_radius, lift, accel)
    # [C2]: N = rho/(r0 + h).
    assert n == pytest.approx(rho / (base_radius + lift), rel=1e-12)
    # [C3]: u_e is the mean of the cam-surface speed ω rho and the face speed ω h''.
    u = entrainment_velocity(speed, base_radius, lift, accel)
    assert u == pytest.approx(speed * (rho + accel) / 2.0, rel=1e-10, abs=1e-12)
    # [C4]: the two forms of the relative film thickness agree where rho > 0.
    if rho > 0.0:
        first = 0.5 * math.sqrt(abs(u) * rho / (speed * (base_radius + lift) ** 2))
        assert relative_film_thickness(n) == pytest.approx(first, rel=1e-10, abs=1e-15)


def test_relative_film_thickness_special_values():
    # [C4]: 0.354 on the base circle (N = 1), zero at N = 0 and N = 0.5 where the
    # entrainment reverses, a local maximum 0.125 at N = 0.25.
    assert relative_film_thickness(1.0) == pytest.approx(0.354, abs=5e-4)
    assert relative_film_thickness(1.0) == pytest.approx(1.0 / (2.0 * math.sqrt(2.0)), rel=1e-5)
    assert relative_film_thickness(0.0) == 0.0
    assert relative_film_thickness(0.5) == 0.0
    assert relative_film_thickness(0.25) == pytest.approx(0.125, rel=1e-4)
    assert relative_film_thickness(0.24) < relative_film_thickness(0.25)
    assert relative_film_thickness(0.26) < relative_film_thickness(0.25)


def test_effective_modulus_steel_on_steel():
    # physics §2 / Johnson §4.2: E* = E/(2(1 - nu²)) = 115.4 GPa for 210 GPa, 0.3.
    modulus = effective_modulus(STEEL_E, STEEL_NU, STEEL_E, STEEL_NU)
    assert modulus == pytest.approx(115.4e9, abs=0.05e9)
    assert modulus == pytest.approx(STEEL_E / (2.0 * (1.0 - STEEL_NU**2)), rel=1e-14)


def test_hertz_line_contact_hand_calculation():
    # Johnson, Contact Mechanics §4.3, via the contact half-width: a² = 4 P R/(π E*),
    # p0 = 2 P/(π a), P the load per unit length. Steel cylinder R = 10 mm, 1000 N over 10 mm.
    modulus = STEEL_E / (2.0 * (1.0 - STEEL_NU**2))
    load, width, radius = 1000.0, 10.0 * MM, 10.0 * MM
    per_length = load / width
    half_width = math.sqrt(4.0 * per_length * radius / (math.pi * modulus))
    expected = 2.0 * per_length / (math.pi * half_width)
    assert expected == pytest.approx(606.0e6, rel=1e-3)  # hand calculation: 606 MPa
    assert hertz_line_contact_stress(load, modulus, width, radius) == pytest.approx(
        expected, rel=1e-12
    )


def test_hertz_stress_edge_cases_are_numbers():
    assert hertz_line_contact_stress(0.0, 115e9, 0.02, 0.01) == 0.0
    assert hertz_line_contact_stress(-5.0, 115e9, 0.02, 0.01) == 0.0
    assert hertz_line_contact_stress(100.0, 115e9, 0.02, 0.0) == math.inf
    assert hertz_line_contact_stress(100.0, 115e9, 0.02, -1e-3) == math.inf


def test_dowson_higginson_hand_calculation_with_reduced_modulus_2e_star():
    # Dowson & Higginson line contact, h_min = 2.65 R U^0.7 G^0.54 W^-0.13 with
    # E' = 2/[(1 - nu1²)/E1 + (1 - nu2²)/E2] = 231 GPa for steel. Hand-evaluated groups:
    # R = 10 mm, u = 5 m/s, w = 40 kN/m, eta0 = 0.01 Pa s, alpha = 2e-8 1/Pa.
    e_prime = 2.0 / (2.0 * (1.0 - STEEL_NU**2) / STEEL_E)
    u_group = 0.01 * 5.0 / (e_prime * 0.01)
    g_group = 2e-8 * e_prime
    w_group = 4e4 / (e_prime * 0.01)
    expected = 2.65 * 0.01 * u_group**0.7 * g_group**0.54 * w_group**-0.13
    assert expected == pytest.approx(0.3597e-6, rel=2e-4)  # by hand (logarithms): 0.3597 µm
    got = film_thickness_dowson_higginson(0.01, 5.0, 4e4, 0.01, 2e-8, e_prime / 2.0)
    assert got == pytest.approx(expected, rel=1e-12)


@settings(max_examples=30, deadline=None)
@given(st.floats(1e-3, 0.05), st.floats(0.1, 20.0), st.floats(1e3, 1e6), st.floats(1.1, 4.0))
def test_dowson_higginson_exponents(radius, speed, load, factor):
    # Power-law scaling of the formula: h ∝ |u|^0.7 and h ∝ w^-0.13.
    base = film_thickness_dowson_higginson(radius, speed, load, 0.01, 2e-8, 115e9)
    faster = film_thickness_dowson_higginson(radius, -factor * speed, load, 0.01, 2e-8, 115e9)
    heavier = film_thickness_dowson_higginson(radius, speed, factor * load, 0.01, 2e-8, 115e9)
    assert faster / base == pytest.approx(factor**0.7, rel=1e-10)
    assert heavier / base == pytest.approx(factor**-0.13, rel=1e-10)


def test_dowson_higginson_edge_cases_are_numbers():
    assert film_thickness_dowson_higginson(-1e-3, 5.0, 4e4, 0.01, 2e-8, 115e9) == 0.0
    assert film_thickness_dowson_higginson(1e-2, 5.0, 0.0, 0.01, 2e-8, 115e9) == math.inf


def test_contact_force_closed_form():
    # physics §2: F = Ps0 + ks h + m_eq ω² h''; 1300 rpm camshaft.
    omega = 1300.0 * 2.0 * math.pi / 60.0
    expected = 400.0 + 40e3 * 0.01 + 0.3 * omega**2 * (-0.02)
    assert contact_force(400.0, 40e3, 0.3, omega, 0.01, -0.02) == pytest.approx(expected)
    assert expected == pytest.approx(800.0 - 111.2, abs=0.1)  # hand: 0.3·136.14²·0.02 = 111.2 N


@pytest.mark.parametrize("law", [LAW_CYCLOIDAL, LAW_HARMONIC])
def test_fullness_of_symmetric_laws_is_one_half(law):
    # ∫0^1 f dx = 1/2 for every point-symmetric rise law, so fullness = 1/2 exactly.
    beta = 1.0
    theta = np.linspace(-beta, beta, 20001)
    out = np.empty((4, theta.size))
    rise_return_cam(law, 0.01, beta, np.zeros(NCOEF), theta, out)
    assert fullness_coefficient(theta, out[0], 2.0 * beta) == pytest.approx(0.5, rel=1e-8)


def test_fullness_degenerate_cases():
    theta = np.linspace(-1.0, 1.0, 11)
    assert fullness_coefficient(theta, np.zeros(11), 2.0) == 0.0
    assert fullness_coefficient(theta, np.full(11, 1e-3), 2.0) == pytest.approx(1.0)


def test_spring_margin_hand_calculation():
    lift = np.array([0.0, 1e-3, 2e-3, 3e-3])
    accel = np.array([0.01, -0.02, -0.01, 0.0])
    omega = 100.0
    inertia = 0.3 * omega**2
    expected = min(
        (400.0 + 40e3 * 1e-3) / (inertia * 0.02), (400.0 + 40e3 * 2e-3) / (inertia * 0.01)
    )
    assert spring_margin(lift, accel, 400.0, 40e3, 0.3, omega) == pytest.approx(expected)
    assert spring_margin(lift, np.abs(accel), 400.0, 40e3, 0.3, omega) == math.inf
