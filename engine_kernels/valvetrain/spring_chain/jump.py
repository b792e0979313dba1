"""Valve jump with the multi-mass spring [V4]: the lowest camshaft speed at which it separates.

The shared search of :mod:`engine_kernels.valvetrain.jump_search` (a geometric scan, then
bisection) with each speed one run of
:func:`engine_kernels.valvetrain.spring_chain.one_case.spring_chain_response`, so surge can
bring the jump below the lumped model's speed.
"""

from __future__ import annotations

import numpy as np

from engine_kernels._jit import jit
from engine_kernels.valvetrain.jump_search import S_SPEED, search_next, search_start
from engine_kernels.valvetrain.spring_chain.layout import (
    CHAIN_CURVE_NAMES,
    CHAIN_OUTPUT_NAMES,
    CO_JUMP_DURATION,
    CO_STATUS,
    SC_SPEED,
)
from engine_kernels.valvetrain.spring_chain.one_case import spring_chain_response
from engine_kernels.valvetrain.valve.layout import STATUS_OK


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
    :mod:`engine_kernels.valvetrain.jump_search`. params : 1-D array ``SC_*`` row (its speed
    entry is ignored); the other arguments as in
    :func:`engine_kernels.valvetrain.valve.jump.jump_speed`.
    """
    work = params.copy()
    out = np.empty(len(CHAIN_OUTPUT_NAMES))
    no_curves = np.empty((len(CHAIN_CURVE_NAMES), 0))
    state = search_start(speed_low, speed_high, scan_points, tolerance)
    while True:
        work[SC_SPEED] = state[S_SPEED]
        spring_chain_response(excitation, table_step, table_start, work, settings, out, no_curves)
        separated = out[CO_JUMP_DURATION] > 0.0
        done, speed, code = search_next(state, separated, out[CO_STATUS] == STATUS_OK)
        if done:
            return speed, code
