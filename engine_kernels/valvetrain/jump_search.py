"""The jump-speed search shared by the valve models (physics §4): the lowest camshaft speed at
which the valve leaves its drive.

A scan over ``scan_points`` geometrically spaced speeds from ``speed_low`` to ``speed_high``
for the first one with a jump, then bisection between it and the previous scan speed until
the bracket is narrower than ``tolerance`` times its upper end. The search is written once,
as a step function over a small state row, and each model drives it with its own response
kernel (:mod:`.valve.jump` for [V2], :mod:`.spring_chain.jump` for [V4]): no kernel is passed
as an argument, so every function here compiles once and is cached like any other.

A driver loops::

    state = search_start(speed_low, speed_high, scan_points, tolerance)
    while True:
        run the model at state[S_SPEED]
        done, speed, code = search_next(state, separated, finished_ok)
        if done:
            return speed, code
"""

from __future__ import annotations

import math

import numpy as np

from engine_kernels._jit import jit

JUMP_FOUND = 0
JUMP_NONE_IN_RANGE = 1
JUMP_AT_LOWER_BOUND = 2
JUMP_RUN_FAILED = 3
JUMP_STATUS_NAMES = ("found", "none_in_range", "at_lower_bound", "run_failed")

# the state row: bracket [rad/s], scan range [rad/s], scan index (-1 once bisecting), the
# number of scan speeds, the relative tolerance [-] and the speed to run next [rad/s]
S_BELOW, S_ABOVE, S_LOW, S_HIGH, S_INDEX, S_POINTS, S_TOLERANCE, S_SPEED = range(8)
N_STATE = 8
BISECTING = -1.0


@jit
def _scan_speed(state, i):
    """The i-th of the geometrically spaced scan speeds [rad/s]."""
    low = state[S_LOW]
    return low * (state[S_HIGH] / low) ** (i / (state[S_POINTS] - 1.0))


@jit
def search_start(speed_low, speed_high, scan_points, tolerance):
    """A new search's state row; the first speed to run is ``state[S_SPEED]`` (= speed_low).

    speed_low, speed_high : float  The scanned range [rad/s].
    scan_points           : int    Number of scan speeds (≥ 2).
    tolerance             : float  Relative bracket width at which bisection stops [-].
    """
    state = np.empty(N_STATE)
    state[S_BELOW] = speed_low
    state[S_ABOVE] = math.nan
    state[S_LOW] = speed_low
    state[S_HIGH] = speed_high
    state[S_INDEX] = 0.0
    state[S_POINTS] = scan_points
    state[S_TOLERANCE] = tolerance
    state[S_SPEED] = _scan_speed(state, 0.0)
    return state


@jit
def search_next(state, separated, finished_ok):
    """Take the outcome of the run at ``state[S_SPEED]``; return ``(done, speed [rad/s],
    code)``. Not done: the next speed to run is ``state[S_SPEED]``. Done: ``speed`` is the
    lowest speed found to separate (NaN if none) and ``code`` one of ``JUMP_FOUND``,
    ``JUMP_NONE_IN_RANGE``, ``JUMP_AT_LOWER_BOUND`` (separates already at ``speed_low``) or
    ``JUMP_RUN_FAILED`` (a run did not finish normally)."""
    if not finished_ok:
        return True, math.nan, JUMP_RUN_FAILED
    speed = state[S_SPEED]
    i = state[S_INDEX]
    if i != BISECTING:
        if separated:
            if i == 0.0:
                return True, speed, JUMP_AT_LOWER_BOUND
            state[S_ABOVE] = speed
            state[S_INDEX] = BISECTING
        else:
            state[S_BELOW] = speed
            if i + 1.0 >= state[S_POINTS]:
                return True, math.nan, JUMP_NONE_IN_RANGE
            state[S_INDEX] = i + 1.0
            state[S_SPEED] = _scan_speed(state, i + 1.0)
            return False, state[S_SPEED], JUMP_FOUND
    elif separated:
        state[S_ABOVE] = speed
    else:
        state[S_BELOW] = speed
    below, above = state[S_BELOW], state[S_ABOVE]
    if above - below > state[S_TOLERANCE] * above:
        state[S_SPEED] = 0.5 * (below + above)
        return False, state[S_SPEED], JUMP_FOUND
    return True, above, JUMP_FOUND
