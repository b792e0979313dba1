"""Slider-crank kinematics and dynamics: the ``crank`` scene (SPEC §5).

Conventions
-----------
* Crank angle α [rad] is measured on the crankshaft from the cylinder's TDC, in the direction
  of rotation. The four-stroke cycle spans ``CYCLE_ANGLE`` = 4π (0–720°): gas-exchange TDC at
  α = 0, firing TDC at α = 2π (the convention of :mod:`engine_kernels.combustion`).
* Curves live on the uniform periodic grid α_j = CYCLE_ANGLE·j/m, j = 0…m−1, so cycle means and
  harmonic orders are plain sums over the grid.
* Piston displacement x is measured from TDC toward the crank; a piston force P is positive when
  it pushes the piston toward the crank; the tangential force T and torque M = T·r are positive
  in the direction of rotation; the radial force Z is positive toward the crank centre.

Batch drivers (one case per ``prange`` iteration, each writing its own output row) share one
parameter matrix ``params[n, N_PARAMS]`` with the columns named below, so a study fills it once
and runs only the drivers its responses need:

* :func:`crank_kinematics_batch` — piston and rod kinematics, approximation errors;
* :func:`crank_forces_batch` — gas, inertia, rod, side, tangential, radial forces and torque of
  one cylinder from a pressure curve;
* :func:`crank_multicylinder_batch` — summed torque of a layout, its harmonic orders and the free
  first- and second-order reciprocating forces.
"""

from __future__ import annotations

import math

import numpy as np

from engine_kernels._jit import batch, jit, prange

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

# Columns of the single-cylinder force output out[n, N_FORCE_OUT].
FORCE_MAX_GAS_FORCE = 0
FORCE_MAX_PISTON_FORCE = 1
FORCE_MIN_PISTON_FORCE = 2
FORCE_MAX_ROD_FORCE = 3
FORCE_MIN_ROD_FORCE = 4
FORCE_MAX_SIDE_FORCE = 5
FORCE_MAX_TANGENTIAL_FORCE = 6
FORCE_MIN_TANGENTIAL_FORCE = 7
FORCE_MAX_RADIAL_FORCE = 8
FORCE_MIN_RADIAL_FORCE = 9
FORCE_MEAN_TORQUE = 10
FORCE_MAX_TORQUE = 11
FORCE_MIN_TORQUE = 12
FORCE_FIRST_ORDER_AMPLITUDE = 13
FORCE_SECOND_ORDER_AMPLITUDE = 14
FORCE_ROTATING_INERTIA = 15
N_FORCE_OUT = 16
FORCE_OUTPUTS = (
    "max_gas_force",
    "max_piston_force",
    "min_piston_force",
    "max_rod_force",
    "min_rod_force",
    "max_side_force",
    "max_tangential_force",
    "min_tangential_force",
    "max_radial_force",
    "min_radial_force",
    "mean_torque",
    "max_torque",
    "min_torque",
    "first_order_inertia_amplitude",
    "second_order_inertia_amplitude",
    "rotating_inertia_force",
)
FORCE_OUTPUT_UNITS = ("N",) * 10 + ("N m",) * 3 + ("N",) * 3

# Curves of the force driver, curves_out[n, N_FORCE_CURVES, m].
FC_GAS_FORCE = 0
FC_INERTIA_FORCE = 1
FC_PISTON_FORCE = 2
FC_ROD_FORCE = 3
FC_SIDE_FORCE = 4
FC_TANGENTIAL_FORCE = 5
FC_RADIAL_FORCE = 6
FC_TORQUE = 7
N_FORCE_CURVES = 8
FORCE_CURVES = (
    "gas_force",
    "inertia_force",
    "piston_force",
    "rod_force",
    "side_force",
    "tangential_force",
    "radial_force",
    "torque",
)
FORCE_CURVE_UNITS = ("N",) * 7 + ("N m",)

# Columns of the multi-cylinder output out[n, N_MULTI_OUT].
MULTI_MEAN_TORQUE = 0
MULTI_MAX_TORQUE = 1
MULTI_MIN_TORQUE = 2
MULTI_TORQUE_PEAK_TO_PEAK = 3
MULTI_TORQUE_NONUNIFORMITY = 4
MULTI_MEAN_POWER = 5
MULTI_FREE_FIRST_ORDER_FORCE = 6
MULTI_FREE_SECOND_ORDER_FORCE = 7
N_MULTI_OUT = 8
MULTI_OUTPUTS = (
    "mean_torque",
    "max_torque",
    "min_torque",
    "torque_peak_to_peak",
    "torque_nonuniformity",
    "mean_power",
    "free_first_order_force",
    "free_second_order_force",
)
MULTI_OUTPUT_UNITS = ("N m", "N m", "N m", "N m", "-", "W", "N", "N")


# --- kinematics -----------------------------------------------------------------------------


@jit
def rod_angle(rod_ratio, crank_angle):
    """Connecting-rod angle β from sin β = λ sin α  [K1].

    rod_ratio  : float  λ = r/l [-].
    crank_angle: float  Crank angle α from TDC [rad].
    Reference: SPEC §5 [K1].
    """
    return math.asin(rod_ratio * math.sin(crank_angle))


@jit
def piston_displacement_exact(crank_radius, rod_ratio, crank_angle):
    """Exact piston displacement from TDC x = r(1 − cos α) + l(1 − cos β)  [K1].

    Written as x = r[(1 − cos α) + λ sin²α/(1 + cos β)], which needs no division by λ and keeps
    full precision as λ → 0.

    crank_radius: float  r [m].
    rod_ratio   : float  λ = r/l [-].
    crank_angle : float  α from TDC [rad].
    Reference: SPEC §5 [K1].
    """
    s = math.sin(crank_angle)
    cos_beta = math.sqrt(1.0 - (rod_ratio * s) ** 2)
    return crank_radius * ((1.0 - math.cos(crank_angle)) + rod_ratio * s * s / (1.0 + cos_beta))


@jit
def piston_velocity_exact(crank_radius, rod_ratio, angular_speed, crank_angle):
    """Exact piston velocity ẋ = rω[sin α + (λ/2) sin 2α / cos β] = rω sin(α + β)/cos β  [K1].

    crank_radius : float  r [m].
    rod_ratio    : float  λ = r/l [-].
    angular_speed: float  Crank speed ω [rad/s].
    crank_angle  : float  α from TDC [rad].
    Reference: SPEC §5 [K1], differentiated once in time at constant ω.
    """
    s = math.sin(crank_angle)
    cos_beta = math.sqrt(1.0 - (rod_ratio * s) ** 2)
    return (
        crank_radius
        * angular_speed
        * (s + 0.5 * rod_ratio * math.sin(2.0 * crank_angle) / cos_beta)
    )


@jit
def piston_acceleration_exact(crank_radius, rod_ratio, angular_speed, crank_angle):
    """Exact piston acceleration ẍ = rω²[cos α + λ cos 2α / cos β + λ³ sin²2α/(4 cos³β)]  [K1].

    crank_radius : float  r [m].
    rod_ratio    : float  λ = r/l [-].
    angular_speed: float  Crank speed ω [rad/s].
    crank_angle  : float  α from TDC [rad].
    Reference: SPEC §5 [K1], differentiated twice in time at constant ω.
    """
    s = math.sin(crank_angle)
    cos_beta = math.sqrt(1.0 - (rod_ratio * s) ** 2)
    s2 = math.sin(2.0 * crank_angle)
    return (
        crank_radius
        * angular_speed**2
        * (
            math.cos(crank_angle)
            + rod_ratio * math.cos(2.0 * crank_angle) / cos_beta
            + rod_ratio**3 * s2 * s2 / (4.0 * cos_beta**3)
        )
    )


@jit
def piston_displacement_two_term(crank_radius, rod_ratio, crank_angle):
    """Two-term piston displacement x = r[(1 − cos α) + (λ/4)(1 − cos 2α)]  [K2].

    crank_radius: float  r [m].
    rod_ratio   : float  λ = r/l [-].
    crank_angle : float  α from TDC [rad].
    Reference: SPEC §5 [K2].
    """
    return crank_radius * (
        (1.0 - math.cos(crank_angle)) + 0.25 * rod_ratio * (1.0 - math.cos(2.0 * crank_angle))
    )


@jit
def piston_velocity_two_term(crank_radius, rod_ratio, angular_speed, crank_angle):
    """Two-term piston velocity v = rω(sin α + (λ/2) sin 2α)  [K3].

    crank_radius : float  r [m].
    rod_ratio    : float  λ = r/l [-].
    angular_speed: float  Crank speed ω [rad/s].
    crank_angle  : float  α from TDC [rad].
    Reference: SPEC §5 [K3].
    """
    return (
        crank_radius
        * angular_speed
        * (math.sin(crank_angle) + 0.5 * rod_ratio * math.sin(2.0 * crank_angle))
    )


@jit
def piston_acceleration_two_term(crank_radius, rod_ratio, angular_speed, crank_angle):
    """Two-term piston acceleration a = rω²(cos α + λ cos 2α)  [K4].

    crank_radius : float  r [m].
    rod_ratio    : float  λ = r/l [-].
    angular_speed: float  Crank speed ω [rad/s].
    crank_angle  : float  α from TDC [rad].
    Reference: SPEC §5 [K4].
    """
    return (
        crank_radius
        * angular_speed**2
        * (math.cos(crank_angle) + rod_ratio * math.cos(2.0 * crank_angle))
    )


@jit
def piston_motion(model, crank_radius, rod_ratio, angular_speed, crank_angle):
    """Piston displacement, velocity and acceleration (x, ẋ, ẍ) under the chosen model.

    model        : int    MODEL_EXACT [K1] or MODEL_TWO_TERM [K2]–[K4].
    crank_radius : float  r [m].
    rod_ratio    : float  λ = r/l [-].
    angular_speed: float  Crank speed ω [rad/s].
    crank_angle  : float  α from TDC [rad].
    Returns (x [m], ẋ [m/s], ẍ [m/s²]). Reference: SPEC §5.
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
    Returns (v_max [m/s], α [rad]). Reference: SPEC §5 [K1]/[K3].
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
    Returns ẍ_min [m/s²]. Reference: SPEC §5 [K1]/[K4].
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
def rod_angular_velocity(rod_ratio, angular_speed, crank_angle):
    """Rod angular velocity β̇ = λω cos α / cos β  [K1].

    rod_ratio    : float  λ = r/l [-].
    angular_speed: float  Crank speed ω [rad/s].
    crank_angle  : float  α from TDC [rad].
    Reference: SPEC §5.
    """
    s = math.sin(crank_angle)
    return rod_ratio * angular_speed * math.cos(crank_angle) / math.sqrt(1.0 - (rod_ratio * s) ** 2)


@jit
def rod_angular_acceleration(rod_ratio, angular_speed, crank_angle):
    """Rod angular acceleration β̈ = −λ(1 − λ²) ω² sin α / cos³β  [K1].

    rod_ratio    : float  λ = r/l [-].
    angular_speed: float  Crank speed ω [rad/s].
    crank_angle  : float  α from TDC [rad].
    Reference: SPEC §5 (exact, constant ω).
    """
    s = math.sin(crank_angle)
    cos_beta = math.sqrt(1.0 - (rod_ratio * s) ** 2)
    return -rod_ratio * (1.0 - rod_ratio**2) * angular_speed**2 * s / cos_beta**3


@jit
def rod_angle_max(rod_ratio):
    """Largest rod angle β_max = asin λ, at α = 90° (and −β_max at 270°).

    rod_ratio: float  λ = r/l [-]. Reference: SPEC §5.
    """
    return math.asin(rod_ratio)


@jit
def rod_angular_velocity_max(rod_ratio, angular_speed):
    """Largest rod angular velocity λω, at α = 0° (and −λω at 180°).

    rod_ratio    : float  λ = r/l [-].
    angular_speed: float  Crank speed ω [rad/s].
    Reference: SPEC §5.
    """
    return rod_ratio * angular_speed


@jit
def rod_angular_acceleration_max(rod_ratio, angular_speed):
    """Largest rod angular acceleration magnitude λω²/√(1 − λ²), at α = 90° and 270°.

    |β̈| = λ(1 − λ²)ω² sin α/(1 − λ² sin²α)^{3/2} grows with sin α, so it peaks at sin α = ±1.

    rod_ratio    : float  λ = r/l [-].
    angular_speed: float  Crank speed ω [rad/s].
    Reference: SPEC §5.
    """
    return rod_ratio * angular_speed**2 / math.sqrt(1.0 - rod_ratio**2)


@jit
def mean_piston_speed(crank_radius, angular_speed):
    """Mean piston speed cm = S n/30 = 2rω/π (S = 2r stroke, n in rpm).

    crank_radius : float  r [m].
    angular_speed: float  Crank speed ω [rad/s].
    Reference: SPEC §5.
    """
    return 2.0 * crank_radius * angular_speed / math.pi


# --- forces ---------------------------------------------------------------------------------


@jit
def gas_force(bore, pressure, crankcase_pressure):
    """Gas force on the piston Pg = (π D²/4)(p − p0)  [F1].

    bore              : float  D [m].
    pressure          : float  Cylinder pressure p [Pa].
    crankcase_pressure: float  p0 [Pa].
    Reference: SPEC §5 [F1].
    """
    return 0.25 * math.pi * bore * bore * (pressure - crankcase_pressure)


@jit
def reciprocating_inertia_first_order(reciprocating_mass, crank_radius, angular_speed, crank_angle):
    """First-order reciprocating inertia force −mj r ω² cos α  [F2].

    reciprocating_mass: float  mj [kg].
    crank_radius      : float  r [m].
    angular_speed     : float  ω [rad/s].
    crank_angle       : float  α from TDC [rad].
    Reference: SPEC §5 [F2].
    """
    return -reciprocating_mass * crank_radius * angular_speed**2 * math.cos(crank_angle)


@jit
def reciprocating_inertia_second_order(
    reciprocating_mass, crank_radius, rod_ratio, angular_speed, crank_angle
):
    """Second-order reciprocating inertia force −mj r ω² λ cos 2α  [F2].

    reciprocating_mass: float  mj [kg].
    crank_radius      : float  r [m].
    rod_ratio         : float  λ [-].
    angular_speed     : float  ω [rad/s].
    crank_angle       : float  α from TDC [rad].
    Reference: SPEC §5 [F2].
    """
    return (
        -reciprocating_mass
        * crank_radius
        * angular_speed**2
        * rod_ratio
        * math.cos(2.0 * crank_angle)
    )


@jit
def rotating_inertia_force(rotating_mass, crank_radius, angular_speed):
    """Rotating inertia force Pr = −mr r ω² (directed along the crank, outward)  [F3].

    rotating_mass: float  mr [kg].
    crank_radius : float  r [m].
    angular_speed: float  ω [rad/s].
    Reference: SPEC §5 [F3].
    """
    return -rotating_mass * crank_radius * angular_speed**2


@jit
def rod_force(piston_force, rod_angle_):
    """Force along the connecting rod S = P/cos β.

    piston_force: float  P = Pg + Pj [N].
    rod_angle_  : float  β [rad].
    Reference: SPEC §5.
    """
    return piston_force / math.cos(rod_angle_)


@jit
def side_force(piston_force, rod_angle_):
    """Piston side (normal) force on the liner N = P tan β.

    piston_force: float  P [N].
    rod_angle_  : float  β [rad].
    Reference: SPEC §5.
    """
    return piston_force * math.tan(rod_angle_)


@jit
def tangential_force(piston_force, crank_angle, rod_angle_):
    """Tangential crankpin force T = P sin(α + β)/cos β (positive driving).

    piston_force: float  P [N].
    crank_angle : float  α [rad].
    rod_angle_  : float  β [rad].
    Reference: SPEC §5.
    """
    return piston_force * math.sin(crank_angle + rod_angle_) / math.cos(rod_angle_)


@jit
def radial_force(piston_force, crank_angle, rod_angle_):
    """Radial crankpin force Z = P cos(α + β)/cos β (positive toward the crank centre).

    piston_force: float  P [N].
    crank_angle : float  α [rad].
    rod_angle_  : float  β [rad].
    Reference: SPEC §5.
    """
    return piston_force * math.cos(crank_angle + rod_angle_) / math.cos(rod_angle_)


@jit
def piston_force(model, row, pressure, crank_angle):
    """Total piston force P = Pg + Pj for one parameter row at one crank angle  [F1], [F2].

    model      : int         MODEL_EXACT (Pj = −mj ẍ exact) or MODEL_TWO_TERM (first + second
                             order only).
    row        : float[:]    One row of ``params`` (columns of this module).
    pressure   : float       Cylinder pressure p [Pa].
    crank_angle: float       α [rad].
    Returns (Pg [N], Pj [N]). Reference: SPEC §5.
    """
    r = row[CRANK_RADIUS]
    acc = piston_motion(model, r, row[ROD_RATIO], row[ANGULAR_SPEED], crank_angle)[2]
    pg = gas_force(row[BORE], pressure, row[CRANKCASE_PRESSURE])
    return pg, -row[RECIPROCATING_MASS] * acc


@jit
def crank_torque_curve(row, pressure, torque_out):
    """Single-cylinder torque M = T r on the cycle grid of ``pressure``.

    row       : float[:]  One row of ``params``.
    pressure  : float[:]  Cylinder pressure on α_j = CYCLE_ANGLE·j/m [Pa].
    torque_out: float[:]  Output, length m [N m].
    Reference: SPEC §5 (M = T r).
    """
    m = pressure.shape[0]
    model = int(row[KINEMATICS_MODEL])
    r = row[CRANK_RADIUS]
    lam = row[ROD_RATIO]
    for j in range(m):
        alpha = CYCLE_ANGLE * j / m
        pg, pj = piston_force(model, row, pressure[j], alpha)
        torque_out[j] = tangential_force(pg + pj, alpha, rod_angle(lam, alpha)) * r


# --- multi-cylinder layouts -----------------------------------------------------------------


@jit
def even_firing_angles(firing_order, firing_out):
    """Even firing: cylinder firing_order[k] fires at k·720°/z  (SPEC §5).

    firing_order: int[:]    Cylinder numbers (1-based) in firing order, length z.
    firing_out  : float[:]  Output, firing angle of cylinder c at index c − 1 [rad].
    """
    z = firing_order.shape[0]
    for k in range(z):
        firing_out[firing_order[k] - 1] = CYCLE_ANGLE * k / z


@jit
def v_crank_firing_angles(firing_order, bank_angle, firing_out):
    """Firing angles of a V engine with shared crankpins (two rods per throw).

    The firing order alternates banks; the leading-bank cylinders (even positions k = 0, 2, …)
    fire evenly every 1440°/z, and each following cylinder on the other bank shares a throw
    with the one before it, so it fires one bank angle γ later. Firing is even (720°/z) only
    when γ = 720°/z (a 6-throw V12 at 60°); a 90° V12 fires at alternating 90°/30° intervals.

    firing_order: int[:]    Cylinder numbers (1-based) in firing order, even length z.
    bank_angle  : float     γ between the banks [rad].
    firing_out  : float[:]  Output, firing angle of cylinder c at index c − 1 [rad].
    Reference: SPEC §5 (a 6-throw V12 fires evenly only at a 60° bank).
    """
    z = firing_order.shape[0]
    for k in range(z):
        lead = CYCLE_ANGLE * (k // 2) / (z // 2)
        firing_out[firing_order[k] - 1] = lead + bank_angle * (k % 2)


@jit
def v_axis_angles(firing_order, bank_angle, axis_out):
    """Cylinder axis angles of a V layout: −γ/2 for the leading bank, +γ/2 for the other.

    Banks alternate along the firing order (position k even → leading bank). Angles are
    measured from the vertical in the direction of rotation; a cylinder reaches TDC when its
    crank throw points along its axis.

    firing_order: int[:]    Cylinder numbers (1-based) in firing order.
    bank_angle  : float     γ [rad].
    axis_out    : float[:]  Output, axis angle of cylinder c at index c − 1 [rad].
    Reference: SPEC §5.
    """
    for k in range(firing_order.shape[0]):
        axis_out[firing_order[k] - 1] = bank_angle * ((k % 2) - 0.5)


@jit
def free_force_amplitude(a_x, a_y, b_x, b_y):
    """Largest magnitude of the rotating/oscillating vector F(t) = A cos t + B sin t.

    |F|² = |A|² cos²t + |B|² sin²t + 2 A·B sin t cos t, maximised in closed form:
    (|A|² + |B|²)/2 + √(((|A|² − |B|²)/2)² + (A·B)²).

    a_x, a_y: float  Components of A [N].
    b_x, b_y: float  Components of B [N].
    Reference: SPEC §5 (free forces of a layout).
    """
    aa = a_x * a_x + a_y * a_y
    bb = b_x * b_x + b_y * b_y
    ab = a_x * b_x + a_y * b_y
    half_diff = 0.5 * (aa - bb)
    return math.sqrt(max(0.5 * (aa + bb) + math.sqrt(half_diff * half_diff + ab * ab), 0.0))


@jit
def free_reciprocating_force(
    reciprocating_mass, crank_radius, rod_ratio, angular_speed, firing, axis, cylinders, order
):
    """Free first- or second-order reciprocating force of a layout (amplitude of the resultant).

    Cylinder i contributes −mj r ω² λ^(order−1) cos(order·(α − ψ_i)) along its axis
    e_i = (sin θ_i, cos θ_i), ψ_i its TDC crank angle (its firing angle; the 720° ambiguity drops
    out of the first and second orders). The vector sum is A cos(order·α) + B sin(order·α).

    reciprocating_mass: float     mj [kg].
    crank_radius      : float     r [m].
    rod_ratio         : float     λ [-].
    angular_speed     : float     ω [rad/s].
    firing            : float[:]  Firing angles ψ_i [rad].
    axis              : float[:]  Cylinder axis angles θ_i [rad].
    cylinders         : int       Number of cylinders used (leading entries of the arrays).
    order             : int       1 or 2.
    Returns the largest magnitude of the resultant [N]. Reference: SPEC §5 [F2].
    """
    a_x = 0.0
    a_y = 0.0
    b_x = 0.0
    b_y = 0.0
    for c in range(cylinders):
        cp = math.cos(order * firing[c])
        sp = math.sin(order * firing[c])
        ex = math.sin(axis[c])
        ey = math.cos(axis[c])
        a_x += cp * ex
        a_y += cp * ey
        b_x += sp * ex
        b_y += sp * ey
    scale = reciprocating_mass * crank_radius * angular_speed**2 * rod_ratio ** (order - 1)
    return scale * free_force_amplitude(a_x, a_y, b_x, b_y)


@jit
def periodic_interpolate(values, position):
    """Linear interpolation of a periodic grid sequence at a fractional index.

    values  : float[:]  Samples on a uniform periodic grid.
    position: float     Fractional index (any real; wrapped modulo the length).
    Reference: standard periodic linear interpolation.
    """
    m = values.shape[0]
    wrapped = position % m
    k = math.floor(wrapped)
    frac = wrapped - k
    k = k % m
    return (1.0 - frac) * values[k] + frac * values[(k + 1) % m]


@jit
def harmonic_amplitude(values, harmonic):
    """Amplitude of harmonic q of a periodic grid sequence, 2|Σ v_j e^{−2πiqj/m}|/m.

    On the four-stroke cycle grid harmonic q is engine order q/2.

    values  : float[:]  Samples on a uniform periodic grid.
    harmonic: int       q ≥ 1.
    Reference: discrete Fourier transform.
    """
    m = values.shape[0]
    re = 0.0
    im = 0.0
    for j in range(m):
        phase = 2.0 * math.pi * harmonic * j / m
        re += values[j] * math.cos(phase)
        im -= values[j] * math.sin(phase)
    return 2.0 * math.sqrt(re * re + im * im) / m


# --- batch drivers --------------------------------------------------------------------------


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
    Reference: SPEC §5.
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


@batch
def crank_forces_batch(params, pressure, out, curves_out):
    """Single-cylinder forces and torque over the four-stroke cycle  [F1]–[F3].

    params    : float[n, N_PARAMS]   Case parameters (columns of this module).
    pressure  : float[n_p, m]        Cylinder pressure [Pa] on α_j = CYCLE_ANGLE·j/m; n_p = n
                                     (one curve per case) or 1 (shared by every case).
    out       : float[n, N_FORCE_OUT]  Scalars, columns FORCE_* (names FORCE_OUTPUTS); the
                                     side force is the largest |N|.
    curves_out: float[n, N_FORCE_CURVES, m], or last dimension 0 to skip. Curves FC_*.
    Reference: SPEC §5.
    """
    m = pressure.shape[1]
    shared = pressure.shape[0] == 1
    store = curves_out.shape[2] > 0
    for i in prange(params.shape[0]):
        row = params[i]
        prow = pressure[0] if shared else pressure[i]
        model = int(row[KINEMATICS_MODEL])
        r = row[CRANK_RADIUS]
        lam = row[ROD_RATIO]
        omega = row[ANGULAR_SPEED]
        mj = row[RECIPROCATING_MASS]
        max_pg = -np.inf
        max_p = -np.inf
        min_p = np.inf
        max_s = -np.inf
        min_s = np.inf
        max_n = 0.0
        max_t = -np.inf
        min_t = np.inf
        max_z = -np.inf
        min_z = np.inf
        sum_t = 0.0
        for j in range(m):
            alpha = CYCLE_ANGLE * j / m
            pg, pj = piston_force(model, row, prow[j], alpha)
            p = pg + pj
            beta = rod_angle(lam, alpha)
            s = rod_force(p, beta)
            nf = side_force(p, beta)
            t = tangential_force(p, alpha, beta)
            z = radial_force(p, alpha, beta)
            max_pg = max(max_pg, pg)
            max_p = max(max_p, p)
            min_p = min(min_p, p)
            max_s = max(max_s, s)
            min_s = min(min_s, s)
            max_n = max(max_n, abs(nf))
            max_t = max(max_t, t)
            min_t = min(min_t, t)
            max_z = max(max_z, z)
            min_z = min(min_z, z)
            sum_t += t
            if store:
                curves_out[i, FC_GAS_FORCE, j] = pg
                curves_out[i, FC_INERTIA_FORCE, j] = pj
                curves_out[i, FC_PISTON_FORCE, j] = p
                curves_out[i, FC_ROD_FORCE, j] = s
                curves_out[i, FC_SIDE_FORCE, j] = nf
                curves_out[i, FC_TANGENTIAL_FORCE, j] = t
                curves_out[i, FC_RADIAL_FORCE, j] = z
                curves_out[i, FC_TORQUE, j] = t * r
        out[i, FORCE_MAX_GAS_FORCE] = max_pg
        out[i, FORCE_MAX_PISTON_FORCE] = max_p
        out[i, FORCE_MIN_PISTON_FORCE] = min_p
        out[i, FORCE_MAX_ROD_FORCE] = max_s
        out[i, FORCE_MIN_ROD_FORCE] = min_s
        out[i, FORCE_MAX_SIDE_FORCE] = max_n
        out[i, FORCE_MAX_TANGENTIAL_FORCE] = max_t
        out[i, FORCE_MIN_TANGENTIAL_FORCE] = min_t
        out[i, FORCE_MAX_RADIAL_FORCE] = max_z
        out[i, FORCE_MIN_RADIAL_FORCE] = min_z
        out[i, FORCE_MEAN_TORQUE] = sum_t * r / m
        out[i, FORCE_MAX_TORQUE] = max_t * r
        out[i, FORCE_MIN_TORQUE] = min_t * r
        out[i, FORCE_FIRST_ORDER_AMPLITUDE] = mj * r * omega**2
        out[i, FORCE_SECOND_ORDER_AMPLITUDE] = mj * r * omega**2 * lam
        out[i, FORCE_ROTATING_INERTIA] = -rotating_inertia_force(row[ROTATING_MASS], r, omega)


@batch
def crank_multicylinder_batch(
    params, pressure, firing_angles, axis_angles, out, harmonics_out, curves_out
):
    """Summed crankshaft torque, its harmonic orders and free forces of a layout  [F1]–[F2].

    Every cylinder has the same pressure curve; cylinder c's torque is the single-cylinder
    torque shifted by its firing angle (periodic linear interpolation, exact when the firing
    angles fall on the grid).

    params       : float[n, N_PARAMS]  Case parameters; CYLINDERS = z cylinders used.
    pressure     : float[n_p, m]       Cylinder pressure [Pa] on the cycle grid; n_p = n or 1.
    firing_angles: float[n_f, z_max]   Firing angle of each cylinder [rad] (see
                                       :func:`even_firing_angles`, :func:`v_crank_firing_angles`);
                                       n_f = n or 1.
    axis_angles  : float[n_f, z_max]   Cylinder axis angle from vertical [rad]: 0 inline,
                                       ±γ/2 for a V (:func:`v_axis_angles`).
    out          : float[n, N_MULTI_OUT]  Scalars, columns MULTI_* (names MULTI_OUTPUTS).
    harmonics_out: float[n, q_max]     Amplitude of engine orders 0.5, 1, 1.5, …, q_max/2 [N m]
                                       (q_max may be 0).
    curves_out   : float[n, 1, m], or last dimension 0 to skip. Summed torque [N m].
    Reference: SPEC §5.
    """
    m = pressure.shape[1]
    shared_p = pressure.shape[0] == 1
    shared_f = firing_angles.shape[0] == 1
    store = curves_out.shape[2] > 0
    step = CYCLE_ANGLE / m
    for i in prange(params.shape[0]):
        row = params[i]
        prow = pressure[0] if shared_p else pressure[i]
        firing = firing_angles[0] if shared_f else firing_angles[i]
        axis = axis_angles[0] if shared_f else axis_angles[i]
        z = int(row[CYLINDERS])
        single = np.empty(m)
        crank_torque_curve(row, prow, single)
        total = np.zeros(m)
        for c in range(z):
            shift = firing[c] / step
            for j in range(m):
                total[j] += periodic_interpolate(single, j - shift)
        mean = total.sum() / m
        t_max = total.max()
        t_min = total.min()
        out[i, MULTI_MEAN_TORQUE] = mean
        out[i, MULTI_MAX_TORQUE] = t_max
        out[i, MULTI_MIN_TORQUE] = t_min
        out[i, MULTI_TORQUE_PEAK_TO_PEAK] = t_max - t_min
        out[i, MULTI_TORQUE_NONUNIFORMITY] = (t_max - t_min) / mean if mean != 0.0 else np.nan
        out[i, MULTI_MEAN_POWER] = mean * row[ANGULAR_SPEED]
        for order in (1, 2):
            out[i, MULTI_FREE_FIRST_ORDER_FORCE + order - 1] = free_reciprocating_force(
                row[RECIPROCATING_MASS],
                row[CRANK_RADIUS],
                row[ROD_RATIO],
                row[ANGULAR_SPEED],
                firing,
                axis,
                z,
                order,
            )
        for q in range(harmonics_out.shape[1]):
            harmonics_out[i, q] = harmonic_amplitude(total, q + 1)
        if store:
            for j in range(m):
                curves_out[i, 0, j] = total[j]
