"""Valve-train model [V1], [V2]: forces, energy, stiffest mode, excitation (SPEC §4).

Model [V2], in time, with the valve lift y measured from the closed position where the seat
is pre-compressed by ``δ0 = Ps0/kz``::

    M ÿ = max(0, k (Y − y) + b (Ẏ − ẏ))                   drive; ≤ 0 means SEPARATION
        + max(0, kz (δ0 − y) − bz ẏ)   while y < δ0        seat; never pulls
        − ks y − Ps0 − γ ẏ

Parameter rows and the other data layouts (``P_*``, ``O_*``, ``C_*``, ``S_*``) are in
:mod:`engine_kernels.valvetrain.layout`. The excitation is a table of the theoretical valve
lift Y(θ) and its angle derivatives (rows Y [m], Y' [m/rad], Y'' [m/rad²]) read by
:func:`excitation_at`. Reference: SPEC §4 and the motorcycle OHC valve-train thesis data quoted there.
"""

from __future__ import annotations

import numpy as np

from engine_kernels._jit import jit, jit_inline
from engine_kernels.valvetrain.layout import (
    P_DRIVE_DAMPING,
    P_DRIVE_STIFFNESS,
    P_EXTERNAL_DAMPING,
    P_MASS,
    P_PRELOAD,
    P_SEAT_DAMPING,
    P_SEAT_STIFFNESS,
    P_SPEED,
    P_SPRING_RATE,
)
from engine_kernels.valvetrain.rk4 import hermite_value, oscillator_spectral_radius

# Constants of the integrator arithmetic, typed float32: exact in both precisions, so a
# float64 kernel computes the same numbers as with Python floats, while the float32 lane
# kernel (engine_kernels.valvetrain.lanes) is not promoted to float64 by a literal.
ZERO = np.float32(0.0)
HALF = np.float32(0.5)
ONE = np.float32(1.0)
TWO = np.float32(2.0)
INF = np.float32(np.inf)
NAN = np.float32(np.nan)

# Selects for loops over SIMD lanes. Numba's builtin max and min are function calls, and a
# call inside a lane loop stops it from vectorising, so these are conditional expressions
# (compiled to selects) and ruff's FURB136 is silenced on purpose.


@jit_inline
def positive_part(x):
    """``max(0, x)`` as a branch-free select (a one-sided contact force)."""
    return x if x > ZERO else ZERO  # noqa: FURB136


@jit_inline
def larger(a, b):
    """The larger of two floats as a branch-free select, for running maxima.

    The ``+ ZERO`` (not an identity for −0.0, so the compiler keeps it) stops LLVM from
    turning ``row = larger(row, x)`` into a conditional store, which vectorises into masked
    stores that are slow on AMD processors.
    """
    return (b if b > a else a) + ZERO  # noqa: FURB136


@jit_inline
def smaller(a, b):
    """The smaller of two floats as a branch-free select, for running minima (see larger)."""
    return (b if b < a else a) + ZERO  # noqa: FURB136


@jit
def equivalent_mass(valve_group_mass, spring_mass, rocker_inertia, valve_arm):
    """Equivalent mass on the valve axis ``M = m_valve + m_spring/3 + I_rocker/l_v²`` [V1].

    valve_group_mass : float  Valve, retainer, cotters, spring seat [kg].
    spring_mass      : float  Valve-spring mass [kg] (a third moves with the valve).
    rocker_inertia   : float  Rocker moment of inertia about its pivot [kg m²].
    valve_arm        : float  Lever arm reducing it to the valve axis [m].
    """
    return valve_group_mass + spring_mass / 3.0 + rocker_inertia / (valve_arm * valve_arm)


@jit_inline
def specific_forces(
    lift, velocity, push, stiffness, damping, preload, seat_stiffness, seat_damping
):
    """Drive and seat forces per unit mass before clipping [V2] [N/kg].

    Drive ``k'(Y − y) + b'(Ẏ − ẏ) = push − k'y − b'ẏ``; seat ``kz'(δ0 − y) − bz'ẏ =
    Ps0' − kz'y − bz'ẏ`` (``kz δ0 = Ps0``). Primes are per unit mass M.

    lift, velocity : float  Valve lift y [m] and velocity ẏ [m/s].
    push           : float  ``k'Y + b'Ẏ`` of the excitation (:func:`drive_push`) [m/s²].
    stiffness      : float  k' = k/M [1/s²];  damping        : float  b' = b/M [1/s].
    preload        : float  Ps0' = Ps0/M [m/s²].
    seat_stiffness : float  kz' = kz/M [1/s²]; seat_damping  : float  bz' = bz/M [1/s].
    """
    drive = push - stiffness * lift - damping * velocity
    seat = preload - seat_stiffness * lift - seat_damping * velocity
    return drive, seat


@jit_inline
def specific_acceleration(
    lift, velocity, drive, seat, spring_rate, preload, external_damping, seat_depth
):
    """Valve acceleration ÿ [m/s²] from the specific forces of :func:`specific_forces` [V2].

    The drive only pushes; the seat only pushes, and only while y < δ0.
    spring_rate      : float  ks' = ks/M [1/s²];  preload : float  Ps0' = Ps0/M [m/s²].
    external_damping : float  γ' = γ/M [1/s];     seat_depth : float  δ0 = Ps0/kz [m].
    Branch-free (selects only), so it vectorises inside loops over SIMD lanes.
    """
    seat = positive_part(seat) if lift < seat_depth else ZERO
    # Grouped so the spring terms are computed alongside the contact forces: a shorter
    # dependency chain per RK4 stage.
    return (positive_part(drive) + seat) - (
        preload + spring_rate * lift + external_damping * velocity
    )


@jit_inline
def drive_push(drive_lift, slope, stiffness, damping_speed):
    """Excitation term ``k'Y + b'Ẏ`` of the drive force per unit mass [m/s²].

    drive_lift    : float  Theoretical valve lift Y [m].
    slope         : float  Y' = dY/dθ [m/rad].
    stiffness     : float  k' = k/M [1/s²].
    damping_speed : float  b'ω = bω/M [1/(s rad)] (Ẏ = ω Y').
    """
    return stiffness * drive_lift + damping_speed * slope


@jit_inline
def valve_acceleration(
    lift,
    velocity,
    drive_lift,
    drive_velocity,
    inv_mass,
    drive_stiffness,
    drive_damping,
    spring_rate,
    preload,
    seat_stiffness,
    seat_damping,
    external_damping,
    seat_depth,
):
    """Valve acceleration ÿ from the one-sided drive and seat forces [V2].

    lift, velocity   : float  Valve lift y [m] and velocity ẏ [m/s].
    drive_lift       : float  Theoretical valve lift Y (drive side) [m].
    drive_velocity   : float  Ẏ = ω Y' [m/s].
    inv_mass         : float  1/M [1/kg].
    drive_stiffness  : float  k [N/m];  drive_damping : float  b [N s/m].
    spring_rate      : float  ks [N/m]; preload       : float  Ps0 [N].
    seat_stiffness   : float  kz [N/m]; seat_damping  : float  bz [N s/m].
    external_damping : float  γ [N s/m].
    seat_depth       : float  Seat pre-compression δ0 = Ps0/kz [m].

    The integrators use the same law per unit mass (:func:`specific_forces`,
    :func:`specific_acceleration`), with the coefficients divided by M once per case.
    """
    k = drive_stiffness * inv_mass
    b = drive_damping * inv_mass
    ps0 = preload * inv_mass
    drive, seat = specific_forces(
        lift,
        velocity,
        k * drive_lift + b * drive_velocity,
        k,
        b,
        ps0,
        seat_stiffness * inv_mass,
        seat_damping * inv_mass,
    )
    return specific_acceleration(
        lift,
        velocity,
        drive,
        seat,
        spring_rate * inv_mass,
        ps0,
        external_damping * inv_mass,
        seat_depth,
    )


@jit_inline
def specific_coefficients(params):
    """Coefficients of [V2] per unit mass for the integrators, from a ``P_*`` row.

    Returns k', b', ks', Ps0', kz', bz', γ' (each divided by M), δ0 = Ps0/kz [m],
    ω [rad/s] and b'ω [1/(s rad)] (see :func:`specific_forces`, :func:`drive_push`).
    """
    inv_mass = 1.0 / params[P_MASS]
    damping = params[P_DRIVE_DAMPING] * inv_mass
    return (
        params[P_DRIVE_STIFFNESS] * inv_mass,
        damping,
        params[P_SPRING_RATE] * inv_mass,
        params[P_PRELOAD] * inv_mass,
        params[P_SEAT_STIFFNESS] * inv_mass,
        params[P_SEAT_DAMPING] * inv_mass,
        params[P_EXTERNAL_DAMPING] * inv_mass,
        params[P_PRELOAD] / params[P_SEAT_STIFFNESS],
        params[P_SPEED],
        damping * params[P_SPEED],
    )


@jit
def valve_spectral_radius(
    mass,
    drive_stiffness,
    drive_damping,
    spring_rate,
    seat_stiffness,
    seat_damping,
    external_damping,
):
    """Largest eigenvalue modulus over the four linear modes of [V2] [1/s].

    Modes: contact+seat ``(k + kz + ks, b + bz + γ)``, contact ``(k + ks, b + γ)``, seat
    ``(kz + ks, bz + γ)``, free ``(ks, γ)`` (SPEC §4, stability). Arguments as in
    :func:`valve_acceleration` ([kg], [N/m], [N s/m]).
    """
    radius = oscillator_spectral_radius(
        mass,
        drive_damping + seat_damping + external_damping,
        drive_stiffness + seat_stiffness + spring_rate,
    )
    radius = max(
        radius,
        oscillator_spectral_radius(
            mass, drive_damping + external_damping, drive_stiffness + spring_rate
        ),
    )
    radius = max(
        radius,
        oscillator_spectral_radius(
            mass, seat_damping + external_damping, seat_stiffness + spring_rate
        ),
    )
    return max(radius, oscillator_spectral_radius(mass, external_damping, spring_rate))


@jit_inline
def valve_energy(
    lift,
    velocity,
    drive_lift,
    mass,
    drive_stiffness,
    spring_rate,
    preload,
    seat_stiffness,
    seat_depth,
):
    """Valve-train energy above the rest state [J].

    ``E = ½Mẏ² + ½ks y² + Ps0 y + ½kz ((δ0 − y)²·[y < δ0] − δ0²) + ½k (Y − y)²·[Y > y]``.
    Along any solution of [V2] ``dE/dt ≤ F_drive·Ẏ``: the one-sided drive and seat, with
    their dampers, only ever remove energy, so E can grow only by the work the cam does
    through the drive. Arguments as in :func:`valve_acceleration` ([m], [m/s], [kg], [N/m],
    [N]).
    """
    seat = seat_depth - lift if lift < seat_depth else ZERO
    drive = drive_lift - lift if drive_lift > lift else ZERO
    return (
        HALF * mass * velocity * velocity
        + HALF * spring_rate * lift * lift
        + preload * lift
        + HALF * seat_stiffness * (seat * seat - seat_depth * seat_depth)
        + HALF * drive_stiffness * drive * drive
    )


@jit
def excitation_lift_slope(excitation, table_step, position):
    """Excitation (Y, Y') at a fractional table position by cubic Hermite interpolation.

    excitation : 2-D array  Rows Y [m], Y' [m/rad], Y'' [m/rad²] at spacing ``table_step``.
    table_step : float      Table spacing [rad].
    position   : float      Position in table intervals from the first node [-].

    Returns Y [m] and Y' [m/rad]; at a node (integer position) exactly the table values.
    Reference: de Boor, *A Practical Guide to Splines*, ch. IV (cubic Hermite).
    """
    last = excitation.shape[1] - 1
    index = min(int(position), last - 1)
    s = position - index
    lift = hermite_value(
        excitation[0, index],
        excitation[1, index],
        excitation[0, index + 1],
        excitation[1, index + 1],
        table_step,
        s,
    )
    slope = hermite_value(
        excitation[1, index],
        excitation[2, index],
        excitation[1, index + 1],
        excitation[2, index + 1],
        table_step,
        s,
    )
    return lift, slope


@jit
def excitation_at(excitation, table_step, position, speed):
    """Excitation (Y [m], Ẏ = ω Y' [m/s]) at a fractional table position.

    speed : float  Camshaft speed ω [rad/s]; other arguments as in
    :func:`excitation_lift_slope`.
    """
    lift, slope = excitation_lift_slope(excitation, table_step, position)
    return lift, speed * slope
