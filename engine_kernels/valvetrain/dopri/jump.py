"""Valve jump by the adaptive pair: the lowest camshaft speed at which the valve leaves its
drive (physics §4), the shared search of :mod:`engine_kernels.valvetrain.jump_search` driven
by :func:`engine_kernels.valvetrain.dopri.integrate.dopri_response`, so that a study run with
``integrator = "dopri"`` finds its jump speed with the integrator it chose.
"""

from __future__ import annotations

import numpy as np

from engine_kernels._jit import jit
from engine_kernels.valvetrain.dopri.integrate import DEFAULT_MAX_STEPS, dopri_response
from engine_kernels.valvetrain.jump_search import S_SPEED, search_next, search_start
from engine_kernels.valvetrain.valve.layout import (
    O_JUMP_DURATION,
    O_STATUS,
    P_SPEED,
    STATUS_OK,
    VALVE_CURVE_NAMES,
    VALVE_OUTPUT_NAMES,
)


@jit
def dopri_jump_speed(
    excitation,
    table_step,
    table_start,
    grid_step,
    params,
    tolerance,
    speed_low,
    speed_high,
    scan_points,
    search_tolerance,
):
    """Lowest camshaft speed at which the valve separates from the drive, each speed of the
    search one run of :func:`dopri_response`, a jump being ``O_JUMP_DURATION > 0``. Returns
    ``(speed [rad/s], code)`` with the ``JUMP_*`` codes of
    :mod:`engine_kernels.valvetrain.jump_search`.

    excitation, table_step, table_start, grid_step, tolerance : as in :func:`dopri_response`
                 (table [m, m/rad, m/rad²], spacing [rad], start [rad], grid [rad], lift
                 tolerance per step [m]).
    params      : 1-D array  Parameter row (``P_*``); its speed entry is ignored.
    speed_low   : float      Lower end of the search [rad/s]; speed_high: upper end [rad/s].
    scan_points : int        Number of scan speeds (≥ 2).
    search_tolerance : float Relative bracket width at which bisection stops [-].
    """
    work = params.copy()
    out = np.empty(len(VALVE_OUTPUT_NAMES))
    no_curves = np.empty((len(VALVE_CURVE_NAMES), 0))
    state = search_start(speed_low, speed_high, scan_points, search_tolerance)
    while True:
        work[P_SPEED] = state[S_SPEED]
        dopri_response(
            excitation,
            table_step,
            table_start,
            grid_step,
            work,
            tolerance,
            0.0,
            DEFAULT_MAX_STEPS,
            out,
            no_curves,
        )
        separated = out[O_JUMP_DURATION] > 0.0
        done, speed, code = search_next(state, separated, out[O_STATUS] == STATUS_OK)
        if done:
            return speed, code
