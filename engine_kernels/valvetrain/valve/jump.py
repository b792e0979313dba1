"""Valve jump: the lowest camshaft speed at which the valve leaves its drive (physics §4).

A scan over speeds followed by bisection, each speed one run of
:func:`engine_kernels.valvetrain.valve.one_case.valve_response`.
"""

from __future__ import annotations

import math

import numpy as np

from engine_kernels._jit import jit
from engine_kernels.valvetrain.valve.layout import (
    O_JUMP_DURATION,
    O_STATUS,
    P_SPEED,
    STATUS_OK,
    VALVE_CURVE_NAMES,
    VALVE_OUTPUT_NAMES,
)
from engine_kernels.valvetrain.valve.one_case import valve_response

JUMP_FOUND = 0
JUMP_NONE_IN_RANGE = 1
JUMP_AT_LOWER_BOUND = 2
JUMP_RUN_FAILED = 3
JUMP_STATUS_NAMES = ("found", "none_in_range", "at_lower_bound", "run_failed")


@jit
def jump_speed(
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
    """Lowest camshaft speed at which the valve separates from the drive (physics §4).

    Scans ``scan_points`` geometrically spaced speeds from ``speed_low`` to ``speed_high``
    for the first one with a jump (``O_JUMP_DURATION > 0``), then bisects between it and
    the previous scan point until the bracket is narrower than ``tolerance`` times its
    upper end. Returns ``(speed [rad/s], code)`` with code ``JUMP_FOUND``,
    ``JUMP_NONE_IN_RANGE`` (speed NaN), ``JUMP_AT_LOWER_BOUND`` (separates already at
    ``speed_low``) or ``JUMP_RUN_FAILED`` (a run did not finish with ``STATUS_OK``).

    params      : 1-D array  Parameter row (``P_*``); its speed entry is ignored.
    speed_low   : float      Lower end of the search [rad/s].
    speed_high  : float      Upper end of the search [rad/s].
    scan_points : int        Number of scan speeds (≥ 2).
    tolerance   : float      Relative bracket width at which bisection stops [-].
    Other arguments as in :func:`valve_response`.
    """
    work = params.copy()
    out = np.empty(len(VALVE_OUTPUT_NAMES))
    no_curves = np.empty((len(VALVE_CURVE_NAMES), 0))
    below = speed_low
    above = math.nan
    for i in range(scan_points):
        speed = speed_low * (speed_high / speed_low) ** (i / (scan_points - 1))
        work[P_SPEED] = speed
        valve_response(excitation, table_step, table_start, work, settings, out, no_curves)
        if out[O_STATUS] != STATUS_OK:
            return math.nan, JUMP_RUN_FAILED
        if out[O_JUMP_DURATION] > 0.0:
            if i == 0:
                return speed, JUMP_AT_LOWER_BOUND
            above = speed
            break
        below = speed
    if math.isnan(above):
        return math.nan, JUMP_NONE_IN_RANGE
    while above - below > tolerance * above:
        work[P_SPEED] = 0.5 * (below + above)
        valve_response(excitation, table_step, table_start, work, settings, out, no_curves)
        if out[O_STATUS] != STATUS_OK:
            return math.nan, JUMP_RUN_FAILED
        if out[O_JUMP_DURATION] > 0.0:
            above = work[P_SPEED]
        else:
            below = work[P_SPEED]
    return above, JUMP_FOUND
