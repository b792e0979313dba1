"""Slider-crank kinematics: the parameter matrix and piston and rod motion (physics §5).

This module holds what every ``crank`` kernel shares — the cycle angle, the kinematics model
codes and the columns of the parameter matrix — plus piston motion under the chosen model, its
extremes, and the kinematics batch driver. The piston formulas (exact [K1] and two-term
[K2]–[K4]) are in :mod:`engine_kernels.crank.piston`, the rod angle and its rates in
:mod:`engine_kernels.crank.connecting_rod`. Forces and torque of one cylinder live in
:mod:`engine_kernels.crank.forces`; multi-cylinder layouts in
:mod:`engine_kernels.crank.multicylinder`.

Conventions
-----------
* Crank angle α [rad] is measured on the crankshaft from the cylinder's TDC, in the direction
  of rotation. The four-stroke cycle spans ``CYCLE_ANGLE`` = 4π (0–720°): gas-exchange TDC at
  α = 0, firing TDC at α = 2π (the convention of :mod:`engine_kernels.crank.combustion`).
* Curves live on the uniform periodic grid α_j = CYCLE_ANGLE·j/m, j = 0…m−1, so cycle means and
  harmonic orders are plain sums over the grid.
* Piston displacement x is measured from TDC toward the crank; a piston force P is positive when
  it pushes the piston toward the crank; the tangential force T and torque M = T·r are positive
  in the direction of rotation; the radial force Z is positive toward the crank centre.

Batch drivers (one case per ``prange`` iteration, each writing its own output row) share one
parameter matrix ``params[n, N_PARAMS]`` with the columns named below, so a study fills it once
and runs only the drivers its responses need:

* :func:`crank_kinematics_batch` (this module) — piston and rod kinematics, approximation
  errors;
* :func:`engine_kernels.crank.forces.crank_forces_batch` — gas, inertia, rod, side, tangential,
  radial forces and torque of one cylinder from a pressure curve;
* :func:`engine_kernels.crank.multicylinder.crank_multicylinder_batch` — summed torque of a layout, its
  harmonic orders and the free first- and second-order reciprocating forces.
"""

from __future__ import annotations

import math

from engine_kernels._jit import batch, jit, prange
from engine_kernels.crank.connecting_rod import (
    rod_angle,
    rod_angle_max,
    rod_angular_acceleration,
    rod_angular_acceleration_max,
    rod_angular_velocity,
    rod_angular_velocity_max,
)
from engine_kernels.crank.piston import (
    piston_acceleration_exact,
    piston_acceleration_two_term,
    piston_displacement_exact,
    piston_displacement_two_term,
    piston_velocity_exact,
    piston_velocity_two_term,
)

CYCLE_ANGLE = 4.0 * math.pi
"""Crank angle of one four-stroke cycle [rad] (720°)."""

MODEL_EXACT = 0
"""Kinematics model code: exact slider-crank relations [K1]."""
MODEL_TWO_TERM = 1
"""Kinematics model code: two-term binomial approximation [K2]–[K4]."""

BISECTION_STEPS = 64
"""Bisection steps locating the crank angle of maximum piston velocity (a = 0)."""
GOLDEN_STEPS = 64
"""Golden-section steps locating the minimum piston acceleration."""
INV_GOLDEN = 0.5 * (math.sqrt(5.0) - 1.0)

# Columns of params[n, N_PARAMS] (SI units).
CRANK_RADIUS = 0  # r [m]
ROD_RATIO = 1  # λ = r/l [-]
ANGULAR_SPEED = 2  # ω [rad/s]
BORE = 3  # D [m]
RECIPROCATING_MASS = 4  # mj [kg], piston group + rod small-end share
ROTATING_MASS = 5  # mr [kg], crank + rod big-end share
CRANKCASE_PRESSURE = 6  # p0 [Pa]
KINEMATICS_MODEL = 7  # MODEL_EXACT or MODEL_TWO_TERM
CYLINDERS = 8  # z [-], used by the multi-cylinder driver only
N_PARAMS = 9
PARAM_NAMES = (
    "crank_radius",
    "rod_ratio",
    "angular_speed",
    "bore",
    "reciprocating_mass",
    "rotating_mass",
    "crankcase_pressure",
    "kinematics_model",
    "cylinders",
)

# Columns of the kinematics output out[n, N_KINEMATICS_OUT].
KIN_MEAN_PISTON_SPEED = 0
KIN_MAX_PISTON_VELOCITY = 1
KIN_CRANK_ANGLE_MAX_VELOCITY = 2
KIN_ACCELERATION_TDC = 3
KIN_MIN_PISTON_ACCELERATION = 4
KIN_MAX_ROD_ANGLE = 5
KIN_MAX_ROD_ANGULAR_VELOCITY = 6
KIN_MAX_ROD_ANGULAR_ACCELERATION = 7
KIN_APPROX_ERROR_DISPLACEMENT = 8
KIN_APPROX_ERROR_VELOCITY = 9
KIN_APPROX_ERROR_ACCELERATION = 10
N_KINEMATICS_OUT = 11
KINEMATICS_OUTPUTS = (
    "mean_piston_speed",
    "max_piston_velocity",
    "crank_angle_max_velocity",
    "piston_acceleration_tdc",
    "min_piston_acceleration",
    "max_rod_angle",
    "max_rod_angular_velocity",
    "max_rod_angular_acceleration",
    "approx_error_displacement",
    "approx_error_velocity",
    "approx_error_acceleration",
)
KINEMATICS_OUTPUT_UNITS = (
    "m/s",
    "m/s",
    "rad",
    "m/s^2",
    "m/s^2",
    "rad",
    "rad/s",
    "rad/s^2",
    "m",
    "m/s",
    "m/s^2",
)

# Curves of the kinematics driver, curves_out[n, N_KINEMATICS_CURVES, m].
KC_DISPLACEMENT = 0
KC_VELOCITY = 1
KC_ACCELERATION = 2
KC_ROD_ANGLE = 3
KC_ROD_ANGULAR_VELOCITY = 4
KC_ROD_ANGULAR_ACCELERATION = 5
N_KINEMATICS_CURVES = 6
KINEMATICS_CURVES = (
    "piston_displacement",
    "piston_velocity",
    "piston_acceleration",
    "rod_angle",
    "rod_angular_velocity",
    "rod_angular_acceleration",
)
KINEMATICS_CURVE_UNITS = ("m", "m/s", "m/s^2", "rad", "rad/s", "rad/s^2")


@jit
def piston_motion(model, crank_radius, rod_ratio, angular_speed, crank_angle):
    """Piston displacement, velocity and acceleration (x, ẋ, ẍ) under the chosen model.

    model        : int    MODEL_EXACT [K1] or MODEL_TWO_TERM [K2]–[K4].
    crank_radius : float  r [m].
    rod_ratio    : float  λ = r/l [-].
    angular_speed: float  Crank speed ω [rad/s].
    crank_angle  : float  α from TDC [rad].
    Returns (x [m], ẋ [m/s], ẍ [m/s²]). Reference: physics §5.
    """
    if model == MODEL_TWO_TERM:
        return (
            piston_displacement_two_term(crank_radius, rod_ratio, crank_angle),
            piston_velocity_two_term(crank_radius, rod_ratio, angular_speed, crank_angle),
            piston_acceleration_two_term(crank_radius, rod_ratio, angular_speed, crank_angle),
        )
    return (
        piston_displacement_exact(crank_radius, rod_ratio, crank_angle),
        piston_velocity_exact(crank_radius, rod_ratio, angular_speed, crank_angle),
        piston_acceleration_exact(crank_radius, rod_ratio, angular_speed, crank_angle),
    )


@jit
def piston_velocity_max(model, crank_radius, rod_ratio, angular_speed):
    """Maximum piston velocity and the crank angle where it occurs (ẍ = 0 in (0, π/2]).

    Bisection on the acceleration of the chosen model; exact to machine precision, independent
    of any angle grid.

    model        : int    MODEL_EXACT or MODEL_TWO_TERM.
    crank_radius : float  r [m].
    rod_ratio    : float  λ = r/l [-], 0 ≤ λ < 1.
    angular_speed: float  Crank speed ω [rad/s], > 0.
    Returns (v_max [m/s], α [rad]). Reference: physics §5 [K1]/[K3].
    """
    lo = 0.0
    hi = 0.5 * math.pi
    for _ in range(BISECTION_STEPS):
        mid = 0.5 * (lo + hi)
        if piston_motion(model, crank_radius, rod_ratio, angular_speed, mid)[2] > 0.0:
            lo = mid
        else:
            hi = mid
    angle = 0.5 * (lo + hi)
    return piston_motion(model, crank_radius, rod_ratio, angular_speed, angle)[1], angle


@jit
def piston_acceleration_min(model, crank_radius, rod_ratio, angular_speed):
    """Minimum (most negative) piston acceleration over a revolution.

    At BDC, −rω²(1 − λ), for small λ; for larger λ the minimum splits into two symmetric points
    either side of BDC. Golden-section search over [π/2, π] (the acceleration is unimodal there;
    symmetric about π).

    model        : int    MODEL_EXACT or MODEL_TWO_TERM.
    crank_radius : float  r [m].
    rod_ratio    : float  λ = r/l [-].
    angular_speed: float  Crank speed ω [rad/s].
    Returns ẍ_min [m/s²]. Reference: physics §5 [K1]/[K4].
    """
    lo = 0.5 * math.pi
    hi = math.pi
    c = hi - INV_GOLDEN * (hi - lo)
    d = lo + INV_GOLDEN * (hi - lo)
    fc = piston_motion(model, crank_radius, rod_ratio, angular_speed, c)[2]
    fd = piston_motion(model, crank_radius, rod_ratio, angular_speed, d)[2]
    for _ in range(GOLDEN_STEPS):
        if fc < fd:
            hi = d
            d = c
            fd = fc
            c = hi - INV_GOLDEN * (hi - lo)
            fc = piston_motion(model, crank_radius, rod_ratio, angular_speed, c)[2]
        else:
            lo = c
            c = d
            fc = fd
            d = lo + INV_GOLDEN * (hi - lo)
            fd = piston_motion(model, crank_radius, rod_ratio, angular_speed, d)[2]
    inner = piston_motion(model, crank_radius, rod_ratio, angular_speed, 0.5 * (lo + hi))[2]
    at_bdc = piston_motion(model, crank_radius, rod_ratio, angular_speed, math.pi)[2]
    return min(inner, at_bdc)


@jit
def mean_piston_speed(crank_radius, angular_speed):
    """Mean piston speed cm = S n/30 = 2rω/π (S = 2r stroke, n in rpm).

    crank_radius : float  r [m].
    angular_speed: float  Crank speed ω [rad/s].
    Reference: physics §5.
    """
    return 2.0 * crank_radius * angular_speed / math.pi


# --- batch driver ---------------------------------------------------------------------------


@batch
def crank_kinematics_batch(params, n_angles, out, curves_out):
    """Piston and rod kinematics of every case  [K1]–[K4].

    params    : float[n, N_PARAMS]  Case parameters (columns of this module; uses r, λ, ω and
                                    the kinematics model).
    n_angles  : int                 Grid points m over the four-stroke cycle (0–720°).
    out       : float[n, N_KINEMATICS_OUT]  Scalars, columns KIN_* (names KINEMATICS_OUTPUTS).
    curves_out: float[n, N_KINEMATICS_CURVES, m], or any shape with last dimension 0 to skip.
                Curves KC_* under the chosen model.

    Velocity maximum and acceleration minimum are located to machine precision; the two-term
    model's errors (max |exact − two-term| of x, ẋ, ẍ) are grid maxima.
    Reference: physics §5.
    """
    store = curves_out.shape[2] > 0
    for i in prange(params.shape[0]):
        r = params[i, CRANK_RADIUS]
        lam = params[i, ROD_RATIO]
        omega = params[i, ANGULAR_SPEED]
        model = int(params[i, KINEMATICS_MODEL])
        err_x = 0.0
        err_v = 0.0
        err_a = 0.0
        for j in range(n_angles):
            alpha = CYCLE_ANGLE * j / n_angles
            xe = piston_displacement_exact(r, lam, alpha)
            ve = piston_velocity_exact(r, lam, omega, alpha)
            ae = piston_acceleration_exact(r, lam, omega, alpha)
            xa = piston_displacement_two_term(r, lam, alpha)
            va = piston_velocity_two_term(r, lam, omega, alpha)
            aa = piston_acceleration_two_term(r, lam, omega, alpha)
            err_x = max(err_x, abs(xe - xa))
            err_v = max(err_v, abs(ve - va))
            err_a = max(err_a, abs(ae - aa))
            if store:
                if model == MODEL_TWO_TERM:
                    curves_out[i, KC_DISPLACEMENT, j] = xa
                    curves_out[i, KC_VELOCITY, j] = va
                    curves_out[i, KC_ACCELERATION, j] = aa
                else:
                    curves_out[i, KC_DISPLACEMENT, j] = xe
                    curves_out[i, KC_VELOCITY, j] = ve
                    curves_out[i, KC_ACCELERATION, j] = ae
                curves_out[i, KC_ROD_ANGLE, j] = rod_angle(lam, alpha)
                curves_out[i, KC_ROD_ANGULAR_VELOCITY, j] = rod_angular_velocity(lam, omega, alpha)
                curves_out[i, KC_ROD_ANGULAR_ACCELERATION, j] = rod_angular_acceleration(
                    lam, omega, alpha
                )
        v_max, alpha_v_max = piston_velocity_max(model, r, lam, omega)
        out[i, KIN_MEAN_PISTON_SPEED] = mean_piston_speed(r, omega)
        out[i, KIN_MAX_PISTON_VELOCITY] = v_max
        out[i, KIN_CRANK_ANGLE_MAX_VELOCITY] = alpha_v_max
        out[i, KIN_ACCELERATION_TDC] = piston_motion(model, r, lam, omega, 0.0)[2]
        out[i, KIN_MIN_PISTON_ACCELERATION] = piston_acceleration_min(model, r, lam, omega)
        out[i, KIN_MAX_ROD_ANGLE] = rod_angle_max(lam)
        out[i, KIN_MAX_ROD_ANGULAR_VELOCITY] = rod_angular_velocity_max(lam, omega)
        out[i, KIN_MAX_ROD_ANGULAR_ACCELERATION] = rod_angular_acceleration_max(lam, omega)
        out[i, KIN_APPROX_ERROR_DISPLACEMENT] = err_x
        out[i, KIN_APPROX_ERROR_VELOCITY] = err_v
        out[i, KIN_APPROX_ERROR_ACCELERATION] = err_a
