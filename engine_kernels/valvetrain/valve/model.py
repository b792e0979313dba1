"""Valve-train model [V1], [V2]: forces, energy, stiffest mode, excitation (physics §4).

Model [V2], in time, with the valve lift y measured from the closed position where the seat
is pre-compressed by ``δ0 = Ps0/kz``::

    M ÿ = max(0, k (Y − y) + b (Ẏ − ẏ))                   drive; ≤ 0 means SEPARATION
        + max(0, kz (δ0 − y) − bz ẏ)   while y < δ0        seat; never pulls
        − ks y − Ps0 − γ ẏ

Parameter rows and the other data layouts (``P_*``, ``O_*``, ``C_*``, ``S_*``) are in
:mod:`engine_kernels.valvetrain.valve.layout`; the integrators use the coefficients per unit mass,
written once per case into the ``K_*`` rows of its record by :func:`valve_coefficients`. The
excitation is a table of the theoretical valve lift Y(θ) and its angle derivatives (rows Y [m],
Y' [m/rad], Y'' [m/rad²]) read by :func:`excitation_at`. The table may hold the lift before the
lash is taken up (smooth, negative on the base circle): every read clips it (:func:`lash_clip`),
so the kink at lash take-up sits where the smooth lift crosses zero between nodes, instead of
being smeared over a table interval by the interpolation of a clipped table (an error of
5–50 nm in Y and up to the whole jump in Y' there, that did not shrink regularly with the
spacing). Reference: physics §4 and the motorcycle OHC valve-train thesis data quoted there.
"""

from __future__ import annotations

import numpy as np

from engine_kernels._jit import jit, jit_inline
from engine_kernels.valvetrain.rk4 import hermite_value, oscillator_spectral_radius
from engine_kernels.valvetrain.valve.layout import (
    K_BAND,
    K_DAMPING,
    K_DAMPING_SPEED,
    K_EXTERNAL_DAMPING,
    K_MASS,
    K_PRELOAD,
    K_SEAT_DAMPING,
    K_SEAT_DEPTH,
    K_SEAT_STIFFNESS,
    K_SPEED,
    K_SPRING_RATE,
    K_STIFFNESS,
    N_RECORD,
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

# Constants of the integrator arithmetic, typed float32: exact in both precisions, so a
# float64 kernel computes the same numbers as with Python floats, while the float32 lane
# kernel (engine_kernels.valvetrain.valve.lanes) is not promoted to float64 by a literal.
ZERO = np.float32(0.0)
HALF = np.float32(0.5)
ONE = np.float32(1.0)
TWO = np.float32(2.0)
INF = np.float32(np.inf)
NAN = np.float32(np.nan)

# Dead band of the contact and seat mode changes, per unit of the preload force [-].
TRANSITION_BAND = 1e-6

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
def seat_depth(params):
    """Seat pre-compression ``δ0 = Ps0/kz`` [m] of a ``P_*`` row."""
    return params[P_PRELOAD] / params[P_SEAT_STIFFNESS]


@jit
def valve_coefficients(params, record, at, w):
    """Write the coefficients of [V2] per unit mass of a ``P_*`` row into a case record.

    params : 1-D array  Parameter row (``P_*``, SI units).
    record : 1-D array  Flat records (layout in :mod:`engine_kernels.valvetrain.valve.layout`); the
                        ``K_*`` rows of this case at ``at + K_*·w`` are written (k', b', ks',
                        Ps0', kz', bz', γ', δ0, ω, b'ω, the mode dead band and M), computed
                        in float64 whatever the precision of ``record``.
    at, w  : int        Offset of this case's row 0 and row stride (1, or lanes per block).
    """
    inv_mass = 1.0 / params[P_MASS]
    damping = params[P_DRIVE_DAMPING] * inv_mass
    preload = params[P_PRELOAD] * inv_mass
    record[at + K_STIFFNESS * w] = params[P_DRIVE_STIFFNESS] * inv_mass
    record[at + K_DAMPING * w] = damping
    record[at + K_SPRING_RATE * w] = params[P_SPRING_RATE] * inv_mass
    record[at + K_PRELOAD * w] = preload
    record[at + K_SEAT_STIFFNESS * w] = params[P_SEAT_STIFFNESS] * inv_mass
    record[at + K_SEAT_DAMPING * w] = params[P_SEAT_DAMPING] * inv_mass
    record[at + K_EXTERNAL_DAMPING * w] = params[P_EXTERNAL_DAMPING] * inv_mass
    record[at + K_SEAT_DEPTH * w] = seat_depth(params)
    record[at + K_SPEED * w] = params[P_SPEED]
    record[at + K_DAMPING_SPEED * w] = damping * params[P_SPEED]
    record[at + K_BAND * w] = TRANSITION_BAND * preload
    record[at + K_MASS * w] = params[P_MASS]


@jit_inline
def case_coefficients(record, at, w):
    """The ``K_*`` rows of a case record as a tuple: element r is row r, so ``c[K_STIFFNESS]``
    is k' as ``record[at + K_STIFFNESS·w]`` is.

    Read once where a case's arithmetic starts (a lane of a lane loop, a run of the one-case
    kernel), the coefficients stay in registers: every row is loaded unconditionally, and
    stores to other rows cannot force them to be reloaded. Rows no caller uses cost nothing
    (Numba inlines this, LLVM drops the unused loads).
    """
    return (
        record[at],
        record[at + w],
        record[at + 2 * w],
        record[at + 3 * w],
        record[at + 4 * w],
        record[at + 5 * w],
        record[at + 6 * w],
        record[at + 7 * w],
        record[at + 8 * w],
        record[at + 9 * w],
        record[at + 10 * w],
        record[at + 11 * w],
        record[at + 12 * w],
        record[at + 13 * w],
        record[at + 14 * w],
        record[at + 15 * w],
    )


@jit_inline
def specific_forces(lift, velocity, push, c):
    """Drive and seat forces per unit mass before clipping [V2] [N/kg].

    Drive ``k'(Y − y) + b'(Ẏ − ẏ) = push − k'y − b'ẏ``; seat ``kz'(δ0 − y) − bz'ẏ =
    Ps0' − kz'y − bz'ẏ`` (``kz δ0 = Ps0``). Primes are per unit mass M.

    lift, velocity : float  Valve lift y [m] and velocity ẏ [m/s].
    push           : float  ``k'Y + b'Ẏ`` of the excitation (:func:`drive_push`) [m/s²].
    c              : Coefficients ``K_*`` of the case (:func:`case_coefficients`).
    """
    drive = push - c[K_STIFFNESS] * lift - c[K_DAMPING] * velocity
    seat = c[K_PRELOAD] - c[K_SEAT_STIFFNESS] * lift - c[K_SEAT_DAMPING] * velocity
    return drive, seat


@jit_inline
def specific_acceleration(lift, velocity, drive, seat, c):
    """Valve acceleration ÿ [m/s²] from the specific forces of :func:`specific_forces` [V2].

    The drive only pushes; the seat only pushes, and only while y < δ0. Coefficients as in
    :func:`specific_forces`. Branch-free (selects only), so it vectorises inside loops over
    SIMD lanes.
    """
    seat = positive_part(seat) if lift < c[K_SEAT_DEPTH] else ZERO
    # Grouped so the spring terms are computed alongside the contact forces: a shorter
    # dependency chain per RK4 stage.
    return (positive_part(drive) + seat) - (
        c[K_PRELOAD] + c[K_SPRING_RATE] * lift + c[K_EXTERNAL_DAMPING] * velocity
    )


@jit_inline
def drive_push(drive_lift, slope, c):
    """Excitation term ``k'Y + b'Ẏ`` of the drive force per unit mass [m/s²].

    drive_lift    : float  Theoretical valve lift Y [m].
    slope         : float  Y' = dY/dθ [m/rad] (Ẏ = ω Y').
    c             : Coefficients ``K_*`` of the case (:func:`case_coefficients`).
    """
    return c[K_STIFFNESS] * drive_lift + c[K_DAMPING_SPEED] * slope


@jit_inline
def specific_point(lift, velocity, drive_lift, slope, c):
    """Forces and acceleration of a case in state (y [m], ẏ [m/s]) at excitation Y [m], Y' [m/rad].

    Returns the drive and seat forces per unit mass before clipping [N/kg]
    (:func:`specific_forces`) and the acceleration ÿ [m/s²] (:func:`specific_acceleration`).
    c             : Coefficients ``K_*`` of the case (:func:`case_coefficients`).
    """
    push = drive_push(drive_lift, slope, c)
    drive, seat = specific_forces(lift, velocity, push, c)
    return drive, seat, specific_acceleration(lift, velocity, drive, seat, c)


@jit
def valve_acceleration(lift, velocity, drive_lift, drive_velocity, params):
    """Valve acceleration ÿ [m/s²] from the one-sided drive and seat forces [V2].

    lift, velocity : float      Valve lift y [m] and velocity ẏ [m/s].
    drive_lift     : float      Theoretical valve lift Y (drive side) [m].
    drive_velocity : float      Ẏ = ω Y' [m/s].
    params         : 1-D array  Parameter row (``P_*``, SI units).

    The integrators use the same law per unit mass (:func:`specific_forces`,
    :func:`specific_acceleration`), with the coefficients of :func:`valve_coefficients`.
    """
    record = np.empty(N_RECORD)
    valve_coefficients(params, record, 0, 1)
    c = case_coefficients(record, 0, 1)
    push = c[K_STIFFNESS] * drive_lift + c[K_DAMPING] * drive_velocity
    drive, seat = specific_forces(lift, velocity, push, c)
    return specific_acceleration(lift, velocity, drive, seat, c)


@jit
def valve_spectral_radius(params):
    """Largest eigenvalue modulus over the four linear modes of [V2] [1/s].

    Modes: contact+seat ``(k + kz + ks, b + bz + γ)``, contact ``(k + ks, b + γ)``, seat
    ``(kz + ks, bz + γ)``, free ``(ks, γ)`` (physics §4, stability).
    params : 1-D array  Parameter row (``P_*``, SI units).
    """
    mass = params[P_MASS]
    k, b = params[P_DRIVE_STIFFNESS], params[P_DRIVE_DAMPING]
    ks, gamma = params[P_SPRING_RATE], params[P_EXTERNAL_DAMPING]
    kz, bz = params[P_SEAT_STIFFNESS], params[P_SEAT_DAMPING]
    radius = oscillator_spectral_radius(mass, b + bz + gamma, k + kz + ks)
    radius = max(radius, oscillator_spectral_radius(mass, b + gamma, k + ks))
    radius = max(radius, oscillator_spectral_radius(mass, bz + gamma, kz + ks))
    return max(radius, oscillator_spectral_radius(mass, gamma, ks))


@jit_inline
def valve_energy(lift, velocity, drive_lift, c):
    """Valve-train energy per unit mass above the rest state [J/kg].

    ``E/M = ½ẏ² + ½ks' y² + Ps0' y + ½kz' ((δ0 − y)²·[y < δ0] − δ0²) + ½k' (Y − y)²·[Y > y]``.
    Along any solution of [V2] ``dE/dt ≤ F_drive·Ẏ``: the one-sided drive and seat, with
    their dampers, only ever remove energy, so E can grow only by the work the cam does
    through the drive. lift y [m], velocity ẏ [m/s], drive_lift Y [m]; coefficients as in
    :func:`specific_forces`.
    """
    depth = c[K_SEAT_DEPTH]
    seat = depth - lift if lift < depth else ZERO
    drive = drive_lift - lift if drive_lift > lift else ZERO
    return (
        HALF * velocity * velocity
        + HALF * c[K_SPRING_RATE] * lift * lift
        + c[K_PRELOAD] * lift
        + HALF * c[K_SEAT_STIFFNESS] * (seat * seat - depth * depth)
        + HALF * c[K_STIFFNESS] * drive * drive
    )


@jit_inline
def lash_clip(drive_lift, slope):
    """The excitation the valve feels: (max(0, Y) [m], Y' [m/rad] where Y > 0 else 0).

    Applied at every read of an excitation table (a table of lift after the lash take-up,
    never negative, is unchanged by it). Also clips Y'' when given (Y', Y'') with Y's sign
    test done by the caller (see :func:`engine_kernels.valvetrain.valve.located.jerk_at`).
    """
    return (max(ZERO, drive_lift)), (slope if drive_lift > ZERO else ZERO)


@jit
def excitation_lift_slope(excitation, table_step, position):
    """Excitation (Y, Y') at a fractional table position by cubic Hermite interpolation.

    excitation : 2-D array  Rows Y [m], Y' [m/rad], Y'' [m/rad²] at spacing ``table_step``.
    table_step : float      Table spacing [rad].
    position   : float      Position in table intervals from the first node [-].

    Returns Y [m] and Y' [m/rad] (:func:`lash_clip`); at a node (integer position) exactly
    the clipped table values. Reference: de Boor, *A Practical Guide to Splines*, ch. IV
    (cubic Hermite).
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
    return lash_clip(lift, slope)


@jit
def excitation_at(excitation, table_step, position, speed):
    """Excitation (Y [m], Ẏ = ω Y' [m/s]) at a fractional table position.

    speed : float  Camshaft speed ω [rad/s]; other arguments as in
    :func:`excitation_lift_slope`.
    """
    lift, slope = excitation_lift_slope(excitation, table_step, position)
    return lift, speed * slope
