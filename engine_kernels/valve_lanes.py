"""Valve dynamics [V2] for blocks of cases in SIMD lanes (SPEC §4, STYLE "Hot integrators").

Same model, RK4 stepping, stability guard and outputs as
:func:`engine_kernels.valve.valve_response` (plain RK4, no switch location): cases are taken
``LANES`` at a time; inside a block every grid step loads the shared excitation once and then
updates all lanes in a loop of branch-free arithmetic that the compiler turns into vector
instructions. Per-lane data (coefficients, state, observations) live in rows of one flat
array, so the lane loops read and write unit-stride rows the compiler knows are disjoint. Blocks run in a ``prange``; each writes only
its own output rows. A block whose lanes need sub-steps runs the sub-stepped path for all its
lanes, each with its own count (lanes past their count hold their state).

Use ``engine_kernels.valve.valve_response_batch`` for switch-aware stepping or curves.
"""

from __future__ import annotations

import numpy as np

from engine_kernels._jit import batch, jit, prange
from engine_kernels.valve import (
    ENERGY_INTERVAL,
    ERROR_ORDER_DIVISOR,
    N_STATS,
    O_ERROR_ESTIMATE,
    P_DRIVE_DAMPING,
    P_DRIVE_STIFFNESS,
    P_EXTERNAL_DAMPING,
    P_INITIAL_LIFT,
    P_INITIAL_VELOCITY,
    P_MASS,
    P_PRELOAD,
    P_SEAT_DAMPING,
    P_SEAT_STIFFNESS,
    P_SPEED,
    P_SPRING_RATE,
    S_ESTIMATE_ERROR,
    TRANSITION_BAND,
    _rk4_step,
    error_estimate_is_stable,
    excitation_at,
    finish_observations,
    observe_closure,
    observe_energy,
    observe_extremes,
    observe_power,
    observe_separation,
    observe_transitions,
    prepare_case,
    reset_observations,
    valve_acceleration,
)

LANES = 32

# Rows of the flat per-block array: lane row r of lane l sits at r·LANES + l, followed by the
# N_STATS observation rows. One flat array with compile-time offsets lets the compiler prove
# that rows never overlap, which is what allows the lane loops to vectorise.
_SPEED = 0
_INV_MASS = 1
_MASS = 2
_K = 3
_B = 4
_KS = 5
_PS0 = 6
_KZ = 7
_BZ = 8
_GAMMA = 9
_DEPTH = 10
_TAU = 11
_LIFT = 12
_VELOCITY = 13
_ACC = 14
_SUBSTEPS = 15
_DIFFERENCE = 16
_LIFT0 = 17
_VELOCITY0 = 18
N_LANE_ROWS = 19
_STATS = N_LANE_ROWS * LANES


@jit
def _load_lanes(rows, steps, data):
    """Fill the lane rows of ``data`` from ``LANES`` parameter rows and sub-step counts."""
    for l in range(LANES):
        row = rows[l]
        data[_SPEED * LANES + l] = row[P_SPEED]
        data[_MASS * LANES + l] = row[P_MASS]
        data[_INV_MASS * LANES + l] = 1.0 / row[P_MASS]
        data[_K * LANES + l] = row[P_DRIVE_STIFFNESS]
        data[_B * LANES + l] = row[P_DRIVE_DAMPING]
        data[_KS * LANES + l] = row[P_SPRING_RATE]
        data[_PS0 * LANES + l] = row[P_PRELOAD]
        data[_KZ * LANES + l] = row[P_SEAT_STIFFNESS]
        data[_BZ * LANES + l] = row[P_SEAT_DAMPING]
        data[_GAMMA * LANES + l] = row[P_EXTERNAL_DAMPING]
        data[_DEPTH * LANES + l] = row[P_PRELOAD] / row[P_SEAT_STIFFNESS]
        data[_SUBSTEPS * LANES + l] = steps[l]
        data[_LIFT0 * LANES + l] = row[P_INITIAL_LIFT]
        data[_VELOCITY0 * LANES + l] = row[P_INITIAL_VELOCITY]


@jit
def _observe_lanes(data, angle, drive_lift, drive_slope, ym, dm, y1, d1, advance):
    """Observe every lane at a grid point and, if ``advance``, take its RK4 grid step.

    The excitation (Y [m], Y' [m/rad]) is shared: at the grid point, its half step and its end.
    Observation and step share one loop so each lane's data are loaded once per grid step.
    """
    for l in range(LANES):
        speed = data[_SPEED * LANES + l]
        lift = data[_LIFT * LANES + l]
        velocity = data[_VELOCITY * LANES + l]
        drive_velocity = speed * drive_slope
        inv_mass = data[_INV_MASS * LANES + l]
        k = data[_K * LANES + l]
        b = data[_B * LANES + l]
        ks = data[_KS * LANES + l]
        ps0 = data[_PS0 * LANES + l]
        kz = data[_KZ * LANES + l]
        bz = data[_BZ * LANES + l]
        gamma = data[_GAMMA * LANES + l]
        depth = data[_DEPTH * LANES + l]
        acc = valve_acceleration(
            lift,
            velocity,
            drive_lift,
            drive_velocity,
            inv_mass,
            k,
            b,
            ks,
            ps0,
            kz,
            bz,
            gamma,
            depth,
        )
        data[_ACC * LANES + l] = acc
        # observe_valve piece by piece: each piece inlines, so this loop vectorises.
        at = _STATS + l
        drive = k * (drive_lift - lift) + b * (drive_velocity - velocity)
        seat = kz * (depth - lift) - bz * velocity
        observe_extremes(data, at, LANES, lift, velocity, acc, drive)
        observe_separation(data, at, LANES, angle, lift, drive_lift, drive, depth)
        observe_closure(data, at, LANES, lift, velocity, depth)
        observe_transitions(data, at, LANES, lift, drive, seat, depth, TRANSITION_BAND * ps0)
        observe_power(data, at, LANES, drive, drive_velocity)
        if advance:
            lift, velocity = _rk4_step(
                lift,
                velocity,
                acc,
                data[_TAU * LANES + l],
                ym,
                speed * dm,
                y1,
                speed * d1,
                inv_mass,
                k,
                b,
                ks,
                ps0,
                kz,
                bz,
                gamma,
                depth,
            )
            data[_LIFT * LANES + l] = lift
            data[_VELOCITY * LANES + l] = velocity


@jit
def _observe_energy_lanes(data, grid_step, drive_lift, drive_slope):
    """Energy checks for every lane (see ``observe_energy``)."""
    for l in range(LANES):
        speed = data[_SPEED * LANES + l]
        observe_energy(
            data,
            _STATS,
            l,
            LANES,
            grid_step / speed,
            data[_LIFT * LANES + l],
            data[_VELOCITY * LANES + l],
            drive_lift,
            speed * drive_slope,
            data[_MASS * LANES + l],
            data[_K * LANES + l],
            data[_KS * LANES + l],
            data[_PS0 * LANES + l],
            data[_KZ * LANES + l],
            data[_DEPTH * LANES + l],
        )


@jit
def _substep_lanes(data, excitation, table_step, node, half, j):
    """Sub-step ``j`` of a grid step for every lane, each with its own sub-step count.

    Lanes past their count keep their state; the excitation is interpolated per lane.
    """
    for l in range(LANES):
        steps = data[_SUBSTEPS * LANES + l]
        active = j < steps
        stage = j if active else 0
        speed = data[_SPEED * LANES + l]
        ya, yda = excitation_at(excitation, table_step, node + 2.0 * half * stage / steps, speed)
        ym, ydm = excitation_at(
            excitation, table_step, node + 2.0 * half * (stage + 0.5) / steps, speed
        )
        yb, ydb = excitation_at(
            excitation, table_step, node + 2.0 * half * (stage + 1) / steps, speed
        )
        lift = data[_LIFT * LANES + l]
        velocity = data[_VELOCITY * LANES + l]
        inv_mass = data[_INV_MASS * LANES + l]
        k = data[_K * LANES + l]
        b = data[_B * LANES + l]
        ks = data[_KS * LANES + l]
        ps0 = data[_PS0 * LANES + l]
        kz = data[_KZ * LANES + l]
        bz = data[_BZ * LANES + l]
        gamma = data[_GAMMA * LANES + l]
        depth = data[_DEPTH * LANES + l]
        acc = valve_acceleration(
            lift, velocity, ya, yda, inv_mass, k, b, ks, ps0, kz, bz, gamma, depth
        )
        new_lift, new_velocity = _rk4_step(
            lift,
            velocity,
            acc,
            data[_TAU * LANES + l],
            ym,
            ydm,
            yb,
            ydb,
            inv_mass,
            k,
            b,
            ks,
            ps0,
            kz,
            bz,
            gamma,
            depth,
        )
        data[_LIFT * LANES + l] = new_lift if active else lift
        data[_VELOCITY * LANES + l] = new_velocity if active else velocity


@jit
def _lane_pass(excitation, table_step, table_start, half, data, trace, compare):
    """Integrate all lanes of a block at RK4 grid step ``2·half·table_step``.

    Records the lift per grid point in ``trace`` (grid point × lane) or, with ``compare``,
    keeps the largest difference from a trace recorded at half this step in ``_DIFFERENCE``.
    """
    n_steps = (excitation.shape[1] - 1) // (2 * half)
    grid_step = 2.0 * half * table_step
    record = trace.shape[0] > 0
    most = 1
    for l in range(LANES):
        data[_LIFT * LANES + l] = data[_LIFT0 * LANES + l]
        data[_VELOCITY * LANES + l] = data[_VELOCITY0 * LANES + l]
        data[_DIFFERENCE * LANES + l] = 0.0
        data[_TAU * LANES + l] = grid_step / data[_SPEED * LANES + l] / data[_SUBSTEPS * LANES + l]
        most = max(most, int(data[_SUBSTEPS * LANES + l]))
        reset_observations(
            data, _STATS, l, LANES, data[_LIFT * LANES + l], data[_VELOCITY * LANES + l]
        )
    for n in range(n_steps + 1):
        node = 2 * half * n
        drive_lift = excitation[0, node]
        drive_slope = excitation[1, node]
        if n % ENERGY_INTERVAL == 0:
            _observe_energy_lanes(data, grid_step, drive_lift, drive_slope)
        if record:
            for l in range(LANES):
                lift = data[_LIFT * LANES + l]
                if compare:
                    data[_DIFFERENCE * LANES + l] = max(
                        data[_DIFFERENCE * LANES + l], abs(lift - trace[2 * n, l])
                    )
                else:
                    trace[n, l] = lift
        angle = table_start + n * grid_step
        if n == n_steps or most > 1:
            _observe_lanes(data, angle, drive_lift, drive_slope, 0.0, 0.0, 0.0, 0.0, False)
            if n == n_steps:
                _observe_energy_lanes(data, grid_step, drive_lift, drive_slope)
            if n < n_steps:
                for j in range(most):
                    _substep_lanes(data, excitation, table_step, node, half, j)
        else:
            _observe_lanes(
                data,
                angle,
                drive_lift,
                drive_slope,
                excitation[0, node + half],
                excitation[1, node + half],
                excitation[0, node + 2 * half],
                excitation[1, node + 2 * half],
                True,
            )


@jit
def _lane_block(excitation, table_step, table_start, params, settings, first, out):
    """Prepare, integrate and report one block of up to ``LANES`` cases."""
    count = min(LANES, params.shape[0] - first)
    substeps = np.zeros(LANES, dtype=np.int64)
    runnable = -1
    for l in range(count):
        substeps[l] = prepare_case(
            excitation, table_step, params[first + l], settings, out[first + l]
        )
        if substeps[l] > 0 and runnable < 0:
            runnable = l
    if runnable < 0:
        return
    # Lanes that must not run (padding, invalid, over the sub-step cap) copy a runnable one,
    # so they can neither fail nor slow the block down; their results are not written.
    rows = np.empty((LANES, params.shape[1]))
    steps = np.empty(LANES, dtype=np.int64)
    for l in range(LANES):
        source = l if (l < count and substeps[l] > 0) else runnable
        rows[l] = params[first + source]
        steps[l] = substeps[source]
    grid_step = 2.0 * table_step
    data = np.empty((N_LANE_ROWS + N_STATS) * LANES)
    _load_lanes(rows, steps, data)
    estimate = settings[S_ESTIMATE_ERROR] != 0 and excitation.shape[1] >= 5
    trace = np.empty(((excitation.shape[1] - 1) // 2 + 1 if estimate else 0, LANES))
    _lane_pass(excitation, table_step, table_start, 1, data, trace, False)
    for l in range(count):
        if substeps[l] > 0:
            finish_observations(
                data,
                _STATS,
                l,
                LANES,
                grid_step,
                data[_LIFT * LANES + l],
                data[_VELOCITY * LANES + l],
                data[_PS0 * LANES + l],
                data[_DEPTH * LANES + l],
                out[first + l],
            )
    if estimate:
        _lane_pass(excitation, table_step, table_start, 2, data, trace, True)
        for l in range(count):
            if substeps[l] > 0 and error_estimate_is_stable(
                params[first + l], table_step, substeps[l], settings
            ):
                out[first + l, O_ERROR_ESTIMATE] = (
                    data[_DIFFERENCE * LANES + l] / ERROR_ORDER_DIVISOR
                )


@batch
def valve_response_lanes(excitation, table_step, table_start, params, settings, out):
    """Valve dynamics of many cases, ``LANES`` cases per SIMD block, blocks in a prange.

    Same arguments and outputs as :func:`engine_kernels.valve.valve_response_batch`
    (``settings[S_SWITCH_AWARE]`` is ignored: this kernel is plain fixed-step RK4).
    Reference: SPEC §4; STYLE "Hot integrators process a block of cases in SIMD lanes".
    """
    n_blocks = (params.shape[0] + LANES - 1) // LANES
    for block in prange(n_blocks):
        _lane_block(excitation, table_step, table_start, params, settings, block * LANES, out)
