"""Valve jump, single-mass model [V2]: the lowest camshaft speed at which the valve leaves its
drive (physics §4), the shared search of :mod:`engine_kernels.valvetrain.jump_search` driven
by :func:`engine_kernels.valvetrain.valve.one_case.valve_response`.
"""

from __future__ import annotations

import numpy as np

from engine_kernels._jit import jit
from engine_kernels.valvetrain.jump_search import S_SPEED, search_next, search_start
from engine_kernels.valvetrain.valve.layout import (
    O_JUMP_DURATION,
    O_STATUS,
    P_SPEED,
    STATUS_OK,
    VALVE_CURVE_NAMES,
    VALVE_OUTPUT_NAMES,
)
from engine_kernels.valvetrain.valve.one_case import valve_response


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
    """Lowest camshaft speed at which the valve separates from the drive (physics §4): the
    search of :mod:`engine_kernels.valvetrain.jump_search`, each speed one run of
    :func:`valve_response`, a jump being ``O_JUMP_DURATION > 0``. Returns ``(speed [rad/s],
    code)`` with the codes ``JUMP_*`` of that module.

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
    state = search_start(speed_low, speed_high, scan_points, tolerance)
    while True:
        work[P_SPEED] = state[S_SPEED]
        valve_response(excitation, table_step, table_start, work, settings, out, no_curves)
        separated = out[O_JUMP_DURATION] > 0.0
        done, speed, code = search_next(state, separated, out[O_STATUS] == STATUS_OK)
        if done:
            return speed, code
