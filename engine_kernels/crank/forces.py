"""Slider-crank forces and torque of one cylinder: the ``forces`` driver (physics §5 [F1]–[F3]).

This module holds the gas force [F1], the reciprocating inertia forces of first and second order
[F2], the rotating inertia force [F3], the rod, side, tangential and radial forces, the
single-cylinder torque curve, the output columns of the force driver and
:func:`crank_forces_batch`. It reads the parameter matrix and kinematics of
:mod:`engine_kernels.crank.kinematics`, whose module docstring states the sign conventions.
"""

from __future__ import annotations

import math

import numpy as np

from engine_kernels._jit import batch, jit, prange
from engine_kernels.crank.connecting_rod import rod_angle
from engine_kernels.crank.kinematics import (
    ANGULAR_SPEED,
    BORE,
    CRANK_RADIUS,
    CRANKCASE_PRESSURE,
    CYCLE_ANGLE,
    KINEMATICS_MODEL,
    RECIPROCATING_MASS,
    ROD_RATIO,
    ROTATING_MASS,
    piston_motion,
)

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

# --- forces ---------------------------------------------------------------------------------


@jit
def gas_force(bore, pressure, crankcase_pressure):
    """Gas force on the piston Pg = (π D²/4)(p − p0)  [F1].

    bore              : float  D [m].
    pressure          : float  Cylinder pressure p [Pa].
    crankcase_pressure: float  p0 [Pa].
    Reference: physics §5 [F1].
    """
    return 0.25 * math.pi * bore * bore * (pressure - crankcase_pressure)


@jit
def reciprocating_inertia_first_order(reciprocating_mass, crank_radius, angular_speed, crank_angle):
    """First-order reciprocating inertia force −mj r ω² cos α  [F2].

    reciprocating_mass: float  mj [kg].
    crank_radius      : float  r [m].
    angular_speed     : float  ω [rad/s].
    crank_angle       : float  α from TDC [rad].
    Reference: physics §5 [F2].
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
    Reference: physics §5 [F2].
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
    Reference: physics §5 [F3].
    """
    return -rotating_mass * crank_radius * angular_speed**2


@jit
def rod_force(piston_force, rod_angle_):
    """Force along the connecting rod S = P/cos β.

    piston_force: float  P = Pg + Pj [N].
    rod_angle_  : float  β [rad].
    Reference: physics §5.
    """
    return piston_force / math.cos(rod_angle_)


@jit
def side_force(piston_force, rod_angle_):
    """Piston side (normal) force on the liner N = P tan β.

    piston_force: float  P [N].
    rod_angle_  : float  β [rad].
    Reference: physics §5.
    """
    return piston_force * math.tan(rod_angle_)


@jit
def tangential_force(piston_force, crank_angle, rod_angle_):
    """Tangential crankpin force T = P sin(α + β)/cos β (positive driving).

    piston_force: float  P [N].
    crank_angle : float  α [rad].
    rod_angle_  : float  β [rad].
    Reference: physics §5.
    """
    return piston_force * math.sin(crank_angle + rod_angle_) / math.cos(rod_angle_)


@jit
def radial_force(piston_force, crank_angle, rod_angle_):
    """Radial crankpin force Z = P cos(α + β)/cos β (positive toward the crank centre).

    piston_force: float  P [N].
    crank_angle : float  α [rad].
    rod_angle_  : float  β [rad].
    Reference: physics §5.
    """
    return piston_force * math.cos(crank_angle + rod_angle_) / math.cos(rod_angle_)


@jit
def piston_force(model, row, pressure, crank_angle):
    """Total piston force P = Pg + Pj for one parameter row at one crank angle  [F1], [F2].

    model      : int         MODEL_EXACT (Pj = −mj ẍ exact) or MODEL_TWO_TERM (first + second
                             order only).
    row        : float[:]    One row of ``params`` (columns of :mod:`engine_kernels.crank.kinematics`).
    pressure   : float       Cylinder pressure p [Pa].
    crank_angle: float       α [rad].
    Returns (Pg [N], Pj [N]). Reference: physics §5.
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
    Reference: physics §5 (M = T r).
    """
    m = pressure.shape[0]
    model = int(row[KINEMATICS_MODEL])
    r = row[CRANK_RADIUS]
    lam = row[ROD_RATIO]
    for j in range(m):
        alpha = CYCLE_ANGLE * j / m
        pg, pj = piston_force(model, row, pressure[j], alpha)
        torque_out[j] = tangential_force(pg + pj, alpha, rod_angle(lam, alpha)) * r


# --- batch driver ---------------------------------------------------------------------------


@batch
def crank_forces_batch(params, pressure, out, curves_out):
    """Single-cylinder forces and torque over the four-stroke cycle  [F1]–[F3].

    params    : float[n, N_PARAMS]   Case parameters (columns of :mod:`engine_kernels.crank.kinematics`).
    pressure  : float[n_p, m]        Cylinder pressure [Pa] on α_j = CYCLE_ANGLE·j/m; n_p = n
                                     (one curve per case) or 1 (shared by every case).
    out       : float[n, N_FORCE_OUT]  Scalars, columns FORCE_* (names FORCE_OUTPUTS); the
                                     side force is the largest |N|.
    curves_out: float[n, N_FORCE_CURVES, m], or last dimension 0 to skip. Curves FC_*.
    Reference: physics §5.
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
