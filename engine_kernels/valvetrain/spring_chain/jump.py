"""Valve jump with the multi-mass spring [V4]: the lowest camshaft speed at which it separates.

The search of :func:`engine_kernels.valvetrain.valve.jump.jump_speed` (a geometric scan, then
bisection; the same status codes) with each speed one run of
:func:`engine_kernels.valvetrain.spring_chain.one_case.spring_chain_response`, so surge can
bring the jump below the lumped model's speed.
"""

from __future__ import annotations

import math

import numpy as np

from engine_kernels._jit import jit
from engine_kernels.valvetrain.spring_chain.layout import (
    CHAIN_CURVE_NAMES,
    CHAIN_OUTPUT_NAMES,
    CO_JUMP_DURATION,
    CO_STATUS,
    SC_SPEED,
)
from engine_kernels.valvetrain.spring_chain.one_case import spring_chain_response
from engine_kernels.valvetrain.valve.jump import (
    JUMP_AT_LOWER_BOUND,
    JUMP_FOUND,
    JUMP_NONE_IN_RANGE,
    JUMP_RUN_FAILED,
)
from engine_kernels.valvetrain.valve.layout import STATUS_OK


@jit
def _jumps(excitation, table_step, table_start, work, settings, out, no_curves, speed):
    """Run the chain at ``speed`` [rad/s]: (separated, finished with STATUS_OK)."""
    work[SC_SPEED] = speed
    spring_chain_response(excitation, table_step, table_start, work, settings, out, no_curves)
    return out[CO_JUMP_DURATION] > 0.0, out[CO_STATUS] == STATUS_OK


@jit
def chain_jump_speed(
    excitation,
    table_step,
    table_start,
    params,
    settings,
    speed_low,
    speed_high,
    scan_points,
    tolerance,
):
    """Lowest camshaft speed at which the valve separates, multi-mass spring (physics §4, [V4]).

    Returns ``(speed [rad/s], code)`` with the codes of
    :func:`engine_kernels.valvetrain.valve.jump.jump_speed`. params : 1-D array ``SC_*`` row (its
    speed entry is ignored); the other arguments as in that function.
    """
    work = params.copy()
    out = np.empty(len(CHAIN_OUTPUT_NAMES))
    no_curves = np.empty((len(CHAIN_CURVE_NAMES), 0))
    args = (excitation, table_step, table_start, work, settings, out, no_curves)
    below, above = speed_low, math.nan
    for i in range(scan_points):
        speed = speed_low * (speed_high / speed_low) ** (i / (scan_points - 1))
        jumped, ok = _jumps(*args, speed)
        if not ok:
            return math.nan, JUMP_RUN_FAILED
        if jumped:
            if i == 0:
                return speed, JUMP_AT_LOWER_BOUND
            above = speed
            break
        below = speed
    if math.isnan(above):
        return math.nan, JUMP_NONE_IN_RANGE
    while above - below > tolerance * above:
        middle = 0.5 * (below + above)
        jumped, ok = _jumps(*args, middle)
        if not ok:
            return math.nan, JUMP_RUN_FAILED
        if jumped:
            above = middle
        else:
            below = middle
    return above, JUMP_FOUND
