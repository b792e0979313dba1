"""Outputs of a valve run located between its observed points (physics §4).

A run is observed at points: the grid points of every kernel, and in
:mod:`engine_kernels.valvetrain.dopri.integrate` also at its located contact and seat switches. An output
read off those points (the largest grid lift, the first separated grid angle, the speed at the
last point above the seat) errs by up to a point spacing, an error that neither shrinks with
the integrator's accuracy nor, on nested grids, shows in the difference between a run and its
companion at half the step (both read the same point half the time). So each is located
between the points, from what the integrators know there:

* **maximum** of the lift (max lift, bounce height): where the velocity turns from positive
  to not positive between two points, the velocity's root by linear interpolation and the
  lift there on the cubic Hermite of (y, ẏ) at both points (fourth order in the spacing;
  the lift is stationary at the root, so the root's error enters squared);
* **jump start**: the root of the drive force between the last point in contact and the
  first separated one, by linear interpolation (second order);
* **seating velocity**: from the last point above the seat, the cubic Taylor polynomial of
  the motion in time (the jerk from the model, :func:`specific_jerk`) to the seat plane,
  solved by Newton's method (third order in the distance; constant acceleration, the former
  rule, was first order and left errors of 1e-6–1e-5 m/s at any step).

The helpers are branch-free where they run at every grid point, so they vectorise in the
SIMD lane kernel (:mod:`engine_kernels.valvetrain.valve.lanes`); rows ``ST_PREV_*`` of the case record
hold the previous point (:mod:`engine_kernels.valvetrain.valve.layout`).
"""

from __future__ import annotations

import math

import numpy as np

from engine_kernels._jit import jit, jit_inline
from engine_kernels.valvetrain.valve.layout import (
    K_DAMPING,
    K_EXTERNAL_DAMPING,
    K_SEAT_DEPTH,
    K_SPEED,
    K_SPRING_RATE,
    K_STIFFNESS,
    PHASE_CLOSED,
    ST_BOUNCE_HEIGHT,
    ST_INVERSE_SPEED,
    ST_MAX_LIFT,
    ST_PHASE,
    ST_PREV_ANGLE,
    ST_PREV_DRIVE,
    ST_PREV_LIFT,
    ST_PREV_VELOCITY,
)
from engine_kernels.valvetrain.valve.model import (
    ONE,
    TWO,
    ZERO,
    drive_push,
    excitation_lift_slope,
    larger,
    specific_forces,
)

THREE = np.float32(3.0)

SEATING_NEWTON_TOLERANCE = 1e-12
"""Relative change of the time to the seat plane at which Newton's method stops [-]."""
MAX_SEATING_ITERATIONS = 50


@jit_inline
def remember_point(record, at, w, angle, lift, velocity, drive):
    """Make (angle [rad], lift [m], velocity [m/s], drive force per unit mass [N/kg]) the
    previous observed point of the case (rows ``ST_PREV_*``)."""
    record[at + ST_PREV_ANGLE * w] = angle
    record[at + ST_PREV_LIFT * w] = lift
    record[at + ST_PREV_VELOCITY * w] = velocity
    record[at + ST_PREV_DRIVE * w] = drive


@jit_inline
def observe_peak(record, at, w, angle, lift, velocity):
    """Located maximum of the lift between the previous observed point and this one.

    Raises the max lift to it and, when the valve had closed and was off its seat (seat phase
    closed or bouncing before this point's update, :func:`engine_kernels.valvetrain.valve.observations.observe_closure`),
    the bounce height to its height above the seat plane. Where the velocity does not turn
    from positive to not positive, the point's own lift counts.

    angle          : float  Cam angle of this point [rad].
    lift, velocity : float  Valve lift y [m] and velocity ẏ [m/s] here.
    """
    y0 = record[at + ST_PREV_LIFT * w]
    v0 = record[at + ST_PREV_VELOCITY * w]
    span = (angle - record[at + ST_PREV_ANGLE * w]) * record[at + ST_INVERSE_SPEED * w]
    turning = (v0 > ZERO) & (velocity <= ZERO)
    s = v0 / (v0 - velocity) if turning else ZERO
    s2 = s * s
    s3 = s2 * s
    # cubic Hermite on the interval, slopes per unit of the interval: v·span
    peak = (
        (TWO * s3 - THREE * s2 + ONE) * y0
        + (s3 - TWO * s2 + s) * span * v0
        + (THREE * s2 - TWO * s3) * lift
        + (s3 - s2) * span * velocity
    )
    peak = larger(peak, lift) if turning else lift
    record[at + ST_MAX_LIFT * w] = larger(record[at + ST_MAX_LIFT * w], peak)
    depth = record[at + K_SEAT_DEPTH * w]
    bounced = record[at + ST_PHASE * w] >= PHASE_CLOSED
    height = peak - depth if bounced & (peak > depth) else ZERO
    record[at + ST_BOUNCE_HEIGHT * w] = larger(record[at + ST_BOUNCE_HEIGHT * w], height)


@jit_inline
def separation_angle(record, at, w, angle, drive):
    """Cam angle [rad] where the drive force (per unit mass, ≤ 0 here) reached zero since the
    previous observed point, by linear interpolation; ``angle`` when it was ≤ 0 there too."""
    f0 = record[at + ST_PREV_DRIVE * w]
    previous = record[at + ST_PREV_ANGLE * w]
    crossing = (f0 >= ZERO) & (f0 > drive)
    fraction = f0 / (f0 - drive) if crossing else ONE
    return previous + fraction * (angle - previous)


@jit_inline
def drive_force_rate(velocity, acceleration, slope, curvature, c):
    """Time derivative of the drive force per unit mass [N/(kg·s)], ``k'(ωY' − ẏ) + b'(ω²Y'' − ÿ)``.

    velocity, acceleration : float  ẏ [m/s] and ÿ [m/s²].
    slope, curvature       : float  Excitation Y' [m/rad] and Y'' [m/rad²].
    c                      : Coefficients ``K_*`` of the case
                             (:func:`engine_kernels.valvetrain.valve.model.case_coefficients`).
    """
    speed = c[K_SPEED]
    return c[K_STIFFNESS] * (speed * slope - velocity) + c[K_DAMPING] * (
        speed * speed * curvature - acceleration
    )


@jit_inline
def specific_jerk(velocity, acceleration, slope, curvature, drive, c):
    """Time derivative ⃛y [m/s³] of the acceleration off the seat [V2] (a located seat landing
    follows it, :func:`seating_speed`).

    velocity, acceleration : float  ẏ [m/s] and ÿ [m/s²].
    slope, curvature       : float  Excitation Y' [m/rad] and Y'' [m/rad²].
    drive                  : float  Drive force per unit mass [N/kg]: the drive acts while > 0.
    c                      : Coefficients ``K_*`` of the case
                             (:func:`engine_kernels.valvetrain.valve.model.case_coefficients`).
    """
    rate = drive_force_rate(velocity, acceleration, slope, curvature, c)
    free = -(c[K_SPRING_RATE] * velocity + c[K_EXTERNAL_DAMPING] * acceleration)
    return free + (rate if drive > ZERO else ZERO)


@jit
def excitation_curvature(excitation, table_step, position):
    """Excitation Y [m], Y' [m/rad] and Y'' [m/rad²] at a fractional table position: Y and Y'
    as :func:`engine_kernels.valvetrain.valve.model.excitation_lift_slope` reads them, Y''
    linear between nodes, all clipped at the lash take-up."""
    drive_lift, slope = excitation_lift_slope(excitation, table_step, position)
    index = min(int(position), excitation.shape[1] - 2)
    s = position - index
    curvature = excitation[2, index] + s * (excitation[2, index + 1] - excitation[2, index])
    return drive_lift, slope, curvature if drive_lift > ZERO else ZERO


@jit
def jerk_at(excitation, table_step, position, lift, velocity, acceleration, c):
    """:func:`specific_jerk` at a fractional table position (:func:`excitation_curvature`).

    excitation : 2-D array  Rows Y [m], Y' [m/rad], Y'' [m/rad²] at spacing ``table_step`` [rad].
    position   : float      Position in table intervals from the first node [-].
    lift, velocity, acceleration : float  y [m], ẏ [m/s], ÿ [m/s²] there.
    """
    drive_lift, slope, curvature = excitation_curvature(excitation, table_step, position)
    drive = specific_forces(lift, velocity, drive_push(drive_lift, slope, c), c)[0]
    return specific_jerk(velocity, acceleration, slope, curvature, drive, c)


@jit
def seating_speed(height, velocity, acceleration, jerk):
    """Speed [m/s] at which the valve reaches the seat plane from a point ``height`` [m] above
    it with velocity [m/s], acceleration [m/s²] and jerk [m/s³] there.

    The first root τ > 0 of ``height + v τ + a τ²/2 + j τ³/6`` by Newton's method from the root
    at constant acceleration; where that fails (no root, a root past the first turn of the
    cubic) the constant-acceleration speed ``sqrt(v² − 2 a height)`` is returned, the rule the
    kernels used before.
    """
    squared = velocity * velocity - 2.0 * acceleration * height
    fallback = math.sqrt(max(squared, 0.0))
    if not (velocity < 0.0 and squared > 0.0 and height >= 0.0):
        return fallback
    tau = 2.0 * height / (-velocity + fallback)  # the smaller root, without cancellation
    for _ in range(MAX_SEATING_ITERATIONS):
        rate = velocity + tau * (acceleration + 0.5 * tau * jerk)
        if not rate < 0.0:
            return fallback
        value = height + tau * (velocity + tau * (0.5 * acceleration + tau * jerk / 6.0))
        change = value / rate
        tau -= change
        if abs(change) <= SEATING_NEWTON_TOLERANCE * tau:
            break
    rate = velocity + tau * (acceleration + 0.5 * tau * jerk)
    if not (tau >= 0.0 and rate < 0.0):
        return fallback
    return -rate
