"""One Dormand–Prince 5(4) step of the valve model [V2] in a fixed mode, its dense output and
the location of a contact or seat switch on it (physics §4, "Integrators and the speed–accuracy
trade").

Within a step the drive contact and the seat contact are held on or off
(:func:`mode_acceleration`, the law of
:func:`engine_kernels.valvetrain.valve.modes.mode_acceleration` on the coefficients per unit mass of
:func:`engine_kernels.valvetrain.valve.model.case_coefficients`), so the right-hand side is smooth
and the pair keeps its orders. The step gives the fifth-order end state, the embedded
fourth-order error estimate and Hairer's free fourth-order dense output. The switching
functions are the drive force ``k(Y − y) + b(Ẏ − ẏ)`` (contact while positive) and the seat
function ``min(kz(δ0 − y), kz(δ0 − y) − bz ẏ)`` (seated while positive: below the seat plane
and pushing); both are evaluated on the dense output, and a crossing is located on it to a
stated angle (``SWITCH_ANGLE_TOLERANCE``). The driver is :mod:`engine_kernels.valvetrain.dopri.integrate`.

Reference: Dormand & Prince, J. Comput. Appl. Math. 6 (1980) 19–26; Hairer, Nørsett & Wanner,
*Solving ODEs I*, §II.4–II.6 (tableau, dense output ``contd5``, step-size control).
"""

from __future__ import annotations

from engine_kernels._jit import jit, jit_inline
from engine_kernels.valvetrain.valve.layout import (
    K_EXTERNAL_DAMPING,
    K_MASS,
    K_PRELOAD,
    K_SEAT_STIFFNESS,
    K_SPRING_RATE,
)
from engine_kernels.valvetrain.valve.model import drive_push, lash_clip, specific_forces

C2, C3, C4, C5 = 1.0 / 5.0, 3.0 / 10.0, 4.0 / 5.0, 8.0 / 9.0
A21 = 1.0 / 5.0
A31, A32 = 3.0 / 40.0, 9.0 / 40.0
A41, A42, A43 = 44.0 / 45.0, -56.0 / 15.0, 32.0 / 9.0
A51, A52, A53, A54 = 19372.0 / 6561.0, -25360.0 / 2187.0, 64448.0 / 6561.0, -212.0 / 729.0
A61, A62, A63 = 9017.0 / 3168.0, -355.0 / 33.0, 46732.0 / 5247.0
A64, A65 = 49.0 / 176.0, -5103.0 / 18656.0
B1, B3, B4, B5, B6 = 35.0 / 384.0, 500.0 / 1113.0, 125.0 / 192.0, -2187.0 / 6784.0, 11.0 / 84.0
E1, E3, E4 = 71.0 / 57600.0, -71.0 / 16695.0, 71.0 / 1920.0
E5, E6, E7 = -17253.0 / 339200.0, 22.0 / 525.0, -1.0 / 40.0
D1, D3 = -12715105075.0 / 11282082432.0, 87487479700.0 / 32700410799.0
D4, D5 = -10690763975.0 / 1880347072.0, 701980252875.0 / 199316789632.0
D6, D7 = -1453857185.0 / 822651844.0, 69997945.0 / 29380423.0

SWITCH_ANGLE_TOLERANCE = 1e-9
"""Width [rad of cam] to which a switch is bracketed on the dense output before the step is
redone to the bracket's far end: the switch is applied at most this late. A force jump of
M·1500 m/s² (the drive taking up the lash at 9000 rpm) applied 1e-9 rad late moves the lift by
~1e-11 m over the rest of the event."""
MAX_LOCATE_ITERATIONS = 200
"""A guard only: at least every third iteration halves the bracket, so a step of up to
1e10 rad of cam is located in fewer iterations."""


@jit_inline
def mode_acceleration(lift, velocity, drive_lift, slope, contact, seated, c):
    """Acceleration ÿ [m/s²] of [V2] with the contact and seat modes held fixed (no clipping).

    lift, velocity : float  Valve lift y [m] and velocity ẏ [m/s].
    drive_lift     : float  Excitation Y [m]; slope: Y' [m/rad].
    contact, seated: bool   Drive and seat contact held on or off.
    c              : Coefficients ``K_*`` of the case
                     (:func:`engine_kernels.valvetrain.valve.model.case_coefficients`).
    """
    drive, seat = specific_forces(lift, velocity, drive_push(drive_lift, slope, c), c)
    acc = -(c[K_PRELOAD] + c[K_SPRING_RATE] * lift + c[K_EXTERNAL_DAMPING] * velocity)
    if contact:
        acc += drive
    if seated:
        acc += seat
    return acc


@jit_inline
def excitation_stage(excitation, table_step, scale, time):
    """Excitation Y [m] and Y' [m/rad] at time ``time`` [s] (table position ``time·scale``).

    The cubic Hermite of :func:`engine_kernels.valvetrain.valve.model.excitation_lift_slope`, the
    same numbers (clipped at the lash take-up), written out here so it is inlined into the
    stages.
    """
    position = time * scale
    index = min(int(position), excitation.shape[1] - 2)
    s = position - index
    s2 = s * s
    s3 = s2 * s
    h00 = 2.0 * s3 - 3.0 * s2 + 1.0
    h10 = (s3 - 2.0 * s2 + s) * table_step
    h01 = -2.0 * s3 + 3.0 * s2
    h11 = (s3 - s2) * table_step
    y0, d0, a0 = excitation[0, index], excitation[1, index], excitation[2, index]
    y1, d1, a1 = excitation[0, index + 1], excitation[1, index + 1], excitation[2, index + 1]
    return lash_clip(
        h00 * y0 + h10 * d0 + h01 * y1 + h11 * d1, h00 * d0 + h10 * a0 + h01 * d1 + h11 * a1
    )


@jit
def dopri_step(excitation, table_step, speed, time, h, lift, velocity, acc, mode, c, dense):
    """One DP5(4) step of [V2] with the modes held fixed, from time ``time`` [s].

    excitation, table_step : Excitation table (3, n) [m, m/rad, m/rad²] and its spacing [rad]
                             (:func:`engine_kernels.valvetrain.valve.model.excitation_at`); the table
                             position of time t is ``t·ω/table_step``.
    speed          : float  Camshaft speed ω [rad/s].
    h              : float  Step [s].
    lift, velocity : float  State y [m], ẏ [m/s] at ``time``; acc: ÿ there [m/s²] (FSAL).
    mode           : (bool, bool)  Drive contact and seat contact held on or off.
    c              : Coefficients ``K_*`` of the case (:func:`mode_acceleration`).
    dense          : 1-D array  (10,) out: dense-output coefficients of lift and velocity.
    Returns the end lift [m], velocity [m/s], acceleration [m/s²] and the error estimate of
    lift [m] and velocity [m/s] (fifth minus fourth order).
    """
    contact, seated = mode
    scale = speed / table_step
    p = lift + h * A21 * velocity
    q = velocity + h * A21 * acc
    ya, va = excitation_stage(excitation, table_step, scale, time + C2 * h)
    k2 = mode_acceleration(p, q, ya, va, contact, seated, c)
    p3 = lift + h * (A31 * velocity + A32 * q)
    q3 = velocity + h * (A31 * acc + A32 * k2)
    ya, va = excitation_stage(excitation, table_step, scale, time + C3 * h)
    k3 = mode_acceleration(p3, q3, ya, va, contact, seated, c)
    p4 = lift + h * (A41 * velocity + A42 * q + A43 * q3)
    q4 = velocity + h * (A41 * acc + A42 * k2 + A43 * k3)
    ya, va = excitation_stage(excitation, table_step, scale, time + C4 * h)
    k4 = mode_acceleration(p4, q4, ya, va, contact, seated, c)
    p5 = lift + h * (A51 * velocity + A52 * q + A53 * q3 + A54 * q4)
    q5 = velocity + h * (A51 * acc + A52 * k2 + A53 * k3 + A54 * k4)
    ya, va = excitation_stage(excitation, table_step, scale, time + C5 * h)
    k5 = mode_acceleration(p5, q5, ya, va, contact, seated, c)
    p6 = lift + h * (A61 * velocity + A62 * q + A63 * q3 + A64 * q4 + A65 * q5)
    q6 = velocity + h * (A61 * acc + A62 * k2 + A63 * k3 + A64 * k4 + A65 * k5)
    ya, va = excitation_stage(excitation, table_step, scale, time + h)
    k6 = mode_acceleration(p6, q6, ya, va, contact, seated, c)
    new_lift = lift + h * (B1 * velocity + B3 * q3 + B4 * q4 + B5 * q5 + B6 * q6)
    new_velocity = velocity + h * (B1 * acc + B3 * k3 + B4 * k4 + B5 * k5 + B6 * k6)
    k7 = mode_acceleration(new_lift, new_velocity, ya, va, contact, seated, c)
    error_lift = h * (E1 * velocity + E3 * q3 + E4 * q4 + E5 * q5 + E6 * q6 + E7 * new_velocity)
    error_velocity = h * (E1 * acc + E3 * k3 + E4 * k4 + E5 * k5 + E6 * k6 + E7 * k7)
    # Hairer's contd5: y(s) = r0 + s(r1 + (1−s)(r2 + s(r3 + (1−s) r4)))
    for row, y0, y1, f1, f3, f4, f5, f6, f7 in (
        (0, lift, new_lift, velocity, q3, q4, q5, q6, new_velocity),
        (5, velocity, new_velocity, acc, k3, k4, k5, k6, k7),
    ):
        difference = y1 - y0
        spline = h * f1 - difference
        dense[row] = y0
        dense[row + 1] = difference
        dense[row + 2] = spline
        dense[row + 3] = difference - h * f7 - spline
        dense[row + 4] = h * (D1 * f1 + D3 * f3 + D4 * f4 + D5 * f5 + D6 * f6 + D7 * f7)
    return new_lift, new_velocity, k7, error_lift, error_velocity


@jit_inline
def dense_state(dense, s):
    """Lift [m] and velocity [m/s] at the fraction ``s`` ∈ [0, 1] of a step (its dense output)."""
    r = 1.0 - s
    lift = dense[0] + s * (dense[1] + r * (dense[2] + s * (dense[3] + r * dense[4])))
    velocity = dense[5] + s * (dense[6] + r * (dense[7] + s * (dense[8] + r * dense[9])))
    return lift, velocity


@jit_inline
def switching_functions(lift, velocity, drive_lift, slope, c):
    """Drive force and seat function [N] of [V2] (contact / seated while positive).

    lift, velocity : float  Valve lift y [m] and velocity ẏ [m/s].
    drive_lift     : float  Excitation Y [m]; slope: Y' [m/rad].
    c              : Coefficients ``K_*`` of the case (:func:`mode_acceleration`).
    """
    drive, seat = specific_forces(lift, velocity, drive_push(drive_lift, slope, c), c)
    gap = c[K_PRELOAD] - c[K_SEAT_STIFFNESS] * lift
    return c[K_MASS] * drive, c[K_MASS] * min(gap, seat)


@jit_inline
def mode_violation(excitation, table_step, speed, time, h, dense, s, mode, band, c):
    """How far the state at fraction ``s`` of a step lies past the switches of its mode [N].

    Returns the drive and the seat violation: the drive force (seat function) beyond zero on
    the side that leaves the mode ``mode`` = (contact, seated), less the dead band ``band``
    [N]; positive once that switch has been crossed. ``time`` [s] and ``h`` [s] are the
    step's start and length, ``dense`` its dense output (:func:`dopri_step`).
    """
    lift, velocity = dense_state(dense, s)
    drive_lift, slope = excitation_stage(excitation, table_step, speed / table_step, time + s * h)
    drive, seat = switching_functions(lift, velocity, drive_lift, slope, c)
    contact, seated = mode
    return (-drive if contact else drive) - band, (-seat if seated else seat) - band


@jit_inline
def _bracket_trial(lo, hi, f_lo, f_hi, iteration, last_width):
    """Next trial point of a bracket [lo, hi] with f(lo) ≤ 0 < f(hi): the Illinois method's
    (regula falsi that halves the weight of a stale end, :func:`_bracket_narrow`), or the
    midpoint when two of its steps have not halved the bracket. Returns the point and the
    width to compare the next pair of steps with."""
    s = (lo * f_hi - hi * f_lo) / (f_hi - f_lo)
    if iteration % 2 == 1:
        if hi - lo > 0.5 * last_width:
            s = 0.5 * (lo + hi)
        last_width = hi - lo
    if not lo < s < hi:
        s = 0.5 * (lo + hi)
    return s, last_width


@jit_inline
def _bracket_narrow(lo, hi, f_lo, f_hi, side, s, f):
    """The bracket after the trial point ``s`` with value ``f`` (see :func:`_bracket_trial`)."""
    if f > 0.0:
        if side == 1:
            f_lo *= 0.5
        return lo, s, f_lo, f, 1
    if side == -1:
        f_hi *= 0.5
    return s, hi, f, f_hi, -1


@jit
def locate_switch(excitation, table_step, speed, time, h, dense, lo, hi, which, mode, band, c):
    """Fraction of the step just past the first crossing of switch ``which`` in (lo, hi].

    The violation (:func:`mode_violation`, 0 drive, 1 seat) is ≤ 0 at ``lo`` and > 0 at
    ``hi``; the bracket shrinks on the dense output until it spans at most
    ``SWITCH_ANGLE_TOLERANCE`` of cam angle, and its end past the root is returned, so the
    redone step ends on the far side of the switch, never later than that tolerance. Trial
    points: :func:`_bracket_trial` (the Illinois method, bisection when it stalls), so a jump
    of the switching function (the drive force at lash take-up, where Ẏ jumps) is bracketed
    as tightly as a smooth crossing. Other arguments as in :func:`mode_violation`.
    """
    f_lo = mode_violation(excitation, table_step, speed, time, h, dense, lo, mode, band, c)[which]
    f_hi = mode_violation(excitation, table_step, speed, time, h, dense, hi, mode, band, c)[which]
    width = SWITCH_ANGLE_TOLERANCE / (h * speed)
    side = 0
    last_width = hi - lo
    for iteration in range(MAX_LOCATE_ITERATIONS):
        if hi - lo <= width:
            break
        s, last_width = _bracket_trial(lo, hi, f_lo, f_hi, iteration, last_width)
        if not lo < s < hi:
            break
        f = mode_violation(excitation, table_step, speed, time, h, dense, s, mode, band, c)[which]
        lo, hi, f_lo, f_hi, side = _bracket_narrow(lo, hi, f_lo, f_hi, side, s, f)
    return hi


@jit
def velocity_turn(dense, width):
    """Fraction of a step where its dense-output velocity turns from positive (at the start)
    to not positive (at the end): a maximum of the lift, bracketed to ``width`` (a fraction of
    the step) like :func:`locate_switch`. ``dense``: the step's dense output."""
    lo, hi = 0.0, 1.0
    f_lo, f_hi = -dense[5], -dense_state(dense, 1.0)[1]
    side = 0
    last_width = 1.0
    for iteration in range(MAX_LOCATE_ITERATIONS):
        if hi - lo <= width:
            break
        s, last_width = _bracket_trial(lo, hi, f_lo, f_hi, iteration, last_width)
        if not lo < s < hi:
            break
        lo, hi, f_lo, f_hi, side = _bracket_narrow(
            lo, hi, f_lo, f_hi, side, s, -dense_state(dense, s)[1]
        )
    return 0.5 * (lo + hi)
