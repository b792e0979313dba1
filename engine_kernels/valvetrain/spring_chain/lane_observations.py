"""Running observations of the multi-mass spring lane kernel [V4] at a sub-step point.

The one-case kernel's observations
(:func:`engine_kernels.valvetrain.spring_chain.one_case.spring_chain_response`: extremes,
energy balance, jump, seat phase, bounces, seating velocity) with its branches written as
selects, inlined into the valve loop of the observation sweep
(:mod:`engine_kernels.valvetrain.spring_chain.lanes`), which then vectorises.
They update the ``LO_*`` rows of :mod:`engine_kernels.valvetrain.spring_chain.lane_layout`.
Reference: physics §4 [V2], [V4].
"""

from __future__ import annotations

import math

from engine_kernels._jit import jit_inline
from engine_kernels.valvetrain.spring_chain.lane_layout import (
    LANES,
    LK_DEPTH,
    LK_PRELOAD,
    LK_SPRING_RATE,
    LK_TAU,
    LO_BOUNCE_HEIGHT,
    LO_BOUNCES,
    LO_ENERGY,
    LO_ENERGY0,
    LO_ENERGY_MAX,
    LO_EXCESS,
    LO_JUMP_ANGLE,
    LO_JUMP_GAP,
    LO_JUMP_START,
    LO_MAX_CONTACT,
    LO_MAX_DEVIATION,
    LO_MAX_LIFT,
    LO_MAX_V,
    LO_MIN_MARGIN,
    LO_MIN_RATIO,
    LO_MIN_V,
    LO_PHASE,
    LO_PREV_LIFT,
    LO_PREV_POWER,
    LO_PREV_V,
    LO_SEATING,
    LO_SURGE,
    LO_WORK,
    LO_WORK_MAX,
)
from engine_kernels.valvetrain.valve.model import larger, positive_part, smaller


@jit_inline
def observe_valve(obs, l, point, drive_lift, angle, sub_angle, first, c):
    """Running observations of lane ``l`` at a sub-step point, as in the one-case kernel.

    point      : (lift y [m], velocity ẏ [m/s], drive force before clipping [N], Ẏ [m/s],
                 retainer force F_N [N], surge deviation [m]) at the point.
    drive_lift : Y [m];  angle : cam angle of the point [rad];  sub_angle : sub-step [rad];
    first      : the run's first point. Selects only.
    """
    lift, velocity, drive, drive_velocity, retainer, deviation = point
    energy = obs[LO_ENERGY * LANES + l]
    power = positive_part(drive) * drive_velocity
    energy0 = energy if first else obs[LO_ENERGY0 * LANES + l]
    work = obs[LO_WORK * LANES + l]
    work = work if first else work + 0.5 * c[LK_TAU] * (power + obs[LO_PREV_POWER * LANES + l])
    obs[LO_ENERGY0 * LANES + l] = energy0
    obs[LO_WORK * LANES + l] = work
    obs[LO_WORK_MAX * LANES + l] = larger(obs[LO_WORK_MAX * LANES + l], abs(work))
    obs[LO_ENERGY_MAX * LANES + l] = larger(obs[LO_ENERGY_MAX * LANES + l], abs(energy))
    obs[LO_EXCESS * LANES + l] = larger(obs[LO_EXCESS * LANES + l], energy - energy0 - work)
    obs[LO_PREV_POWER * LANES + l] = power
    obs[LO_MAX_LIFT * LANES + l] = larger(obs[LO_MAX_LIFT * LANES + l], lift)
    obs[LO_MAX_V * LANES + l] = larger(obs[LO_MAX_V * LANES + l], velocity)
    obs[LO_MIN_V * LANES + l] = smaller(obs[LO_MIN_V * LANES + l], velocity)
    obs[LO_MAX_CONTACT * LANES + l] = larger(obs[LO_MAX_CONTACT * LANES + l], drive)
    static = c[LK_PRELOAD] + c[LK_SPRING_RATE] * lift
    obs[LO_MIN_RATIO * LANES + l] = smaller(obs[LO_MIN_RATIO * LANES + l], retainer / static)
    obs[LO_MAX_DEVIATION * LANES + l] = larger(
        obs[LO_MAX_DEVIATION * LANES + l], abs(retainer - static)
    )
    obs[LO_SURGE * LANES + l] = larger(obs[LO_SURGE * LANES + l], deviation)
    depth = c[LK_DEPTH]
    event = drive_lift > depth
    margin = obs[LO_MIN_MARGIN * LANES + l]
    obs[LO_MIN_MARGIN * LANES + l] = smaller(margin, drive) if event else margin
    jumping = event & (drive <= 0.0) & (lift > depth)
    start = obs[LO_JUMP_START * LANES + l]
    obs[LO_JUMP_START * LANES + l] = angle if jumping & math.isnan(start) else start
    obs[LO_JUMP_ANGLE * LANES + l] += sub_angle if jumping else 0.0
    gap = obs[LO_JUMP_GAP * LANES + l]
    obs[LO_JUMP_GAP * LANES + l] = larger(gap, lift - drive_lift) if jumping else gap
    observe_seat(obs, l, lift, velocity, depth, first)


@jit_inline
def observe_seat(obs, l, lift, velocity, depth, first):
    """Seat phase, bounces and seating velocity of lane ``l`` (the one-case kernel's branches
    as selects). lift y [m], velocity ẏ [m/s], depth δ0 [m]; first : the run's first point."""
    phase = obs[LO_PHASE * LANES + l]
    prev_lift = obs[LO_PREV_LIFT * LANES + l]
    prev_v = obs[LO_PREV_V * LANES + l]
    up = lift > depth
    reopened = up & (phase >= 2.0)
    obs[LO_BOUNCES * LANES + l] += 1.0 if reopened & (prev_lift <= depth) else 0.0
    height = obs[LO_BOUNCE_HEIGHT * LANES + l]
    obs[LO_BOUNCE_HEIGHT * LANES + l] = larger(height, lift - depth) if reopened else height
    closing = (not up) & (phase == 1.0) & (not first)
    fraction = (depth - prev_lift) / (lift - prev_lift)
    seating = abs(prev_v + fraction * (velocity - prev_v))
    obs[LO_SEATING * LANES + l] = seating if closing else obs[LO_SEATING * LANES + l]
    opened = 1.0 if up & (phase == 0.0) else phase
    obs[LO_PHASE * LANES + l] = 3.0 if reopened else (2.0 if closing else opened)
    obs[LO_PREV_LIFT * LANES + l] = lift
    obs[LO_PREV_V * LANES + l] = velocity
