"""Valve motion with the contact and seat modes held fixed: the pieces of switch-aware RK4.

Within a step of :func:`engine_kernels.valvetrain.valve.switching.switch_aware_step` the drive
contact and the seat contact are either on or off (no clipping); these kernels give the
acceleration and one RK4 step in such a fixed mode of [V2], and the modes a state implies.
The coefficients are those of a ``P_*`` parameter row (SI units, as in
:func:`engine_kernels.valvetrain.valve.model.valve_acceleration`). Reference: physics §4.
"""

from __future__ import annotations

from engine_kernels._jit import jit
from engine_kernels.valvetrain.valve.layout import (
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
from engine_kernels.valvetrain.valve.model import excitation_at, seat_depth


@jit
def mode_acceleration(lift, velocity, drive_lift, drive_velocity, contact, seated, params):
    """Acceleration with the contact and seat modes held fixed (no clipping) [m/s²].

    lift, velocity             : float  Valve lift y [m] and velocity ẏ [m/s].
    drive_lift, drive_velocity : float  Excitation Y [m] and Ẏ [m/s].
    contact, seated            : bool   Drive and seat contact held on or off.
    params                     : 1-D array  Parameter row (``P_*``).
    """
    force = (
        -params[P_SPRING_RATE] * lift - params[P_PRELOAD] - params[P_EXTERNAL_DAMPING] * velocity
    )
    if contact:
        force += params[P_DRIVE_STIFFNESS] * (drive_lift - lift) + params[P_DRIVE_DAMPING] * (
            drive_velocity - velocity
        )
    if seated:
        force += (
            params[P_SEAT_STIFFNESS] * (seat_depth(params) - lift)
            - params[P_SEAT_DAMPING] * velocity
        )
    return force * (1.0 / params[P_MASS])


@jit
def mode_step(excitation, table_step, start, stop, lift, velocity, contact, seated, params):
    """One RK4 step in a fixed mode between two table positions; returns the end state.

    excitation, table_step : Excitation table and its spacing [rad] (as in
                             :func:`engine_kernels.valvetrain.valve.model.excitation_at`).
    start, stop            : float  Table positions of the step [-].
    Other arguments as in :func:`mode_acceleration`; the speed is the row's ``P_SPEED``.
    """
    speed = params[P_SPEED]
    tau = (stop - start) * table_step / speed
    y0, yd0 = excitation_at(excitation, table_step, start, speed)
    ym, ydm = excitation_at(excitation, table_step, 0.5 * (start + stop), speed)
    y1, yd1 = excitation_at(excitation, table_step, stop, speed)
    a1 = mode_acceleration(lift, velocity, y0, yd0, contact, seated, params)
    p2 = lift + 0.5 * tau * velocity
    v2 = velocity + 0.5 * tau * a1
    a2 = mode_acceleration(p2, v2, ym, ydm, contact, seated, params)
    p3 = lift + 0.5 * tau * v2
    v3 = velocity + 0.5 * tau * a2
    a3 = mode_acceleration(p3, v3, ym, ydm, contact, seated, params)
    p4 = lift + tau * v3
    v4 = velocity + tau * a3
    a4 = mode_acceleration(p4, v4, y1, yd1, contact, seated, params)
    return (
        lift + tau / 6.0 * (velocity + 2.0 * v2 + 2.0 * v3 + v4),
        velocity + tau / 6.0 * (a1 + 2.0 * a2 + 2.0 * a3 + a4),
    )


@jit
def consistent_modes(lift, velocity, drive_lift, drive_velocity, contact, seated, params):
    """Modes implied by the state; an exact zero keeps the current mode.

    Arguments as in :func:`mode_acceleration`.
    """
    drive = params[P_DRIVE_STIFFNESS] * (drive_lift - lift) + params[P_DRIVE_DAMPING] * (
        drive_velocity - velocity
    )
    if drive != 0.0:
        contact = drive > 0.0
    gap = seat_depth(params) - lift
    seat = params[P_SEAT_STIFFNESS] * gap - params[P_SEAT_DAMPING] * velocity
    if gap != 0.0 and seat != 0.0:
        seated = gap > 0.0 and seat > 0.0
    return contact, seated
