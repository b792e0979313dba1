"""Cam kinematics batch drivers and the parameter columns of the `cam` scene (physics §2, §8).

Each case is a row of ``params[n, N_PARAMS]`` (float64, SI, columns P_*); six-segment shapes are
rows of ``shapes[n, 6]`` (int64) and polydyne coefficients rows of ``coeffs[n, NCOEF]``. The
drivers are separate so a study computes only what its responses need:

1. ``cam_kinematics_batch``            curves h, h', h'', h''' and profile diagnostics;
2. ``cam_kinematic_responses_batch``   lift, face width, acceleration, jerk, fullness;
3. ``cam_geometry_batch``              curvature, lubrication coefficient, entrainment;
4. ``cam_loads_batch``                 contact force, Hertz stress, spring margin, EHL film.

Drivers 1 and 2 are in this module, 3 and 4 (and their G_*, L_* columns) in
:mod:`engine_kernels.cam.loads`; one design case per ``prange`` iteration. Output columns are
named by the K_*, G_*, L_* constants and the *_NAMES / *_UNITS tuples (in
column order). Design criteria come out as margins and 1.0/0.0 flags: a concave or cusped cam
gives a negative minimum radius, infinite stress and flags 0 — numbers, never an exception.
"""

from __future__ import annotations

import math

import numpy as np

from engine_kernels._jit import batch, jit, prange
from engine_kernels.cam.contact import fullness_coefficient
from engine_kernels.cam.lift_laws import LAW_SIX_SEGMENT, N_RISE_LAWS, rise_return_cam
from engine_kernels.cam.multi_segment import (
    D_CLOSURE_RESIDUAL,
    D_EVENT_HALF_WIDTH,
    D_INPUT_VALID,
    D_RAW_NOSE_VELOCITY,
    D_UNSCALED_WORKING_LIFT,
    N_DIAG,
    N_SEGMENTS,
    multi_segment_cam,
    ramp_layout,
)

P_LAW = 0
P_CAM_SPEED = 1
P_BASE_RADIUS = 2
P_LIFT = 3
P_RISE_ANGLE = 4
P_RAMP_HEIGHT = 5
P_RAMP_WIDTH = 6
P_RAMP_VELOCITY = 7
P_SEG_WIDTH0 = 8
P_SEG_ACCEL0 = P_SEG_WIDTH0 + N_SEGMENTS
P_SEG_AMP0 = P_SEG_ACCEL0 + N_SEGMENTS
P_CAM_WIDTH = P_SEG_AMP0 + N_SEGMENTS
P_E1 = P_CAM_WIDTH + 1
P_NU1 = P_CAM_WIDTH + 2
P_E2 = P_CAM_WIDTH + 3
P_NU2 = P_CAM_WIDTH + 4
P_SPRING_PRELOAD = P_CAM_WIDTH + 5
P_SPRING_RATE = P_CAM_WIDTH + 6
P_EQUIVALENT_MASS = P_CAM_WIDTH + 7
P_VISCOSITY = P_CAM_WIDTH + 8
P_PRESSURE_VISCOSITY = P_CAM_WIDTH + 9
P_NOSE_WINDOW = P_CAM_WIDTH + 10
P_MIN_RADIUS_LIMIT = P_CAM_WIDTH + 11
P_STRESS_LIMIT = P_CAM_WIDTH + 12
P_SPRING_MARGIN_LIMIT = P_CAM_WIDTH + 13
N_PARAMS = P_CAM_WIDTH + 14

_SEGMENT_PARAMS = tuple(
    f"{kind}{k}" for kind in ("seg_width", "seg_accel", "seg_amp") for k in range(N_SEGMENTS)
)
PARAM_NAMES = (
    "law",
    "cam_speed",
    "base_radius",
    "lift",
    "rise_angle",
    "ramp_height",
    "ramp_width",
    "ramp_velocity",
    *_SEGMENT_PARAMS,
    "cam_width",
    "e1",
    "nu1",
    "e2",
    "nu2",
    "spring_preload",
    "spring_rate",
    "equivalent_mass",
    "viscosity",
    "pressure_viscosity",
    "nose_window",
    "min_radius_limit",
    "stress_limit",
    "spring_margin_limit",
)
PARAM_UNITS = (
    "1",
    "rad/s",
    "m",
    "m",
    "rad",
    "m",
    "rad",
    "m/rad",
    *(("rad",) * N_SEGMENTS + ("m/rad^2",) * N_SEGMENTS + ("m/rad^2",) * N_SEGMENTS),
    "m",
    "Pa",
    "1",
    "Pa",
    "1",
    "N",
    "N/m",
    "kg",
    "Pa s",
    "1/Pa",
    "rad",
    "m",
    "Pa",
    "1",
)
"""P_LIFT: rise H of a rise law, or the target working lift of the six-segment profile (≤ 0:
unscaled). P_RISE_ANGLE: rise duration β of a rise law, or the working half-event of the
six-segment profile (≤ 0: sum of the widths). Ramp and segment columns are read only by the
six-segment profile (LAW_SIX_SEGMENT)."""

CURVE_NAMES = ("lift", "velocity", "acceleration", "jerk")
CURVE_UNITS = ("m", "m/rad", "m/rad^2", "m/rad^3")

K_MAX_LIFT = 0
K_MAX_VELOCITY = 1
K_MAX_ACCELERATION = 2
K_MIN_ACCELERATION = 3
K_MAX_JERK = 4
K_FULLNESS = 5
K_MAX_ACCELERATION_TIME = 6
K_MIN_ACCELERATION_TIME = 7
K_WORKING_FULLNESS = 8
N_KIN = 9
KINEMATIC_NAMES = (
    "max_lift",
    "max_velocity",
    "max_acceleration",
    "min_acceleration",
    "max_jerk",
    "fullness",
    "max_acceleration_time",
    "min_acceleration_time",
    "working_fullness",
)
KINEMATIC_UNITS = (
    "m",
    "m/rad",
    "m/rad^2",
    "m/rad^2",
    "m/rad^3",
    "1",
    "m/s^2",
    "m/s^2",
    "1",
)
"""max_velocity = max|h'| is the required face half-width; max_jerk is over the working part
only (the ramp's acceleration steps have infinite jerk, physics §2); max_acceleration_time is the
peak |acceleration| ω² max|h''| in m/s², min_acceleration_time the signed ω² min h''.
fullness follows physics §2 over the whole event (ramps included); working_fullness is the same
ratio for the lift above the ramp over the working part only, ∫(h - Hr) dθ over |θ| <= W
divided by (h_max - Hr)·2W — the fullness of the valve opening once the lash is taken up."""


@jit
def half_widths(params, i):
    """Working half-event and event half-width incl. the ramp of case ``i`` [rad].

    For the six-segment profile: P_RISE_ANGLE (or the sum of the widths if that is <= 0) and
    that plus the ramp width; for every other law code both are P_RISE_ANGLE (so curves made
    elsewhere, e.g. from a measured table, put their half-event there)."""
    if int(params[i, P_LAW]) != LAW_SIX_SEGMENT:
        return params[i, P_RISE_ANGLE], params[i, P_RISE_ANGLE]
    working = params[i, P_RISE_ANGLE]
    if working <= 0.0:
        working = 0.0
        for k in range(N_SEGMENTS):
            working += params[i, P_SEG_WIDTH0 + k]
    return working, working + max(params[i, P_RAMP_WIDTH], 0.0)


@jit
def nose_index(theta):
    """Grid index closest to the nose (used when the nose window holds no grid point)."""
    best = 0
    for j in range(theta.shape[0]):
        if abs(theta[j]) < abs(theta[best]):
            best = j
    return best


@jit
def invalid_case(curves, i):
    """True when case ``i`` has NaN curves (input flagged invalid by the kinematics)."""
    for c in range(curves.shape[1]):
        for j in range(curves.shape[2]):
            if math.isnan(curves[i, c, j]):
                return True
    return False


@jit
def cam_kinematics_case(params, shapes, coeffs, theta, curves_out, diag_out):
    """Lift curves and profile diagnostics of one case (a row of :func:`cam_kinematics_batch`).

    params    : array  (N_PARAMS,) case parameters, SI.
    shapes    : array  (6,) int64 six-segment shape codes.
    coeffs    : array  (NCOEF,) polydyne coefficients [-].
    theta     : array  (m,) cam angles from the nose [rad].
    curves_out: array  (4, m) output h [m], h' [m/rad], h'' [m/rad²], h''' [m/rad³].
    diag_out  : array  (N_DIAG,) output, as in :func:`cam_kinematics_batch`.
    """
    law = int(params[P_LAW])
    if law == LAW_SIX_SEGMENT:
        widths = params[P_SEG_WIDTH0 : P_SEG_WIDTH0 + N_SEGMENTS].copy()
        accels = params[P_SEG_ACCEL0 : P_SEG_ACCEL0 + N_SEGMENTS].copy()
        amps = params[P_SEG_AMP0 : P_SEG_AMP0 + N_SEGMENTS].copy()
        multi_segment_cam(
            theta,
            params[P_RISE_ANGLE],
            widths,
            shapes,
            accels,
            amps,
            params[P_RAMP_HEIGHT],
            params[P_RAMP_WIDTH],
            params[P_RAMP_VELOCITY],
            params[P_LIFT],
            curves_out,
            diag_out,
        )
    elif 0 <= law < N_RISE_LAWS and params[P_RISE_ANGLE] > 0.0:
        rise_return_cam(law, params[P_LIFT], params[P_RISE_ANGLE], coeffs, theta, curves_out)
        for c in range(N_DIAG):
            diag_out[c] = 1.0
        diag_out[D_CLOSURE_RESIDUAL] = 0.0
        diag_out[D_RAW_NOSE_VELOCITY] = 0.0
        diag_out[D_UNSCALED_WORKING_LIFT] = params[P_LIFT]
        diag_out[D_EVENT_HALF_WIDTH] = params[P_RISE_ANGLE]
    else:
        curves_out[:, :] = np.nan
        diag_out[:] = np.nan
        diag_out[D_INPUT_VALID] = 0.0


@batch
def cam_kinematics_batch(params, shapes, coeffs, theta, curves_out, diag_out):
    """Lift curves and profile diagnostics for every case (physics §2).

    params    : array  (n, N_PARAMS) case parameters, SI (see PARAM_NAMES/PARAM_UNITS).
    shapes    : array  (n, 6) int64 six-segment shape codes (SHAPE_* of ``multi_segment``).
    coeffs    : array  (n, NCOEF) polydyne coefficients [-].
    theta     : array  (m,) cam angles from the nose [rad].
    curves_out: array  (n, 4, m) output h [m], h' [m/rad], h'' [m/rad²], h''' [m/rad³].
    diag_out  : array  (n, N_DIAG) output, ``multi_segment.DIAG_NAMES``; for rise laws closure
                       residual and raw nose velocity 0, scales 1, flags 1, unscaled working
                       lift H and event half-width β.

    An unknown law code or β ≤ 0 gives NaN curves with input_valid = 0.
    """
    for i in prange(params.shape[0]):
        cam_kinematics_case(params[i], shapes[i], coeffs[i], theta, curves_out[i], diag_out[i])


@batch
def min_radius_of_curvature_batch(params, shapes, coeffs, theta, out):
    """Smallest radius of curvature ρ = r0 + h + h'' on the grid ``theta`` per case [C1]
    (flat-faced tappet), without keeping the curves: O(n) memory whatever the grid.

    params: array  (n, N_PARAMS) case parameters, SI (the base radius r0 among them).
    shapes: array  (n, 6) int64 six-segment shape codes.
    coeffs: array  (n, NCOEF) polydyne coefficients [-].
    theta : array  (m,) cam angles from the nose [rad].
    out   : array  (n,) output min ρ [m]; NaN where a curve value is NaN (invalid input).
    """
    for i in prange(params.shape[0]):
        curves = np.empty((4, theta.shape[0]))
        diag = np.empty(N_DIAG)
        cam_kinematics_case(params[i], shapes[i], coeffs[i], theta, curves, diag)
        smallest = math.inf
        for j in range(theta.shape[0]):
            rho = params[i, P_BASE_RADIUS] + curves[0, j] + curves[2, j]
            if math.isnan(rho):
                smallest = math.nan
                break
            smallest = min(smallest, rho)
        out[i] = smallest


@batch
def cam_kinematic_responses_batch(params, theta, curves, out):
    """Scalar kinematic responses per case (physics §2).

    params: array  (n, N_PARAMS) case parameters, SI.
    theta : array  (m,) increasing cam angles covering the event [rad].
    curves: array  (n, 4, m) h, h', h'', h''' from ``cam_kinematics_batch``.
    out   : array  (n, N_KIN) output, columns KINEMATIC_NAMES (units KINEMATIC_UNITS).
    """
    for i in prange(params.shape[0]):
        if invalid_case(curves, i):
            out[i, :] = np.nan
            continue
        working, event = half_widths(params, i)
        base = 0.0
        if int(params[i, P_LAW]) == LAW_SIX_SEGMENT:
            _, base, _, _ = ramp_layout(
                params[i, P_RAMP_HEIGHT], params[i, P_RAMP_WIDTH], params[i, P_RAMP_VELOCITY]
            )
        speed2 = params[i, P_CAM_SPEED] ** 2
        working_area = 0.0
        max_lift = -math.inf
        max_velocity = 0.0
        max_accel = -math.inf
        min_accel = math.inf
        max_jerk = 0.0
        for j in range(theta.shape[0]):
            max_lift = max(max_lift, curves[i, 0, j])
            max_velocity = max(max_velocity, abs(curves[i, 1, j]))
            max_accel = max(max_accel, curves[i, 2, j])
            min_accel = min(min_accel, curves[i, 2, j])
            if abs(theta[j]) <= working:
                max_jerk = max(max_jerk, abs(curves[i, 3, j]))
                if j > 0 and abs(theta[j - 1]) <= working:
                    mean = 0.5 * (curves[i, 0, j] + curves[i, 0, j - 1]) - base
                    working_area += mean * (theta[j] - theta[j - 1])
        out[i, K_MAX_LIFT] = max_lift
        out[i, K_MAX_VELOCITY] = max_velocity
        out[i, K_MAX_ACCELERATION] = max_accel
        out[i, K_MIN_ACCELERATION] = min_accel
        out[i, K_MAX_JERK] = max_jerk
        out[i, K_FULLNESS] = fullness_coefficient(theta, curves[i, 0], 2.0 * event)
        out[i, K_MAX_ACCELERATION_TIME] = speed2 * max(max_accel, -min_accel)
        out[i, K_MIN_ACCELERATION_TIME] = speed2 * min_accel
        rise = max_lift - base
        valid = rise > 0.0 and working > 0.0
        out[i, K_WORKING_FULLNESS] = working_area / (rise * 2.0 * working) if valid else 0.0
