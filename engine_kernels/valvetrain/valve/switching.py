"""Switch-aware RK4 for the valve model: located contact and seat switches (physics §4).

Plain fixed-step RK4 loses its order on [V2]: the one-sided drive and seat switch inside
steps. Here the contact and seat modes are held fixed within a step; at the step end each
switching function's sign is compared with the current mode, and a cubic Hermite of the
switching function through its values and time derivatives looks inside the step for a dip
past zero; the earliest crossing is located (seeded on the Hermite, refined by re-taking the
RK4 sub-step to it, aiming just past the root so it is not found again; both stop at a stated
angle, ``SWITCH_ANGLE_TOLERANCE``, not at an iteration count), the mode switches
and the step is finished (the motion in a fixed mode is in
:mod:`engine_kernels.valvetrain.valve.modes`). This restores fourth order (physics §4, "Integrators and the
speed–accuracy trade") and makes step halving a usable error estimate.
"""

from __future__ import annotations

import math

from engine_kernels._jit import jit
from engine_kernels.valvetrain.dopri.step import SWITCH_ANGLE_TOLERANCE
from engine_kernels.valvetrain.rk4 import hermite_value
from engine_kernels.valvetrain.valve.layout import (
    P_DRIVE_DAMPING,
    P_DRIVE_STIFFNESS,
    P_SEAT_DAMPING,
    P_SEAT_STIFFNESS,
    P_SPEED,
)
from engine_kernels.valvetrain.valve.model import excitation_at, seat_depth
from engine_kernels.valvetrain.valve.modes import consistent_modes, mode_acceleration, mode_step

SWITCH_OVERSHOOT = 1e-9
SWITCHES_PER_STEP = 8
MAX_LOCATE_ITERATIONS = 200
"""A guard only: the bisection halves its bracket every iteration and stops at
``SWITCH_ANGLE_TOLERANCE``; Newton's method stops there too."""


@jit
def _guards(
    lift,
    velocity,
    acceleration,
    drive_lift,
    drive_velocity,
    drive_acceleration,
    contact,
    seated,
    params,
):
    """Switching guards of the current mode and their time derivatives.

    A guard is positive while the mode is consistent: contact ``±(k(Y − y) + b(Ẏ − ẏ))``;
    seated ``δ0 − y`` and ``kz(δ0 − y) − bz ẏ``; unseated the negative of whichever of the
    two is still positive. params: the ``P_*`` row.
    """
    k, b = params[P_DRIVE_STIFFNESS], params[P_DRIVE_DAMPING]
    kz, bz = params[P_SEAT_STIFFNESS], params[P_SEAT_DAMPING]
    sign = 1.0 if contact else -1.0
    g0 = sign * (k * (drive_lift - lift) + b * (drive_velocity - velocity))
    d0 = sign * (k * (drive_velocity - velocity) + b * (drive_acceleration - acceleration))
    gap = seat_depth(params) - lift
    force = kz * gap - bz * velocity
    force_rate = -kz * velocity - bz * acceleration
    if seated:
        return g0, d0, gap, -velocity, force, force_rate
    if gap <= 0.0:
        return g0, d0, -gap, velocity, math.inf, 0.0
    return g0, d0, -force, -force_rate, math.inf, 0.0


@jit
def _cubic_root(g0, d0, g1, d1, width):
    """First root in (0, 1] of the cubic Hermite through (g0, d0) and (g1, d1), or −1.

    Values at both ends, slopes per unit of the step fraction; g0 ≥ 0 at the start. The root
    is bracketed by bisection to ``width`` (a fraction of the step) and the bracket's far end
    returned.
    """
    end = 1.0
    if g1 > 0.0:
        # look for an interior dip below zero at the critical points of the cubic
        a = 6.0 * (g0 - g1) + 3.0 * (d0 + d1)
        bq = -6.0 * (g0 - g1) - 4.0 * d0 - 2.0 * d1
        c = d0
        end = -1.0
        disc = bq * bq - 4.0 * a * c
        if disc >= 0.0 and a != 0.0:
            root = math.sqrt(disc)
            for cand in ((-bq - root) / (2.0 * a), (-bq + root) / (2.0 * a)):
                if 0.0 < cand < 1.0 and hermite_value(g0, d0, g1, d1, 1.0, cand) < 0.0:
                    end = cand if end < 0.0 else min(end, cand)
        elif a == 0.0 and bq != 0.0:
            cand = -c / bq
            if 0.0 < cand < 1.0 and hermite_value(g0, d0, g1, d1, 1.0, cand) < 0.0:
                end = cand
        if end < 0.0:
            return -1.0
    lo = 0.0
    hi = end
    for _ in range(MAX_LOCATE_ITERATIONS):
        if hi - lo <= width:
            break
        mid = 0.5 * (lo + hi)
        if hermite_value(g0, d0, g1, d1, 1.0, mid) > 0.0:
            lo = mid
        else:
            hi = mid
    return hi


@jit
def _guard_values(excitation, table_step, position, lift, velocity, contact, seated, params):
    """Guards and time derivatives at a table position (see :func:`_guards`)."""
    speed = params[P_SPEED]
    drive_lift, drive_velocity = excitation_at(excitation, table_step, position, speed)
    index = min(int(position), excitation.shape[1] - 2)
    s = position - index
    curvature = excitation[2, index] + s * (excitation[2, index + 1] - excitation[2, index])
    drive_acc = speed * speed * curvature if drive_lift > 0.0 else 0.0  # clipped at the lash
    acc = mode_acceleration(lift, velocity, drive_lift, drive_velocity, contact, seated, params)
    return _guards(
        lift, velocity, acc, drive_lift, drive_velocity, drive_acc, contact, seated, params
    )


@jit
def switch_aware_step(excitation, table_step, start, stop, lift, velocity, params):
    """RK4 from table position ``start`` to ``stop`` with located contact and seat switches.

    excitation : 2-D array  Excitation table (3, n) [m, m/rad, m/rad²] at spacing
                            ``table_step`` [rad].
    start, stop: float      Table positions of the step [-] (table intervals from node 0).
    lift, velocity : float  State at ``start`` [m], [m/s].
    params     : 1-D array  Parameter row (``P_*``, SI units; the camshaft speed ω is its
                            ``P_SPEED``). Returns the end state and the number of located
                            switches (at most ``SWITCHES_PER_STEP``).
    """
    speed = params[P_SPEED]
    drive_lift, drive_velocity = excitation_at(excitation, table_step, start, speed)
    seated = lift < seat_depth(params)
    contact, seated = consistent_modes(
        lift, velocity, drive_lift, drive_velocity, False, seated, params
    )
    position = start
    switches = 0
    for _ in range(SWITCHES_PER_STEP + 1):
        span = stop - position
        tau = span * table_step / speed
        width = SWITCH_ANGLE_TOLERANCE / (span * table_step)  # of the step
        new_lift, new_velocity = mode_step(
            excitation, table_step, position, stop, lift, velocity, contact, seated, params
        )
        if switches == SWITCHES_PER_STEP:
            return new_lift, new_velocity, switches
        ga0, da0, gb0, db0, gc0, dc0 = _guard_values(
            excitation, table_step, position, lift, velocity, contact, seated, params
        )
        ga1, da1, gb1, db1, gc1, dc1 = _guard_values(
            excitation, table_step, stop, new_lift, new_velocity, contact, seated, params
        )
        first = 2.0
        which = -1
        for g0, d0, g1, d1, label in (
            (ga0, da0, ga1, da1, 0),
            (gb0, db0, gb1, db1, 1),
            (gc0, dc0, gc1, dc1, 2),
        ):
            if math.isinf(g0):
                continue
            root = _cubic_root(max(g0, 0.0), d0 * tau, g1, d1 * tau, width)
            if 0.0 <= root < first:
                first = root
                which = label
        if which < 0:
            return new_lift, new_velocity, switches
        fraction = min(first + SWITCH_OVERSHOOT, 1.0)
        for _newton in range(MAX_LOCATE_ITERATIONS):
            target = position + fraction * span
            trial_lift, trial_velocity = mode_step(
                excitation, table_step, position, target, lift, velocity, contact, seated, params
            )
            guards = _guard_values(
                excitation, table_step, target, trial_lift, trial_velocity, contact, seated, params
            )
            g = guards[2 * which]
            dg = guards[2 * which + 1] * tau
            if g < 0.0 or dg >= 0.0 or fraction >= 1.0 or -g / dg <= width:
                break
            fraction = min(fraction - g / dg + SWITCH_OVERSHOOT, 1.0)
        position = target
        lift = trial_lift
        velocity = trial_velocity
        switches += 1
        drive_lift, drive_velocity = excitation_at(excitation, table_step, position, speed)
        new_contact, new_seated = consistent_modes(
            lift, velocity, drive_lift, drive_velocity, contact, seated, params
        )
        if new_contact == contact and new_seated == seated:
            if which == 0:
                new_contact = not contact
            else:
                new_seated = not seated
        contact = new_contact
        seated = new_seated
        if position >= stop:
            return lift, velocity, switches
    return lift, velocity, switches
