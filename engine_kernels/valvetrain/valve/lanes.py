"""Valve dynamics [V2] stepped for a block of cases in SIMD lanes (physics §4, STYLE "Hot integrators").

Same model, plain fixed-step RK4, observations and arithmetic as
:func:`engine_kernels.valvetrain.valve.one_case.valve_response` (no switch location, no curves),
so both give the same numbers, ``LANES`` cases at a time; the batch drivers that group cases
into blocks are in :mod:`engine_kernels.valvetrain.valve.lane_batch`. Every grid step reads the
shared excitation once and then runs loops over the lanes: one observes the grid point, one
takes the RK4 step (two loops run faster than one fused loop, which runs out of registers).
Sub-stepped blocks also follow the seat phase at every sub-step point, where a landing on a
stiff seat cannot hide. Only when some lane's seat phase changed (first closure, a bounce)
does a scalar loop record it.

Per-lane data (the case record of :mod:`engine_kernels.valvetrain.valve.layout`: coefficients per
unit mass, time steps, observations; then the state) are rows of one flat array, row ``r`` of
lane ``l`` at ``r·LANES + l``: with compile-time row offsets the compiler can
prove that rows never overlap. What else keeps the lane loops vectorised (checked in
tests/engine_kernels/test_valve_lanes.py): every helper called in them is inlined by Numba
(``jit_inline``) and takes scalars, this array or the coefficient tuple read from it but
calls nothing itself (Numba's builtin ``max``/``min`` are calls: ``model.larger`` and friends
are selects), and no row is loaded under a condition: a lane reads its coefficients once, at
the top of the loop body (``model.case_coefficients``).

Precision follows the excitation table: a float64 table gives the numbers of the one-case
kernel; a float32 table runs the lanes in single precision, twice the lanes per vector (8
instead of 4 per AVX2 register, 16 instead of 8 per AVX-512 one; the stability guard, the
coefficients and the outputs stay float64; sub-steps interpolate the excitation in float64).
At the default 0.5° step the single-precision round-off is orders of magnitude below the RK4
error (tests/engine_kernels/test_valve_lanes.py).
"""

from __future__ import annotations

from engine_kernels._jit import jit, jit_inline, jit_lanes
from engine_kernels.valvetrain.valve.energy_balance import ENERGY_INTERVAL, observe_energy
from engine_kernels.valvetrain.valve.layout import (
    K_SPEED,
    N_RECORD,
    P_INITIAL_LIFT,
    P_INITIAL_VELOCITY,
)
from engine_kernels.valvetrain.valve.located import jerk_at
from engine_kernels.valvetrain.valve.model import (
    case_coefficients,
    drive_push,
    excitation_lift_slope,
    lash_clip,
    specific_point,
)
from engine_kernels.valvetrain.valve.observations import (
    nose_position,
    observe_closure,
    observe_valve,
    record_closure_events,
    start_observations,
)
from engine_kernels.valvetrain.valve.step import rk4_valve_step, valve_time_steps

LANES = 32

# Rows of the flat per-block array after the case records (coefficients, time steps and
# observations, engine_kernels.valvetrain.valve.layout): the state of each lane, and the angle.
R_LIFT = N_RECORD
R_VELOCITY = N_RECORD + 1
R_ACC = N_RECORD + 2
R_PREV_LIFT = N_RECORD + 3
R_PREV_VELOCITY = N_RECORD + 4
R_DIFFERENCE = N_RECORD + 5
R_ANGLE = N_RECORD + 6
N_LANE_ROWS = N_RECORD + 7


@jit_inline
def _lane_point(data, l, drive_lift, slope):
    """State of lane ``l`` and its forces at a point of excitation Y [m], Y' [m/rad].

    Returns lift [m], velocity [m/s], drive and seat forces per unit mass before clipping
    [N/kg] (``specific_forces``) and the acceleration [m/s²] (``specific_acceleration``).
    """
    lift = data[R_LIFT * LANES + l]
    velocity = data[R_VELOCITY * LANES + l]
    c = case_coefficients(data, l, LANES)
    drive, seat, acc = specific_point(lift, velocity, drive_lift, slope, c)
    return lift, velocity, drive, seat, acc


@jit_inline
def _lane_step(data, l, lift, velocity, acc, ym, sm, y1, s1):
    """RK4 step of lane ``l`` from its first-stage ``acc``; excitation Y [m], Y' [m/rad]."""
    c = case_coefficients(data, l, LANES)
    push_mid = drive_push(ym, sm, c)
    lift, velocity = rk4_valve_step(lift, velocity, acc, push_mid, drive_push(y1, s1, c), c)
    data[R_LIFT * LANES + l] = lift
    data[R_VELOCITY * LANES + l] = velocity


@jit
def _start_lanes(data, angle, drive_lift, slope):
    """First grid point of every lane: acceleration into ``R_ACC``, observations started."""
    for l in range(LANES):
        lift, velocity, drive, seat, acc = _lane_point(data, l, drive_lift, slope)
        data[R_ACC * LANES + l] = acc
        drive_velocity = data[K_SPEED * LANES + l] * slope
        start_observations(
            data, l, LANES, angle, lift, velocity, acc, drive_lift, drive_velocity, drive, seat
        )


@jit_lanes
def _observe_lanes(data, angle, drive_lift, slope, past_nose):
    """Grid point of every lane: acceleration into ``R_ACC``, observations updated.

    Returns True if the seat phase of some lane changed (``record_closure_events``): a flag,
    not a count, so no 64-bit integer in the loop halves the float32 vector width.
    """
    changed = False
    for l in range(LANES):
        lift, velocity, drive, seat, acc = _lane_point(data, l, drive_lift, slope)
        data[R_ACC * LANES + l] = acc
        event = observe_valve(
            data,
            l,
            LANES,
            angle,
            lift,
            velocity,
            acc,
            drive_lift,
            data[K_SPEED * LANES + l] * slope,
            drive,
            seat,
            past_nose,
        )
        changed |= event
    return changed


@jit
def _record_events_lanes(data, excitation, table_step, prev_position):
    """Record closure and bounce events of every lane (scalar; only after an event).

    prev_position : Table position [-] of the previous (sub-)step point, where the state in
    ``_PREV_*`` was.
    """
    prev_drive_lift, prev_slope = excitation_lift_slope(excitation, table_step, prev_position)
    for l in range(LANES):
        lift = data[R_PREV_LIFT * LANES + l]
        velocity = data[R_PREV_VELOCITY * LANES + l]
        c = case_coefficients(data, l, LANES)
        _, _, acc = specific_point(lift, velocity, prev_drive_lift, prev_slope, c)
        jerk = jerk_at(excitation, table_step, prev_position, lift, velocity, acc, c)
        record_closure_events(data, l, LANES, lift, velocity, acc, jerk)


@jit
def _energy_lanes(data, drive_lift, slope):
    """Energy checks of every lane at a grid point (``observe_energy``)."""
    for l in range(LANES):
        lift, velocity, drive, _, _ = _lane_point(data, l, drive_lift, slope)
        drive_velocity = data[K_SPEED * LANES + l] * slope
        observe_energy(data, l, LANES, lift, velocity, drive_lift, drive_velocity, drive)


@jit
def _step_lanes(data, ym, sm, y1, s1):
    """RK4 grid step of every lane from the acceleration in ``R_ACC``.

    Keeps the state it starts from in ``_PREV_*`` (for ``record_closure_events``).
    """
    for l in range(LANES):
        lift = data[R_LIFT * LANES + l]
        velocity = data[R_VELOCITY * LANES + l]
        data[R_PREV_LIFT * LANES + l] = lift
        data[R_PREV_VELOCITY * LANES + l] = velocity
        _lane_step(data, l, lift, velocity, data[R_ACC * LANES + l], ym, sm, y1, s1)


@jit
def _substep_lanes(data, ya, sa, ym, sm, yb, sb):
    """RK4 sub-step of every lane; excitation at its start, middle and end.

    Keeps the state it starts from in ``_PREV_*`` (for ``record_closure_events``).
    """
    for l in range(LANES):
        lift, velocity, _, _, acc = _lane_point(data, l, ya, sa)
        data[R_PREV_LIFT * LANES + l] = lift
        data[R_PREV_VELOCITY * LANES + l] = velocity
        _lane_step(data, l, lift, velocity, acc, ym, sm, yb, sb)


@jit
def _observe_seat_lanes(data, past_nose):
    """Seat phase of every lane at an RK4 sub-step point inside a grid step.

    A landing on a stiff seat can begin and end between grid points, never between sub-step
    points (see ``engine_kernels.valvetrain.valve.one_case._observe_substep``). ``past_nose``: the point is at or
    past the cam's nose.
    Returns True if the seat phase of some lane changed (``observe_closure``).
    """
    changed = False
    for l in range(LANES):
        changed |= observe_closure(data, l, LANES, data[R_LIFT * LANES + l], past_nose)
    return changed


@jit
def _record_lanes(data, trace, n, compare):
    """Record the lift of every lane at grid point ``n`` or compare with the recorded one."""
    for l in range(LANES):
        lift = data[R_LIFT * LANES + l]
        if compare:
            difference = abs(lift - trace[n, l])
            data[R_DIFFERENCE * LANES + l] = max(data[R_DIFFERENCE * LANES + l], difference)
        else:
            trace[n, l] = lift


@jit
def lane_pass(excitation, table_step, table_start, compare, substeps, params, cases, data, trace):
    """Integrate all lanes of a block at RK4 grid step ``2·table_step``.

    substeps : int  RK4 sub-steps per grid step, the same for every lane of the block.
    cases    : 1-D int64  Parameter rows of the lanes (their initial state).
    Records the lift per grid point in ``trace`` (grid point × lane) or, with ``compare``,
    keeps the largest difference from that trace in ``R_DIFFERENCE`` (the step-halving pass
    runs with twice the sub-steps of the recorded one).
    """
    half = 1
    n_steps = (excitation.shape[1] - 1) // (2 * half)
    grid_step = 2.0 * half * table_step
    record = trace.shape[0] > 0
    for l in range(LANES):
        valve_time_steps(data, l, LANES, grid_step, substeps)
        data[R_LIFT * LANES + l] = params[cases[l], P_INITIAL_LIFT]
        data[R_VELOCITY * LANES + l] = params[cases[l], P_INITIAL_VELOCITY]
        data[R_DIFFERENCE * LANES + l] = 0.0
    prev_position = 0.0  # read once n > 0
    nose = nose_position(excitation)
    for n in range(n_steps + 1):
        node = 2 * half * n
        drive_lift, slope = lash_clip(excitation[0, node], excitation[1, node])
        data[R_ANGLE * LANES] = table_start + n * grid_step
        angle = data[R_ANGLE * LANES]  # in the block's precision
        if record:
            _record_lanes(data, trace, n, compare)
        if n == 0:
            _start_lanes(data, angle, drive_lift, slope)
        elif _observe_lanes(data, angle, drive_lift, slope, node >= nose):
            _record_events_lanes(data, excitation, table_step, prev_position)
        if n % ENERGY_INTERVAL == 0 or n == n_steps:
            _energy_lanes(data, drive_lift, slope)
        if n == n_steps:
            break
        prev_position = float(node)
        if substeps == 1:
            # names of their own: the sub-step branch's are float64, these keep the table's
            # precision (one name for both would promote a float32 block's step to double)
            y_mid, s_mid = lash_clip(excitation[0, node + half], excitation[1, node + half])
            y_end, s_end = lash_clip(excitation[0, node + 2 * half], excitation[1, node + 2 * half])
            _step_lanes(data, y_mid, s_mid, y_end, s_end)
            continue
        for j in range(substeps):
            position = node + 2.0 * half * j / substeps
            ya, sa = excitation_lift_slope(excitation, table_step, position)
            if j > 0:
                if _observe_seat_lanes(data, position >= nose):
                    _record_events_lanes(data, excitation, table_step, prev_position)
                prev_position = position
            ym, sm = excitation_lift_slope(
                excitation, table_step, node + 2.0 * half * (j + 0.5) / substeps
            )
            yb, sb = excitation_lift_slope(
                excitation, table_step, node + 2.0 * half * (j + 1) / substeps
            )
            _substep_lanes(data, ya, sa, ym, sm, yb, sb)
