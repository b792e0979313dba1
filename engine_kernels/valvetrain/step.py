"""One plain RK4 step of the valve model [V2], shared by the one-case and lane integrators.

Reference: Hairer, Nørsett & Wanner, *Solving ODEs I*, §II.1; SPEC §4.
"""

from __future__ import annotations

from engine_kernels._jit import jit_inline
from engine_kernels.valvetrain.model import TWO, specific_acceleration, specific_forces

# Step doubling: the RK4 error of a run at step h is about (y_2h − y_h)/(2⁴ − 1).
ERROR_ORDER_DIVISOR = 15.0


@jit_inline
def rk4_valve_step(
    lift,
    velocity,
    acc,
    tau,
    half_tau,
    sixth_tau,
    push_mid,
    push_end,
    stiffness,
    damping,
    spring_rate,
    preload,
    seat_stiffness,
    seat_damping,
    external_damping,
    seat_depth,
):
    """One classic RK4 step of [V2] from the first-stage acceleration ``acc`` [m/s²].

    tau, half_tau, sixth_tau : float  Time step h, h/2 and h/6 [s] (passed in so the lane
                                      kernel computes them once per case, not per step).
    push_mid, push_end       : float  Excitation term ``k'Y + b'Ẏ`` at the half step and the
                                      end (:func:`engine_kernels.valvetrain.model.drive_push`)
                                      [m/s²].
    Coefficients per unit mass as in :func:`engine_kernels.valvetrain.model.specific_forces` and
    :func:`engine_kernels.valvetrain.model.specific_acceleration`. Returns the lift [m] and
    velocity [m/s] at the step end. Reference: Hairer, Nørsett & Wanner, *Solving ODEs I*,
    §II.1.
    """
    k, b, ps0, kz, bz = stiffness, damping, preload, seat_stiffness, seat_damping
    ks, gamma, depth = spring_rate, external_damping, seat_depth
    p2 = lift + half_tau * velocity
    v2 = velocity + half_tau * acc
    drive, seat = specific_forces(p2, v2, push_mid, k, b, ps0, kz, bz)
    a2 = specific_acceleration(p2, v2, drive, seat, ks, ps0, gamma, depth)
    p3 = lift + half_tau * v2
    v3 = velocity + half_tau * a2
    drive, seat = specific_forces(p3, v3, push_mid, k, b, ps0, kz, bz)
    a3 = specific_acceleration(p3, v3, drive, seat, ks, ps0, gamma, depth)
    p4 = lift + tau * v3
    v4 = velocity + tau * a3
    drive, seat = specific_forces(p4, v4, push_end, k, b, ps0, kz, bz)
    a4 = specific_acceleration(p4, v4, drive, seat, ks, ps0, gamma, depth)
    return (
        lift + sixth_tau * (velocity + TWO * (v2 + v3) + v4),
        velocity + sixth_tau * (acc + TWO * (a2 + a3) + a4),
    )
