"""Valve motion with the contact and seat modes held fixed: the pieces of switch-aware RK4.

Within a step of :func:`engine_kernels.valvetrain.switching.switch_aware_step` the drive
contact and the seat contact are either on or off (no clipping); these kernels give the
acceleration and one RK4 step in such a fixed mode of [V2], and the modes a state implies.
Coefficients as in :func:`engine_kernels.valvetrain.model.valve_acceleration`, except
``inv_mass`` = 1/M [1/kg]. Reference: SPEC §4.
"""

from __future__ import annotations

from engine_kernels._jit import jit
from engine_kernels.valvetrain.model import excitation_at


@jit
def mode_acceleration(
    lift,
    velocity,
    drive_lift,
    drive_velocity,
    contact,
    seated,
    inv_mass,
    k,
    b,
    ks,
    ps0,
    kz,
    bz,
    gamma,
    depth,
):
    """Acceleration with the contact and seat modes held fixed (no clipping) [m/s²]."""
    force = -ks * lift - ps0 - gamma * velocity
    if contact:
        force += k * (drive_lift - lift) + b * (drive_velocity - velocity)
    if seated:
        force += kz * (depth - lift) - bz * velocity
    return force * inv_mass


@jit
def mode_step(
    excitation,
    table_step,
    start,
    stop,
    speed,
    lift,
    velocity,
    contact,
    seated,
    inv_mass,
    k,
    b,
    ks,
    ps0,
    kz,
    bz,
    gamma,
    depth,
):
    """One RK4 step in a fixed mode between two table positions; returns the end state."""
    tau = (stop - start) * table_step / speed
    y0, yd0 = excitation_at(excitation, table_step, start, speed)
    ym, ydm = excitation_at(excitation, table_step, 0.5 * (start + stop), speed)
    y1, yd1 = excitation_at(excitation, table_step, stop, speed)
    a1 = mode_acceleration(
        lift, velocity, y0, yd0, contact, seated, inv_mass, k, b, ks, ps0, kz, bz, gamma, depth
    )
    p2 = lift + 0.5 * tau * velocity
    v2 = velocity + 0.5 * tau * a1
    a2 = mode_acceleration(
        p2, v2, ym, ydm, contact, seated, inv_mass, k, b, ks, ps0, kz, bz, gamma, depth
    )
    p3 = lift + 0.5 * tau * v2
    v3 = velocity + 0.5 * tau * a2
    a3 = mode_acceleration(
        p3, v3, ym, ydm, contact, seated, inv_mass, k, b, ks, ps0, kz, bz, gamma, depth
    )
    p4 = lift + tau * v3
    v4 = velocity + tau * a3
    a4 = mode_acceleration(
        p4, v4, y1, yd1, contact, seated, inv_mass, k, b, ks, ps0, kz, bz, gamma, depth
    )
    return (
        lift + tau / 6.0 * (velocity + 2.0 * v2 + 2.0 * v3 + v4),
        velocity + tau / 6.0 * (a1 + 2.0 * a2 + 2.0 * a3 + a4),
    )


@jit
def consistent_modes(
    lift, velocity, drive_lift, drive_velocity, contact, seated, k, b, kz, bz, depth
):
    """Modes implied by the state; an exact zero keeps the current mode."""
    drive = k * (drive_lift - lift) + b * (drive_velocity - velocity)
    if drive != 0.0:
        contact = drive > 0.0
    gap = depth - lift
    seat = kz * gap - bz * velocity
    if gap != 0.0 and seat != 0.0:
        seated = gap > 0.0 and seat > 0.0
    return contact, seated
