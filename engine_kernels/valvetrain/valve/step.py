"""One plain RK4 step of the valve model [V2], shared by the one-case and lane integrators.

Reference: Hairer, Nørsett & Wanner, *Solving ODEs I*, §II.1; physics §4.
"""

from __future__ import annotations

from engine_kernels._jit import jit_inline
from engine_kernels.valvetrain.valve.layout import (
    K_HALF_TAU,
    K_SIXTH_TAU,
    K_SPEED,
    K_TAU,
    K_TIME_STEP,
)
from engine_kernels.valvetrain.valve.model import TWO, specific_acceleration, specific_forces


@jit_inline
def valve_time_steps(record, at, w, grid_step, substeps):
    """Write the RK4 sub-step h, h/2, h/6 and the grid time step Δθ/ω into a case record.

    record, at, w : Record of the case (``K_TAU`` ... ``K_TIME_STEP`` rows written, ω read;
                    :mod:`engine_kernels.valvetrain.valve.layout`).
    grid_step     : float  Grid step Δθ [rad].
    substeps      : int    RK4 sub-steps per grid step.
    Computed in float64 whatever the precision of ``record``, once per case and pass.
    """
    speed = record[at + K_SPEED * w]
    tau = grid_step / speed / substeps
    record[at + K_TAU * w] = tau
    record[at + K_HALF_TAU * w] = 0.5 * tau
    record[at + K_SIXTH_TAU * w] = tau / 6.0
    record[at + K_TIME_STEP * w] = grid_step / speed


@jit_inline
def rk4_valve_step(lift, velocity, acc, push_mid, push_end, c):
    """One classic RK4 step of [V2] from the first-stage acceleration ``acc`` [m/s²].

    push_mid, push_end : float  Excitation term ``k'Y + b'Ẏ`` at the half step and the end
                                (:func:`engine_kernels.valvetrain.valve.model.drive_push`) [m/s²].
    c                  : Coefficients and time steps ``K_*`` of the case
                         (:func:`engine_kernels.valvetrain.valve.model.case_coefficients`).
    Returns the lift [m] and velocity [m/s] at the step end. Reference: Hairer, Nørsett &
    Wanner, *Solving ODEs I*, §II.1.
    """
    tau, half_tau, sixth_tau = c[K_TAU], c[K_HALF_TAU], c[K_SIXTH_TAU]
    p2 = lift + half_tau * velocity
    v2 = velocity + half_tau * acc
    drive, seat = specific_forces(p2, v2, push_mid, c)
    a2 = specific_acceleration(p2, v2, drive, seat, c)
    p3 = lift + half_tau * v2
    v3 = velocity + half_tau * a2
    drive, seat = specific_forces(p3, v3, push_mid, c)
    a3 = specific_acceleration(p3, v3, drive, seat, c)
    p4 = lift + tau * v3
    v4 = velocity + tau * a3
    drive, seat = specific_forces(p4, v4, push_end, c)
    a4 = specific_acceleration(p4, v4, drive, seat, c)
    return (
        lift + sixth_tau * (velocity + TWO * (v2 + v3) + v4),
        velocity + sixth_tau * (acc + TWO * (a2 + a3) + a4),
    )
