"""Batch drivers of the cam scene against Python loops over the scalar kernels (physics §2, §8)."""

from __future__ import annotations

import math
import os
import subprocess
import sys
from types import SimpleNamespace

import numpy as np
import pytest
from scipy.integrate import trapezoid

from engine_kernels.cam import kinematics as cb
from engine_kernels.cam import loads as cam_loads
from engine_kernels.cam.contact import (
    contact_force,
    effective_modulus,
    entrainment_velocity,
    film_thickness_dowson_higginson,
    hertz_line_contact_stress,
    lubrication_coefficient,
    radius_of_curvature,
    relative_film_thickness,
)
from engine_kernels.cam.lift_laws import (
    LAW_CYCLOIDAL,
    LAW_MODIFIED_SINE,
    LAW_POLYDYNE,
    LAW_SIX_SEGMENT,
    NCOEF,
    rise_return_cam,
)
from engine_kernels.cam.multi_segment import (
    D_EVENT_HALF_WIDTH,
    D_INPUT_VALID,
    D_POSITIVE_SCALE,
    D_UNSCALED_WORKING_LIFT,
    DIAG_NAMES,
    DIAG_UNITS,
    N_DIAG,
    SHAPE_FILLET,
    SHAPE_LIN,
    SHAPE_SIN_FULL,
    SHAPE_SIN_LEFT,
    multi_segment_cam,
)

DEG = math.pi / 180.0
MM = 1e-3
CAM_SPEED = 1300.0 * 2.0 * math.pi / 60.0  # physics §9: camshaft 1300 rpm
SHAPES_12V150 = np.array(
    [SHAPE_LIN, SHAPE_SIN_FULL, SHAPE_LIN, SHAPE_SIN_LEFT, SHAPE_FILLET, SHAPE_SIN_LEFT],
    dtype=np.int64,
)
RAMP = (0.3 * MM, 20.0 * DEG, 1.2 * MM)  # assumed lash ramp inside the feasible band
THETA = np.linspace(-math.pi, math.pi, 721)


def _case(law, lift, rise_angle, base_radius=20.5 * MM, ramp=(0.0, 0.0, 0.0), speed=CAM_SPEED):
    """One row of params with the physics §9 assumptions (steel, 20 mm width, 400 N, 40 N/mm)."""
    p = np.zeros(cb.N_PARAMS)
    p[cb.P_LAW] = law
    p[cb.P_CAM_SPEED] = speed
    p[cb.P_BASE_RADIUS] = base_radius
    p[cb.P_LIFT] = lift
    p[cb.P_RISE_ANGLE] = rise_angle
    p[cb.P_RAMP_HEIGHT], p[cb.P_RAMP_WIDTH], p[cb.P_RAMP_VELOCITY] = ramp
    seg = slice(cb.P_SEG_WIDTH0, cb.P_SEG_WIDTH0 + 6)
    p[seg] = np.array([4.5, 11.0, 4.5, 5.0, 22.0, 23.0]) * DEG
    p[cb.P_SEG_ACCEL0 : cb.P_SEG_ACCEL0 + 6] = np.array([55, 55, 0, -12.5, -22.5, -24.5]) * MM
    p[cb.P_SEG_AMP0 : cb.P_SEG_AMP0 + 6] = np.array([0, 12.5, 0, 7.5, 0, 5.5]) * MM
    p[cb.P_CAM_WIDTH] = 20.0 * MM
    p[cb.P_E1] = p[cb.P_E2] = 210e9
    p[cb.P_NU1] = p[cb.P_NU2] = 0.3
    p[cb.P_SPRING_PRELOAD] = 400.0
    p[cb.P_SPRING_RATE] = 40e3
    p[cb.P_EQUIVALENT_MASS] = 0.3
    p[cb.P_VISCOSITY] = 0.01
    p[cb.P_PRESSURE_VISCOSITY] = 2e-8
    p[cb.P_NOSE_WINDOW] = 30.0 * DEG
    p[cb.P_MIN_RADIUS_LIMIT] = 3.0 * MM
    p[cb.P_STRESS_LIMIT] = 600e6
    p[cb.P_SPRING_MARGIN_LIMIT] = 1.2
    return p


def _cases():
    coeffs = np.zeros((6, NCOEF))
    coeffs[2, 4:8] = [35.0, -84.0, 70.0, -20.0]  # 4-5-6-7 polynomial as polydyne
    params = np.array(
        [
            _case(LAW_CYCLOIDAL, 10.0 * MM, 70.0 * DEG),
            _case(LAW_MODIFIED_SINE, 8.0 * MM, 60.0 * DEG),
            _case(LAW_POLYDYNE, 9.0 * MM, 65.0 * DEG),
            _case(LAW_SIX_SEGMENT, 0.0, 70.0 * DEG),
            _case(LAW_SIX_SEGMENT, 10.8 * MM, 70.0 * DEG, ramp=RAMP),
            # cusped: tiny base circle, slow so the contact force stays positive
            _case(LAW_CYCLOIDAL, 10.0 * MM, 0.5, base_radius=0.5 * MM, speed=10.0),
        ]
    )
    shapes = np.tile(SHAPES_12V150, (params.shape[0], 1))
    return params, shapes, coeffs


def _run_all(params, shapes, coeffs, theta, store=True):
    n, m = params.shape[0], theta.size
    curves = np.empty((n, 4, m))
    diag = np.empty((n, N_DIAG))
    cb.cam_kinematics_batch(params, shapes, coeffs, theta, curves, diag)
    kin = np.empty((n, cb.N_KIN))
    cb.cam_kinematic_responses_batch(params, theta, curves, kin)
    geo = np.empty((n, cam_loads.N_GEO))
    geo_curves = np.empty((n, cam_loads.N_GEO_CURVES, m if store else 0))
    cam_loads.cam_geometry_batch(params, theta, curves, geo, geo_curves)
    load = np.empty((n, cam_loads.N_LOAD))
    load_curves = np.empty((n, cam_loads.N_LOAD_CURVES, m if store else 0))
    cam_loads.cam_loads_batch(params, theta, curves, load, load_curves)
    return curves, diag, kin, geo, geo_curves, load, load_curves


@pytest.fixture(scope="module")
def results():
    params, shapes, coeffs = _cases()
    names = ("curves", "diag", "kin", "geo", "geo_curves", "load", "load_curves")
    outputs = dict(zip(names, _run_all(params, shapes, coeffs, THETA), strict=True))
    return SimpleNamespace(params=params, shapes=shapes, coeffs=coeffs, **outputs)


def test_name_tuples_match_column_counts():
    assert len(cb.PARAM_NAMES) == len(cb.PARAM_UNITS) == cb.N_PARAMS
    assert len(DIAG_NAMES) == len(DIAG_UNITS) == N_DIAG
    assert len(cb.KINEMATIC_NAMES) == len(cb.KINEMATIC_UNITS) == cb.N_KIN
    assert len(cam_loads.GEOMETRY_NAMES) == len(cam_loads.GEOMETRY_UNITS) == cam_loads.N_GEO
    assert len(cam_loads.LOAD_NAMES) == len(cam_loads.LOAD_UNITS) == cam_loads.N_LOAD
    assert len(cam_loads.GEOMETRY_CURVE_NAMES) == cam_loads.N_GEO_CURVES
    assert len(cam_loads.LOAD_CURVE_NAMES) == cam_loads.N_LOAD_CURVES
    assert cb.PARAM_NAMES[cb.P_SEG_AMP0 + 5] == "seg_amp5"
    assert cb.PARAM_NAMES[cb.P_SPRING_MARGIN_LIMIT] == "spring_margin_limit"


def test_kinematics_match_the_scalar_kernels(results):
    params, shapes, coeffs = results.params, results.shapes, results.coeffs
    curves, diag = results.curves, results.diag
    for i in range(params.shape[0]):
        p = params[i]
        expected = np.empty((4, THETA.size))
        if p[cb.P_LAW] == LAW_SIX_SEGMENT:
            expected_diag = np.empty(N_DIAG)
            multi_segment_cam(
                THETA,
                p[cb.P_RISE_ANGLE],
                p[cb.P_SEG_WIDTH0 : cb.P_SEG_WIDTH0 + 6].copy(),
                shapes[i].copy(),
                p[cb.P_SEG_ACCEL0 : cb.P_SEG_ACCEL0 + 6].copy(),
                p[cb.P_SEG_AMP0 : cb.P_SEG_AMP0 + 6].copy(),
                p[cb.P_RAMP_HEIGHT],
                p[cb.P_RAMP_WIDTH],
                p[cb.P_RAMP_VELOCITY],
                p[cb.P_LIFT],
                expected,
                expected_diag,
            )
            np.testing.assert_array_equal(diag[i], expected_diag)
        else:
            rise_return_cam(
                int(p[cb.P_LAW]),
                p[cb.P_LIFT],
                p[cb.P_RISE_ANGLE],
                coeffs[i].copy(),
                THETA,
                expected,
            )
            # Rise laws: trivially closed, unscaled, monotone, feasible; half-width β.
            assert diag[i, D_UNSCALED_WORKING_LIFT] == p[cb.P_LIFT]
            assert diag[i, D_EVENT_HALF_WIDTH] == p[cb.P_RISE_ANGLE]
            assert diag[i, D_INPUT_VALID] == 1.0
        np.testing.assert_array_equal(curves[i], expected)


def test_kinematic_responses_match_numpy_reductions(results):
    params, curves, diag, kin = results.params, results.curves, results.diag, results.kin
    for i in range(params.shape[0]):
        h, h1, h2, h3 = curves[i]
        event = diag[i, D_EVENT_HALF_WIDTH]
        six_segment = params[i, cb.P_LAW] == LAW_SIX_SEGMENT
        working = event - (params[i, cb.P_RAMP_WIDTH] if six_segment else 0.0)
        # The test ramp is feasible, so the lift at the ramp end is the given height.
        ramp_height = params[i, cb.P_RAMP_HEIGHT] if six_segment else 0.0
        inside = np.abs(THETA) <= working
        speed2 = params[i, cb.P_CAM_SPEED] ** 2
        expected = {
            "max_lift": h.max(),
            "max_velocity": np.abs(h1).max(),
            "max_acceleration": h2.max(),
            "min_acceleration": h2.min(),
            "max_jerk": np.abs(h3[inside]).max(),
            "fullness": trapezoid(h, THETA) / (h.max() * 2.0 * event),
            "max_acceleration_time": speed2 * np.abs(h2).max(),
            "min_acceleration_time": speed2 * h2.min(),
            "working_fullness": trapezoid(h[inside] - ramp_height, THETA[inside])
            / ((h.max() - ramp_height) * 2.0 * working),
        }
        for name, value in expected.items():
            assert kin[i, cb.KINEMATIC_NAMES.index(name)] == pytest.approx(value, rel=1e-12)


def test_12v150_max_jerk_is_the_segment_1_slope_and_ramp_jerk_is_excluded(results):
    diag, kin = results.diag, results.kin
    # Segment 1 is a straight line 0 -> 55 mm/rad² over 4.5 deg (physics §9), scaled by sp; its
    # slope is the largest jerk of the working part.
    unscaled = kin[3, cb.K_MAX_JERK]
    assert unscaled == pytest.approx(55.0 * MM / (4.5 * DEG), rel=1e-12)
    assert kin[4, cb.K_MAX_JERK] == pytest.approx(unscaled * diag[4, D_POSITIVE_SCALE], rel=1e-12)
    # physics §2 criterion: jerk < 1000 mm/rad³; fullness slightly above 0.55.
    assert unscaled < 1.0
    assert 0.55 < kin[3, cb.K_FULLNESS] < 0.56
    # Without a ramp the two fullness columns measure the same area (up to the grid interval
    # cut at ±W, where h ~ 1e-9 m).
    assert kin[3, cb.K_WORKING_FULLNESS] == pytest.approx(kin[3, cb.K_FULLNESS], rel=1e-6)


def _geometry_reference(p, h, h2):
    r0 = p[cb.P_BASE_RADIUS]
    speed = p[cb.P_CAM_SPEED]
    rho = np.array([radius_of_curvature(r0, a, b) for a, b in zip(h, h2, strict=True)])
    lub = np.array([lubrication_coefficient(r0, a, b) for a, b in zip(h, h2, strict=True)])
    ue = np.array([entrainment_velocity(speed, r0, a, b) for a, b in zip(h, h2, strict=True)])
    film = np.array([relative_film_thickness(x) for x in lub])
    return rho, lub, ue, film


def test_geometry_matches_a_python_loop_over_scalar_kernels(results):
    params, curves, geo, geo_curves = (
        results.params,
        results.curves,
        results.geo,
        results.geo_curves,
    )
    for i in range(params.shape[0]):
        p = params[i]
        rho, lub, ue, film = _geometry_reference(p, curves[i, 0], curves[i, 2])
        window = np.abs(THETA) <= p[cb.P_NOSE_WINDOW]
        np.testing.assert_array_equal(geo_curves[i], np.stack([rho, lub, ue, film]))
        expected = [
            rho.min(),
            rho.min() - p[cb.P_MIN_RADIUS_LIMIT],
            float(rho.min() > p[cb.P_MIN_RADIUS_LIMIT]),
            lub[window].max(),
            lub[window].min(),
            film[window].min(),
            np.abs(ue).max(),
        ]
        np.testing.assert_array_equal(geo[i], expected)


def test_loads_match_a_python_loop_over_scalar_kernels(results):
    params, curves, load, load_curves = (
        results.params,
        results.curves,
        results.load,
        results.load_curves,
    )
    for i in range(params.shape[0]):
        p = params[i]
        h, h2 = curves[i, 0], curves[i, 2]
        rho, _, ue, _ = _geometry_reference(p, h, h2)
        modulus = effective_modulus(p[cb.P_E1], p[cb.P_NU1], p[cb.P_E2], p[cb.P_NU2])
        args = (p[cb.P_SPRING_PRELOAD], p[cb.P_SPRING_RATE], p[cb.P_EQUIVALENT_MASS])
        force = np.array(
            [contact_force(*args, p[cb.P_CAM_SPEED], a, b) for a, b in zip(h, h2, strict=True)]
        )
        width = p[cb.P_CAM_WIDTH]
        stress = np.array(
            [
                hertz_line_contact_stress(f, modulus, width, r)
                for f, r in zip(force, rho, strict=True)
            ]
        )
        film = np.array(
            [
                film_thickness_dowson_higginson(
                    r, u, f / width, p[cb.P_VISCOSITY], p[cb.P_PRESSURE_VISCOSITY], modulus
                )
                for r, u, f in zip(rho, ue, force, strict=True)
            ]
        )
        np.testing.assert_array_equal(load_curves[i], np.stack([force, stress, film]))
        # Spring margin by its definition (physics §2) over the decelerating region.
        neg = h2 < 0.0
        inertia = p[cb.P_EQUIVALENT_MASS] * p[cb.P_CAM_SPEED] ** 2
        margin = np.min((args[0] + args[1] * h[neg]) / (inertia * -h2[neg]))
        window = np.abs(THETA) <= p[cb.P_NOSE_WINDOW]
        expected = [
            force.max(),
            force.min(),
            stress.max(),
            p[cb.P_STRESS_LIMIT] - stress.max(),
            float(stress.max() <= p[cb.P_STRESS_LIMIT]),
            margin,
            float(margin > p[cb.P_SPRING_MARGIN_LIMIT]),
            film[window].min(),
        ]
        np.testing.assert_allclose(load[i], expected, rtol=1e-13)


def test_cusped_cam_gives_numbers_and_failed_flags(results):
    diag, kin, geo, load = results.diag, results.kin, results.geo, results.load
    i = 5
    # Closed form of the cycloidal cam: rho = r0 + H f + H f2/β² reaches
    # r0 + H (3/4 + 1/(2π)) - 2π H/β² at x = 3/4, far below zero.
    assert geo[i, cam_loads.G_MIN_RADIUS] < 0.0
    assert geo[i, cam_loads.G_RADIUS_OK] == 0.0
    assert load[i, cam_loads.L_MAX_STRESS] == math.inf
    assert load[i, cam_loads.L_STRESS_OK] == 0.0
    assert load[i, cam_loads.L_MIN_FORCE] > 0.0
    for table in (diag, kin, geo, load):
        assert not np.isnan(table[i]).any()


def test_a_cam_concave_only_where_the_tappet_lifts_off_still_fails_the_stress_check():
    """Cycloidal rise, 10 mm in 0.5 rad on a 0.5 mm base circle at 3000 rad/s. Closed form
    (x = θ/β): h = H(x − sin 2πx / 2π), h'' = (2πH/β²) sin 2πx, ρ = r0 + h + h'' and the
    contact force F = P + k h + m ω² h''. Wherever ρ ≤ 0 here F ≤ 0 too, so no loaded point
    is concave: the stress used to be finite with stress_ok = 1 (an audit found 16 of 114
    random cams that were not convex reported so). A flat tappet cannot follow such a cam
    ([C1]): infinite stress, stress_ok 0."""
    lift, beta, r0, speed = 10.0 * MM, 0.5, 0.5 * MM, 3000.0
    params = np.array([_case(LAW_CYCLOIDAL, lift, beta, base_radius=r0, speed=speed)])
    x = np.linspace(0.0, 1.0, 100_001)
    h = lift * (x - np.sin(2 * np.pi * x) / (2 * np.pi))
    h2 = 2 * np.pi * lift / beta**2 * np.sin(2 * np.pi * x)
    rho = r0 + h + h2
    force = 400.0 + 40e3 * h + 0.3 * speed**2 * h2
    assert rho.min() < 0.0  # the case is what it says
    assert force[rho <= 0.0].max() <= 0.0
    shapes = SHAPES_12V150[None, :].copy()
    _, _, _, geo, _, load, _ = _run_all(params, shapes, np.zeros((6, NCOEF)), THETA, store=False)
    assert geo[0, cam_loads.G_MIN_RADIUS] < 0.0
    assert load[0, cam_loads.L_MAX_STRESS] == math.inf
    assert load[0, cam_loads.L_STRESS_MARGIN] == -math.inf
    assert load[0, cam_loads.L_STRESS_OK] == 0.0


def test_unknown_law_is_flagged_not_raised():
    params = np.array([_case(42.0, 10.0 * MM, 1.0)])
    shapes = SHAPES_12V150[None, :].copy()
    curves, diag, kin, geo, _, load, _ = _run_all(
        params, shapes, np.zeros((1, NCOEF)), THETA, store=False
    )
    assert diag[0, D_INPUT_VALID] == 0.0
    assert np.isnan(curves).all()
    assert np.isnan(kin).all()
    assert np.isnan(geo).all()
    assert np.isnan(load).all()


_INTERPRETED = """
import sys
import numpy as np
from engine_kernels.cam import kinematics as cb
from engine_kernels.cam import loads as cam_loads
from engine_kernels.cam.multi_segment import N_DIAG

data = np.load(sys.argv[1])
params, shapes, coeffs, theta = data["params"], data["shapes"], data["coeffs"], data["theta"]
n, m = params.shape[0], theta.size
curves = np.empty((n, 4, m))
diag = np.empty((n, N_DIAG))
cb.cam_kinematics_batch(params, shapes, coeffs, theta, curves, diag)
kin = np.empty((n, cb.N_KIN))
cb.cam_kinematic_responses_batch(params, theta, curves, kin)
geo = np.empty((n, cam_loads.N_GEO))
cam_loads.cam_geometry_batch(params, theta, curves, geo, np.empty((n, cam_loads.N_GEO_CURVES, 0)))
load = np.empty((n, cam_loads.N_LOAD))
cam_loads.cam_loads_batch(params, theta, curves, load, np.empty((n, cam_loads.N_LOAD_CURVES, 0)))
np.savez(sys.argv[2], curves=curves, diag=diag, kin=kin, geo=geo, load=load)
"""


def test_interpreted_and_compiled_drivers_agree(tmp_path):
    # The same drivers as plain Python (NUMBA_DISABLE_JIT=1) on a coarse grid.
    params, shapes, coeffs = _cases()
    theta = np.linspace(-math.pi, math.pi, 181)
    curves, diag, kin, geo, _, load, _ = _run_all(params, shapes, coeffs, theta, store=False)
    inputs, outputs = tmp_path / "in.npz", tmp_path / "out.npz"
    np.savez(inputs, params=params, shapes=shapes, coeffs=coeffs, theta=theta)
    env = {**os.environ, "NUMBA_DISABLE_JIT": "1"}
    subprocess.run(
        [sys.executable, "-c", _INTERPRETED, str(inputs), str(outputs)], check=True, env=env
    )
    plain = np.load(outputs)
    for name, compiled in (("curves", curves), ("diag", diag), ("kin", kin), ("geo", geo)):
        np.testing.assert_allclose(plain[name], compiled, rtol=1e-10, atol=1e-15, err_msg=name)
    np.testing.assert_allclose(plain["load"], load, rtol=1e-10, err_msg="load")
