"""Valve dynamics [V2] for blocks of cases in SIMD lanes (SPEC §4, STYLE "Hot integrators").

Same model, plain fixed-step RK4, stability guard, observations and outputs as
:func:`engine_kernels.valve.valve_response` (no switch location, no curves), with the same
arithmetic, so both give the same numbers, ``LANES`` cases at a time. The cases are grouped
by the RK4 sub-step count the stability guard gives each of them, so a block steps all its
lanes together with one count while each case keeps exactly its own: a case's results do not
depend on which other cases share its block. Every grid step reads the shared excitation once
and then runs loops over the lanes: one observes the grid point, one takes the RK4 step (two
loops run faster than one fused loop, which runs out of registers). Sub-stepped blocks also
follow the seat phase at every sub-step point, where a landing on a stiff seat cannot hide.
Only when some lane's seat phase changed (first closure, a bounce) does a scalar loop record it.

Per-lane data (coefficients per unit mass, state, observations) are rows of one flat array,
row ``r`` of lane ``l`` at ``r·LANES + l``: with compile-time row offsets the compiler can
prove that rows never overlap. What else keeps the lane loops vectorised (checked in
tests/engine_kernels/test_valve_lanes.py): every helper called in them is inlined by Numba
(``jit_inline``) and takes scalars or this array but calls nothing itself (Numba's builtin
``max``/``min`` are calls: ``valve_model.larger`` and friends are selects), and no row is
loaded under a condition. Blocks run in a ``prange``, in an order that spreads the costly
(sub-stepped) ones over the threads; each block writes only its own cases' output rows.

Precision follows the excitation table: a float64 table gives the numbers of the one-case
kernel; a float32 table runs the lanes in single precision, twice the lanes per vector (8
instead of 4 per AVX2 register, 16 instead of 8 per AVX-512 one; the stability guard, the
coefficients and the outputs stay float64; sub-steps interpolate the excitation in float64).
At the default 0.5° step the single-precision round-off is orders of magnitude below the RK4
error (tests/engine_kernels/test_valve_lanes.py).
"""

from __future__ import annotations

import numpy as np

from engine_kernels._jit import batch, jit, jit_inline, prange
from engine_kernels.valve import ERROR_ORDER_DIVISOR, rk4_valve_step
from engine_kernels.valve_guard import error_estimate_is_stable, prepare_case
from engine_kernels.valve_model import (
    O_ERROR_ESTIMATE,
    P_INITIAL_LIFT,
    P_INITIAL_VELOCITY,
    P_MASS,
    S_ESTIMATE_ERROR,
    drive_push,
    excitation_lift_slope,
    specific_acceleration,
    specific_coefficients,
    specific_forces,
)
from engine_kernels.valve_observations import (
    ENERGY_INTERVAL,
    N_STATS,
    TRANSITION_BAND,
    finish_observations,
    nose_position,
    observe_closure,
    observe_energy,
    observe_valve,
    record_closure_events,
    start_observations,
)

LANES = 32

# Rows of the flat per-block array, followed by the N_STATS observation rows. Coefficients
# are per unit mass (see engine_kernels.valve_model.specific_coefficients).
_K = 0
_B = 1
_KS = 2
_PS0 = 3
_KZ = 4
_BZ = 5
_GAMMA = 6
_DEPTH = 7
_SPEED = 8
_B_SPEED = 9
_BAND = 10
_MASS = 11
_TAU = 12
_HALF_TAU = 13
_SIXTH_TAU = 14
_TIME_STEP = 15
_LIFT = 16
_VELOCITY = 17
_ACC = 18
_PREV_LIFT = 19
_PREV_VELOCITY = 20
_DIFFERENCE = 21
_ANGLE = 22
N_LANE_ROWS = 23
_STATS = N_LANE_ROWS * LANES


@jit_inline
def _lane_point(data, l, drive_lift, slope):
    """State of lane ``l`` and its forces at a point of excitation Y [m], Y' [m/rad].

    Returns lift [m], velocity [m/s], drive and seat forces per unit mass before clipping
    [N/kg] (``specific_forces``) and the acceleration [m/s²] (``specific_acceleration``).
    """
    lift = data[_LIFT * LANES + l]
    velocity = data[_VELOCITY * LANES + l]
    drive, seat, acc = _lane_forces(data, l, lift, velocity, drive_lift, slope)
    return lift, velocity, drive, seat, acc


@jit_inline
def _lane_forces(data, l, lift, velocity, drive_lift, slope):
    """Forces and acceleration of lane ``l`` in state (lift [m], velocity [m/s]) (_lane_point)."""
    push = drive_push(drive_lift, slope, data[_K * LANES + l], data[_B_SPEED * LANES + l])
    drive, seat = specific_forces(
        lift,
        velocity,
        push,
        data[_K * LANES + l],
        data[_B * LANES + l],
        data[_PS0 * LANES + l],
        data[_KZ * LANES + l],
        data[_BZ * LANES + l],
    )
    acc = specific_acceleration(
        lift,
        velocity,
        drive,
        seat,
        data[_KS * LANES + l],
        data[_PS0 * LANES + l],
        data[_GAMMA * LANES + l],
        data[_DEPTH * LANES + l],
    )
    return drive, seat, acc


@jit_inline
def _lane_step(data, l, lift, velocity, acc, ym, sm, y1, s1):
    """RK4 step of lane ``l`` from its first-stage ``acc``; excitation Y [m], Y' [m/rad]."""
    k = data[_K * LANES + l]
    b_speed = data[_B_SPEED * LANES + l]
    lift, velocity = rk4_valve_step(
        lift,
        velocity,
        acc,
        data[_TAU * LANES + l],
        data[_HALF_TAU * LANES + l],
        data[_SIXTH_TAU * LANES + l],
        drive_push(ym, sm, k, b_speed),
        drive_push(y1, s1, k, b_speed),
        k,
        data[_B * LANES + l],
        data[_KS * LANES + l],
        data[_PS0 * LANES + l],
        data[_KZ * LANES + l],
        data[_BZ * LANES + l],
        data[_GAMMA * LANES + l],
        data[_DEPTH * LANES + l],
    )
    data[_LIFT * LANES + l] = lift
    data[_VELOCITY * LANES + l] = velocity


@jit
def _start_lanes(data, angle, drive_lift, slope):
    """First grid point of every lane: acceleration into ``_ACC``, observations started."""
    for l in range(LANES):
        lift, velocity, drive, seat, acc = _lane_point(data, l, drive_lift, slope)
        data[_ACC * LANES + l] = acc
        start_observations(
            data,
            _STATS + l,
            LANES,
            angle,
            lift,
            velocity,
            acc,
            drive_lift,
            data[_SPEED * LANES + l] * slope,
            drive,
            seat,
            data[_DEPTH * LANES + l],
        )


@jit
def _observe_lanes(data, angle, drive_lift, slope, past_nose):
    """Grid point of every lane: acceleration into ``_ACC``, observations updated.

    Returns True if the seat phase of some lane changed (``record_closure_events``): a flag,
    not a count, so no 64-bit integer in the loop halves the float32 vector width.
    """
    changed = False
    for l in range(LANES):
        lift, velocity, drive, seat, acc = _lane_point(data, l, drive_lift, slope)
        data[_ACC * LANES + l] = acc
        event = observe_valve(
            data,
            _STATS + l,
            LANES,
            angle,
            lift,
            velocity,
            acc,
            drive_lift,
            data[_SPEED * LANES + l] * slope,
            drive,
            seat,
            data[_DEPTH * LANES + l],
            data[_BAND * LANES + l],
            past_nose,
        )
        changed |= event
    return changed


@jit
def _record_events_lanes(data, prev_drive_lift, prev_slope):
    """Record closure and bounce events of every lane (scalar; only after an event).

    prev_drive_lift, prev_slope : Y [m] and Y' [m/rad] at the previous (sub-)step point,
    where the state in ``_PREV_*`` was.
    """
    for l in range(LANES):
        lift = data[_PREV_LIFT * LANES + l]
        velocity = data[_PREV_VELOCITY * LANES + l]
        _, _, acc = _lane_forces(data, l, lift, velocity, prev_drive_lift, prev_slope)
        record_closure_events(
            data, _STATS + l, LANES, lift, velocity, acc, data[_DEPTH * LANES + l]
        )


@jit
def _energy_lanes(data, drive_lift, slope):
    """Energy checks of every lane at a grid point (``observe_energy``)."""
    for l in range(LANES):
        lift, velocity, drive, _, _ = _lane_point(data, l, drive_lift, slope)
        observe_energy(
            data,
            _STATS + l,
            LANES,
            data[_TIME_STEP * LANES + l],
            lift,
            velocity,
            drive_lift,
            data[_SPEED * LANES + l] * slope,
            drive,
            data[_K * LANES + l],
            data[_KS * LANES + l],
            data[_PS0 * LANES + l],
            data[_KZ * LANES + l],
            data[_DEPTH * LANES + l],
        )


@jit
def _step_lanes(data, ym, sm, y1, s1):
    """RK4 grid step of every lane from the acceleration in ``_ACC``.

    Keeps the state it starts from in ``_PREV_*`` (for ``record_closure_events``).
    """
    for l in range(LANES):
        lift = data[_LIFT * LANES + l]
        velocity = data[_VELOCITY * LANES + l]
        data[_PREV_LIFT * LANES + l] = lift
        data[_PREV_VELOCITY * LANES + l] = velocity
        _lane_step(data, l, lift, velocity, data[_ACC * LANES + l], ym, sm, y1, s1)


@jit
def _substep_lanes(data, ya, sa, ym, sm, yb, sb):
    """RK4 sub-step of every lane; excitation at its start, middle and end.

    Keeps the state it starts from in ``_PREV_*`` (for ``record_closure_events``).
    """
    for l in range(LANES):
        lift, velocity, _, _, acc = _lane_point(data, l, ya, sa)
        data[_PREV_LIFT * LANES + l] = lift
        data[_PREV_VELOCITY * LANES + l] = velocity
        _lane_step(data, l, lift, velocity, acc, ym, sm, yb, sb)


@jit
def _observe_seat_lanes(data, past_nose):
    """Seat phase of every lane at an RK4 sub-step point inside a grid step.

    A landing on a stiff seat can begin and end between grid points, never between sub-step
    points (see ``engine_kernels.valve._observe_substep``). ``past_nose``: the point is at or
    past the cam's nose.
    Returns True if the seat phase of some lane changed (``observe_closure``).
    """
    changed = False
    for l in range(LANES):
        changed |= observe_closure(
            data,
            _STATS + l,
            LANES,
            data[_LIFT * LANES + l],
            data[_DEPTH * LANES + l],
            past_nose,
        )
    return changed


@jit
def _record_lanes(data, trace, n, compare):
    """Record the lift of every lane at grid point ``n`` or compare with a finer trace."""
    for l in range(LANES):
        lift = data[_LIFT * LANES + l]
        if compare:
            difference = abs(lift - trace[2 * n, l])
            data[_DIFFERENCE * LANES + l] = max(data[_DIFFERENCE * LANES + l], difference)
        else:
            trace[n, l] = lift


@jit
def _lane_pass(excitation, table_step, table_start, half, substeps, params, cases, data, trace):
    """Integrate all lanes of a block at RK4 grid step ``2·half·table_step``.

    substeps : int  RK4 sub-steps per grid step, the same for every lane of the block.
    cases    : 1-D int64  Parameter rows of the lanes (their initial state).
    Records the lift per grid point in ``trace`` (grid point × lane) when ``half`` is 1 or,
    when it is 2, keeps the largest difference from that trace in ``_DIFFERENCE``.
    """
    n_steps = (excitation.shape[1] - 1) // (2 * half)
    grid_step = 2.0 * half * table_step
    record = trace.shape[0] > 0
    compare = half == 2
    for l in range(LANES):
        speed = data[_SPEED * LANES + l]
        tau = grid_step / speed / substeps
        data[_TAU * LANES + l] = tau
        data[_HALF_TAU * LANES + l] = 0.5 * tau
        data[_SIXTH_TAU * LANES + l] = tau / 6.0
        data[_TIME_STEP * LANES + l] = grid_step / speed
        data[_LIFT * LANES + l] = params[cases[l], P_INITIAL_LIFT]
        data[_VELOCITY * LANES + l] = params[cases[l], P_INITIAL_VELOCITY]
        data[_DIFFERENCE * LANES + l] = 0.0
    prev_drive_lift, prev_slope = excitation[0, 0], excitation[1, 0]  # read once n > 0
    nose = nose_position(excitation)
    for n in range(n_steps + 1):
        node = 2 * half * n
        drive_lift = excitation[0, node]
        slope = excitation[1, node]
        data[_ANGLE * LANES] = table_start + n * grid_step
        angle = data[_ANGLE * LANES]  # in the block's precision
        if record:
            _record_lanes(data, trace, n, compare)
        if n == 0:
            _start_lanes(data, angle, drive_lift, slope)
        elif _observe_lanes(data, angle, drive_lift, slope, node >= nose):
            _record_events_lanes(data, prev_drive_lift, prev_slope)
        if n % ENERGY_INTERVAL == 0 or n == n_steps:
            _energy_lanes(data, drive_lift, slope)
        if n == n_steps:
            break
        prev_drive_lift, prev_slope = drive_lift, slope
        if substeps == 1:
            _step_lanes(
                data,
                excitation[0, node + half],
                excitation[1, node + half],
                excitation[0, node + 2 * half],
                excitation[1, node + 2 * half],
            )
            continue
        for j in range(substeps):
            position = node + 2.0 * half * j / substeps
            ya, sa = excitation_lift_slope(excitation, table_step, position)
            if j > 0:
                if _observe_seat_lanes(data, position >= nose):
                    _record_events_lanes(data, prev_drive_lift, prev_slope)
                prev_drive_lift, prev_slope = ya, sa
            ym, sm = excitation_lift_slope(
                excitation, table_step, node + 2.0 * half * (j + 0.5) / substeps
            )
            yb, sb = excitation_lift_slope(
                excitation, table_step, node + 2.0 * half * (j + 1) / substeps
            )
            _substep_lanes(data, ya, sa, ym, sm, yb, sb)


@jit
def _block_data(excitation, params, cases):
    """Per-lane rows of a block, in the precision of the excitation table.

    cases : 1-D int64  Parameter row of each of the ``LANES`` lanes.
    """
    data = np.empty((N_LANE_ROWS + N_STATS) * LANES, excitation.dtype)
    for l in range(LANES):
        k, b, ks, ps0, kz, bz, gamma, depth, speed, b_speed = specific_coefficients(
            params[cases[l]]
        )
        data[_K * LANES + l] = k
        data[_B * LANES + l] = b
        data[_KS * LANES + l] = ks
        data[_PS0 * LANES + l] = ps0
        data[_KZ * LANES + l] = kz
        data[_BZ * LANES + l] = bz
        data[_GAMMA * LANES + l] = gamma
        data[_DEPTH * LANES + l] = depth
        data[_SPEED * LANES + l] = speed
        data[_B_SPEED * LANES + l] = b_speed
        data[_BAND * LANES + l] = TRANSITION_BAND * ps0
        data[_MASS * LANES + l] = params[cases[l], P_MASS]
    return data


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
    data = _block_data(excitation, rows, cases)
    lanes = np.empty((trace.shape[0], LANES))
    _lane_pass(excitation, table_step, table_start, 1, substeps, rows, cases, data, lanes)
    trace[:] = lanes[:, 0]


@jit
def _lane_block(excitation, table_step, table_start, params, settings, block, substeps, out):
    """Integrate and report one block: up to ``LANES`` cases with the same sub-step count.

    block : 1-D int64  Row indices of the block's cases in ``params`` and ``out``.
    Lanes past the block's cases repeat its first case; their results are not written.
    """
    count = block.shape[0]
    cases = np.empty(LANES, dtype=np.int64)
    for l in range(LANES):
        cases[l] = block[l if l < count else 0]
    data = _block_data(excitation, params, cases)
    estimate = settings[S_ESTIMATE_ERROR] != 0 and excitation.shape[1] >= 5
    trace = np.empty(((excitation.shape[1] - 1) // 2 + 1 if estimate else 0, LANES))
    _lane_pass(excitation, table_step, table_start, 1, substeps, params, cases, data, trace)
    for l in range(count):
        finish_observations(
            data,
            _STATS + l,
            LANES,
            2.0 * table_step,
            data[_LIFT * LANES + l],
            data[_VELOCITY * LANES + l],
            data[_MASS * LANES + l],
            data[_PS0 * LANES + l],
            data[_DEPTH * LANES + l],
            out[cases[l]],
        )
    if not estimate:
        return
    _lane_pass(excitation, table_step, table_start, 2, substeps, params, cases, data, trace)
    for l in range(count):
        if error_estimate_is_stable(params[cases[l]], table_step, substeps, settings):
            out[cases[l], O_ERROR_ESTIMATE] = data[_DIFFERENCE * LANES + l] / ERROR_ORDER_DIVISOR


@jit
def block_starts(substeps, order):
    """Split cases sorted by sub-step count into blocks of ≤ ``LANES`` with one count each.

    substeps : 1-D int64  Sub-steps per case from the stability guard (0: not integrated).
    order    : 1-D int64  Case indices sorted by ``substeps``.
    Returns the block boundaries as positions in ``order`` (block b is
    ``order[starts[b]:starts[b + 1]]``); cases with 0 sub-steps are left out.
    """
    n = order.shape[0]
    starts = np.empty(n + 1, dtype=np.int64)
    blocks = 0
    i = 0
    while i < n and substeps[order[i]] == 0:
        i += 1
    while i < n:
        starts[blocks] = i
        blocks += 1
        count = substeps[order[i]]
        end = min(i + LANES, n)
        i += 1
        while i < end and substeps[order[i]] == count:
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


@batch
def valve_response_lanes(excitation, table_step, table_start, params, settings, out):
    """Valve dynamics of many cases, ``LANES`` cases per SIMD block, blocks in a prange.

    Same arguments and outputs as :func:`engine_kernels.valve.valve_response_batch`
    (``settings[S_SWITCH_AWARE]`` is ignored: this kernel is plain fixed-step RK4).
    Reference: SPEC §4; STYLE "Hot integrators process a block of cases in SIMD lanes".
    """
    n_cases = params.shape[0]
    substeps = np.empty(n_cases, dtype=np.int64)
    for i in prange(n_cases):
        substeps[i] = prepare_case(excitation, table_step, params[i], settings, out[i])
    order = np.argsort(substeps, kind="mergesort")
    starts = block_starts(substeps, order)
    schedule = spread_order(starts.shape[0] - 1)
    for i in prange(schedule.shape[0]):
        b = schedule[i]
        block = order[starts[b] : starts[b + 1]]
        _lane_block(
            excitation, table_step, table_start, params, settings, block, substeps[block[0]], out
        )
