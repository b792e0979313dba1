"""Valve dynamics [V2] of many cases in SIMD blocks: the lane batch drivers (physics §4).

:func:`valve_response_lanes` gives the results of
:func:`engine_kernels.valvetrain.valve.one_case.valve_response_batch` (plain RK4, no curves),
``LANES`` cases per block stepped together by :mod:`engine_kernels.valvetrain.valve.lanes`, about
4× more cases per CPU-second at the physics §9 step. The cases are grouped by the RK4 sub-step
count the stability guard gives each of them, so a block steps all its lanes together with
one count while each case keeps exactly its own: a case's results do not depend on which
other cases share its block. Blocks run in a ``prange``, in an order that spreads the costly
(sub-stepped) ones over the threads; each block writes only its own cases' output rows.
"""

from __future__ import annotations

import numpy as np

from engine_kernels._jit import batch, jit, prange
from engine_kernels.valvetrain.valve.guard import prepare_case
from engine_kernels.valvetrain.valve.lanes import (
    LANES,
    N_LANE_ROWS,
    R_DIFFERENCE,
    R_LIFT,
    R_VELOCITY,
    lane_pass,
)
from engine_kernels.valvetrain.valve.layout import O_ERROR_ESTIMATE, S_ESTIMATE_ERROR
from engine_kernels.valvetrain.valve.model import valve_coefficients
from engine_kernels.valvetrain.valve.observations import finish_observations


@jit
def block_data(excitation, params, cases):
    """Per-lane rows of a block, in the precision of the excitation table.

    cases : 1-D int64  Parameter row of each of the ``LANES`` lanes (their coefficients
                       ``K_*`` are written, ``valve_coefficients``).
    """
    data = np.empty(N_LANE_ROWS * LANES, excitation.dtype)
    for l in range(LANES):
        valve_coefficients(params[cases[l]], data, l, LANES)
    return data


@jit
def finish_lanes(data, count, step_angle, cases, out):
    """Write the ``O_*`` outputs of the first ``count`` lanes (``finish_observations``).

    step_angle : float      Grid step Δθ [rad].
    cases      : 1-D int64  Output row of each lane.
    """
    for l in range(count):
        lift = data[R_LIFT * LANES + l]
        velocity = data[R_VELOCITY * LANES + l]
        finish_observations(data, l, LANES, step_angle, lift, velocity, out[cases[l]])


@jit
def lane_difference(data, l):
    """Largest lift difference [m] of lane ``l`` from the step-halving pass (``lane_pass``)."""
    return data[R_DIFFERENCE * LANES + l]


@jit
def lift_trace_lanes(excitation, table_step, table_start, params, settings, trace):
    """Valve lift [m] of one case at every RK4 grid point, integrated in the lane kernel.

    params : 1-D array  One ``P_*`` row (every lane of the block integrates it).
    trace  : 1-D array  Output, one value per grid point (``(excitation.shape[1] − 1)//2 + 1``);
                        NaN throughout if the stability guard refuses the case.
    For accuracy studies of the single-precision lanes, whose trajectory differs from the
    one-case kernel's by round-off.
    """
    out = np.empty(O_ERROR_ESTIMATE + 1)
    substeps = prepare_case(excitation, table_step, params, settings, out)
    if substeps == 0:
        trace[:] = np.nan
        return
    rows = params.reshape((1, params.shape[0]))
    cases = np.zeros(LANES, dtype=np.int64)
    data = block_data(excitation, rows, cases)
    lanes = np.empty((trace.shape[0], LANES))
    lane_pass(excitation, table_step, table_start, False, substeps, rows, cases, data, lanes)
    trace[:] = lanes[:, 0]


@jit
def block_cases(block):
    """Parameter rows of the ``LANES`` lanes of a block: its cases, then its first case again
    in the lanes past them (their results are not written)."""
    count = block.shape[0]
    cases = np.empty(LANES, dtype=np.int64)
    for l in range(LANES):
        cases[l] = block[l if l < count else 0]
    return cases


@jit
def _lane_block(excitation, table_step, table_start, params, settings, block, substeps, out):
    """Integrate and report one block: up to ``LANES`` cases with the same sub-step count.

    block : 1-D int64  Row indices of the block's cases in ``params`` and ``out``.
    Lanes past the block's cases repeat its first case; their results are not written.
    """
    count = block.shape[0]
    cases = block_cases(block)
    data = block_data(excitation, params, cases)
    estimate = settings[S_ESTIMATE_ERROR] != 0 and excitation.shape[1] >= 5
    trace = np.empty(((excitation.shape[1] - 1) // 2 + 1 if estimate else 0, LANES))
    lane_pass(excitation, table_step, table_start, False, substeps, params, cases, data, trace)
    finish_lanes(data, count, 2.0 * table_step, cases, out)
    if not estimate:
        return
    lane_pass(excitation, table_step, table_start, True, 2 * substeps, params, cases, data, trace)
    for l in range(count):
        out[cases[l], O_ERROR_ESTIMATE] = lane_difference(data, l)


@jit
def block_starts(keys, order):
    """Split cases sorted by key into blocks of ≤ ``LANES`` with one key each.

    keys  : 1-D int64  Block key per case: its sub-step count here, (N, sub-steps) for the
                       multi-mass spring; 0: not integrated.
    order : 1-D int64  Case indices sorted by ``keys``.
    Returns the block boundaries as positions in ``order`` (block b is
    ``order[starts[b]:starts[b + 1]]``); cases with key 0 are left out.
    """
    n = order.shape[0]
    starts = np.empty(n + 1, dtype=np.int64)
    blocks = 0
    i = 0
    while i < n and keys[order[i]] == 0:
        i += 1
    while i < n:
        starts[blocks] = i
        blocks += 1
        key = keys[order[i]]
        end = min(i + LANES, n)
        i += 1
        while i < end and keys[order[i]] == key:
            i += 1
    starts[blocks] = n
    return starts[: blocks + 1]


@jit
def spread_order(n):
    """The integers 0…n−1 in bit-reversed (van der Corput) order.

    Every contiguous run of the result samples the whole range about evenly, so when blocks
    sorted by cost are run in this order, any contiguous share of a ``prange`` (Numba gives
    each thread one) gets a fair mix of cheap and costly blocks.
    Reference: Niederreiter, *Random Number Generation and Quasi-Monte Carlo Methods*, §3.1.
    """
    bits = 0
    while (1 << bits) < n:
        bits += 1
    order = np.empty(n, dtype=np.int64)
    count = 0
    for i in range(1 << bits):
        reversed_i = 0
        rest = i
        for _ in range(bits):
            reversed_i = (reversed_i << 1) | (rest & 1)
            rest >>= 1
        if reversed_i < n:
            order[count] = reversed_i
            count += 1
    return order


@jit
def block_schedule(keys):
    """Cases sorted by block key (stable), the block boundaries in that order
    (:func:`block_starts`) and the order to run the blocks in (:func:`spread_order`)."""
    order = np.argsort(keys, kind="mergesort")
    starts = block_starts(keys, order)
    return order, starts, spread_order(starts.shape[0] - 1)


@jit
def scheduled_block(order, starts, schedule, i):
    """The case indices of the ``i``-th block to run (:func:`block_schedule`)."""
    b = schedule[i]
    return order[starts[b] : starts[b + 1]]


@jit
def _lift_block(excitation, table_step, table_start, params, block, substeps, out, lifts):
    """:func:`_lane_block` without the error estimate, keeping each case's lift at every grid
    point in its row of ``lifts``."""
    count = block.shape[0]
    cases = block_cases(block)
    data = block_data(excitation, params, cases)
    trace = np.empty((lifts.shape[1], LANES), excitation.dtype)
    lane_pass(excitation, table_step, table_start, False, substeps, params, cases, data, trace)
    finish_lanes(data, count, 2.0 * table_step, cases, out)
    for l in range(count):
        lifts[cases[l], :] = trace[:, l]


@batch
def valve_lift_lanes(excitation, table_step, table_start, params, settings, out, lifts):
    """:func:`valve_response_lanes` that also keeps each case's lift at every grid point, as
    :func:`engine_kernels.valvetrain.valve.one_case.valve_lift_batch` does one case at a time
    (the same numbers to round-off; ``S_ESTIMATE_ERROR`` is not used).

    lifts : 2-D array  (n_cases, (excitation.shape[1] − 1)//2 + 1) lift y [m] per grid point,
                       NaN where the case is not integrated.
    """
    n_cases = params.shape[0]
    substeps = np.empty(n_cases, dtype=np.int64)
    for i in prange(n_cases):
        substeps[i] = prepare_case(excitation, table_step, params[i], settings, out[i])
        if substeps[i] == 0:
            lifts[i, :] = np.nan
    order, starts, schedule = block_schedule(substeps)
    for i in prange(schedule.shape[0]):
        block = scheduled_block(order, starts, schedule, i)
        _lift_block(
            excitation, table_step, table_start, params, block, substeps[block[0]], out, lifts
        )


@batch
def valve_response_lanes(excitation, table_step, table_start, params, settings, out):
    """Valve dynamics of many cases, ``LANES`` cases per SIMD block, blocks in a prange.

    Same arguments and outputs as :func:`engine_kernels.valvetrain.valve.one_case.valve_response_batch`
    (``settings[S_SWITCH_AWARE]`` is ignored: this kernel is plain fixed-step RK4).
    Reference: physics §4; STYLE "Hot integrators process a block of cases in SIMD lanes".
    """
    n_cases = params.shape[0]
    substeps = np.empty(n_cases, dtype=np.int64)
    for i in prange(n_cases):
        substeps[i] = prepare_case(excitation, table_step, params[i], settings, out[i])
    order, starts, schedule = block_schedule(substeps)
    for i in prange(schedule.shape[0]):
        block = scheduled_block(order, starts, schedule, i)
        _lane_block(
            excitation, table_step, table_start, params, settings, block, substeps[block[0]], out
        )
