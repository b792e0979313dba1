"""Valve dynamics with the multi-mass spring [V4] stepped for a block of cases in SIMD lanes.

Same model, fixed-step RK4, observations and arithmetic as
:func:`engine_kernels.valvetrain.spring_chain_response.spring_chain_response` (no curves), for
``LANES`` cases that share the number of coil masses N and the RK4 sub-step count; the batch
driver that forms such blocks is :mod:`engine_kernels.valvetrain.spring_chain_lane_batch`.
The force laws, energy terms and valve balance are the inlined select helpers of
:mod:`engine_kernels.valvetrain.spring_chain`, shared with the one-case kernel.

Layout (STYLE "Hot integrators", as :mod:`engine_kernels.valvetrain.lanes`): one flat array,
row ``r`` of lane ``l`` at ``r·LANES + l``. First the coefficients and time steps (``_K_*``)
and the running observations (``_O_*``), then one block of ``NODE_ROWS`` rows per node
``j = 0 … N+1`` (0 the fixed head, always zero; 1 … N the coils; N+1 the valve): the state
x, v, the current RK4 stage point, the running RK4 sums, the first-stage acceleration, the
force of segment j (nodes j, j+1) and its coil-clash state. The 2(N+1) state rows per lane are
the x, v rows of nodes 1 … N+1. Within a node sweep every row a lane loop touches sits a
compile-time number of rows from the others, so the compiler sees that they never overlap.

A sub-step is four sweeps over the nodes, each with one loop over the lanes per node: the
observation sweep evaluates the forces at the state (first RK4 stage, energy, clash and
valve observations) and forms the second stage point; each stage sweep evaluates the forces
at the stage point, keeps the RK4 sums and forms the next point, the last one the new state.
A sweep needs a node's point and that of the node above it only, so a node is advanced as
soon as its upper segment's force is known. The RK4 sums are kept in the one-case kernel's
order (``v + 2(V₂ + V₃) + V₄``, doubling being exact), so both give the same numbers.
Reference: SPEC §4 [V2], [V4].
"""

from __future__ import annotations

import math

import numpy as np

from engine_kernels._jit import jit, jit_inline, jit_lanes
from engine_kernels.valvetrain.model import excitation_lift_slope, larger, positive_part, smaller
from engine_kernels.valvetrain.spring_chain import (
    chain_coefficients,
    coil_deviation,
    contact_energy,
    kinetic_energy,
    segment_energy,
    segment_force,
    valve_balance,
)
from engine_kernels.valvetrain.spring_chain_guard import chain_status
from engine_kernels.valvetrain.spring_chain_layout import (
    CO_BOUNCE_COUNT,
    CO_BOUNCE_HEIGHT,
    CO_CLASH_COUNT,
    CO_ENERGY_EXCESS,
    CO_JUMP_DURATION,
    CO_JUMP_GAP,
    CO_JUMP_START,
    CO_MAX_CONTACT_FORCE,
    CO_MAX_LIFT,
    CO_MAX_RETAINER_DEVIATION,
    CO_MAX_VELOCITY,
    CO_MIN_FORCE_MARGIN,
    CO_MIN_RETAINER_RATIO,
    CO_MIN_VELOCITY,
    CO_SEATING_VELOCITY,
    CO_STATUS,
    CO_SUBSTEPS,
    CO_SURGE_AMPLITUDE,
    SC_INITIAL_LIFT,
    SC_INITIAL_VELOCITY,
    SC_SPRING_RATE,
)

LANES = 32

# Coefficients (chain_coefficients without N) and time steps of each lane [SI].
(_K_VALVE_MASS, _K_COIL_MASS, _K_RATE, _K_DAMPER, _K_GAP, _K_KC, _K_CC, _K_K, _K_B, _K_KZ) = range(
    10
)
(_K_BZ, _K_GAMMA, _K_PRELOAD, _K_DEPTH, _K_SPEED, _K_SPRING_RATE, _K_INV_COIL) = range(10, 17)
_K_TAU, _K_HALF, _K_SIXTH = range(17, 20)
# Running observations of each lane (seat phase as in engine_kernels.valvetrain.layout).
(_O_MAX_LIFT, _O_MAX_V, _O_MIN_V, _O_MAX_CONTACT, _O_MIN_MARGIN) = range(5)
(_O_MIN_RATIO, _O_MAX_DEVIATION, _O_SURGE, _O_JUMP_START, _O_JUMP_ANGLE) = range(5, 10)
(_O_JUMP_GAP, _O_PHASE, _O_SEATING, _O_BOUNCES, _O_BOUNCE_HEIGHT) = range(10, 15)
(_O_ENERGY0, _O_WORK, _O_WORK_MAX, _O_EXCESS, _O_ENERGY_MAX) = range(15, 20)
(_O_PREV_LIFT, _O_PREV_V, _O_PREV_POWER, _O_ENERGY, _O_DEVIATION) = range(20, 25)
_O_DRIVE_VELOCITY = 25
N_COEFFICIENTS = 20
N_OBSERVATIONS = 26
# Rows of a node block: state, stage point, RK4 sums, first-stage and current acceleration,
# upper segment force [N], its clash state (1: closed) and count of clash onsets.
_X, _V, _PX, _PV, _SX, _SV, _A1, _ACC, _F, _SOLID, _CLASHES = range(11)
NODE_ROWS = 11


@jit
def new_block(masses):
    """Zeroed arrays of a block of N = ``masses``: coefficients, observations and nodes (the
    head node's rows stay zero). Three arrays: the compiler then checks once per lane loop
    that a node row it writes is no coefficient it reads, rather than row by row."""
    return (
        np.zeros(N_COEFFICIENTS * LANES),
        np.zeros(N_OBSERVATIONS * LANES),
        np.zeros((masses + 2) * NODE_ROWS * LANES),
    )


@jit_inline
def _at(j, field, l):
    """Index of ``field`` of node ``j`` for lane ``l``, unsigned: Numba then adds no
    negative-index wraparound, which would hide the affine address from the vectoriser."""
    return np.uint64((j * NODE_ROWS + field) * LANES + l)


@jit_inline
def _k(coef, l):
    """Coefficients and time steps of lane ``l`` (``_K_*`` order), read once per loop body."""
    return (
        coef[_K_VALVE_MASS * LANES + l],
        coef[_K_COIL_MASS * LANES + l],
        coef[_K_RATE * LANES + l],
        coef[_K_DAMPER * LANES + l],
        coef[_K_GAP * LANES + l],
        coef[_K_KC * LANES + l],
        coef[_K_CC * LANES + l],
        coef[_K_K * LANES + l],
        coef[_K_B * LANES + l],
        coef[_K_KZ * LANES + l],
        coef[_K_BZ * LANES + l],
        coef[_K_GAMMA * LANES + l],
        coef[_K_PRELOAD * LANES + l],
        coef[_K_DEPTH * LANES + l],
        coef[_K_SPEED * LANES + l],
        coef[_K_SPRING_RATE * LANES + l],
        coef[_K_INV_COIL * LANES + l],
        coef[_K_TAU * LANES + l],
        coef[_K_HALF * LANES + l],
        coef[_K_SIXTH * LANES + l],
    )


@jit_inline
def _segment(nodes, l, j, x, v, c):
    """Force F_j [N] of segment j from fields ``x``, ``v`` of nodes j and j+1 (stored in
    ``_F``) and its compression d_j [m]."""
    d = nodes[_at(j + 1, x, l)] - nodes[_at(j, x, l)]
    rate = nodes[_at(j + 1, v, l)] - nodes[_at(j, v, l)]
    force = segment_force(
        d, c[_K_RATE], c[_K_DAMPER], c[_K_PRELOAD], c[_K_GAP], c[_K_KC], c[_K_CC], rate
    )
    nodes[_at(j, _F, l)] = force
    return force, d


@jit_inline
def _observe_segment(obs, nodes, l, j, c):
    """First stage of segment j at the state: force, strain energy, clash onsets; returns F_j."""
    force, d = _segment(nodes, l, j, _X, _V, c)
    obs[_O_ENERGY * LANES + l] = segment_energy(
        obs[_O_ENERGY * LANES + l], d, c[_K_RATE], c[_K_GAP], c[_K_KC]
    )
    solid = d > c[_K_GAP]
    onset = solid & (nodes[_at(j, _SOLID, l)] == 0.0)
    nodes[_at(j, _CLASHES, l)] += 1.0 if onset else 0.0
    nodes[_at(j, _SOLID, l)] = 1.0 if solid else 0.0
    return force


@jit_inline
def _valve(nodes, l, n, x, v, drive_lift, drive_velocity, c):
    """Valve (node N+1) at fields ``x``, ``v``: lift [m], velocity [m/s], drive and seat
    forces [N] and acceleration [m/s²] for excitation Y [m], Ẏ [m/s]."""
    lift = nodes[_at(n + 1, x, l)]
    velocity = nodes[_at(n + 1, v, l)]
    drive, seat, acc = valve_balance(
        lift,
        velocity,
        drive_lift,
        drive_velocity,
        nodes[_at(n, _F, l)],
        c[_K_VALVE_MASS],
        c[_K_K],
        c[_K_B],
        c[_K_KZ],
        c[_K_BZ],
        c[_K_GAMMA],
        c[_K_PRELOAD],
        c[_K_DEPTH],
    )
    return lift, velocity, drive, seat, acc


@jit_inline
def _first_point(nodes, l, j, acc, c):
    """Keep the first-stage acceleration of node j and form its second-stage point."""
    nodes[_at(j, _A1, l)] = acc
    nodes[_at(j, _PX, l)] = nodes[_at(j, _X, l)] + c[_K_HALF] * nodes[_at(j, _V, l)]
    nodes[_at(j, _PV, l)] = nodes[_at(j, _V, l)] + c[_K_HALF] * acc


@jit_inline
def _advance(nodes, l, j, acc, stage, c):
    """Node j after the forces of RK4 stage 2, 3 or 4 (acceleration ``acc``) [m, m/s]."""
    x = nodes[_at(j, _X, l)]
    v = nodes[_at(j, _V, l)]
    pv = nodes[_at(j, _PV, l)]
    if stage == 2:
        nodes[_at(j, _SX, l)] = pv
        nodes[_at(j, _SV, l)] = acc
        nodes[_at(j, _PX, l)] = x + c[_K_HALF] * pv
        nodes[_at(j, _PV, l)] = v + c[_K_HALF] * acc
    elif stage == 3:
        nodes[_at(j, _SX, l)] = v + 2.0 * (nodes[_at(j, _SX, l)] + pv)
        nodes[_at(j, _SV, l)] = nodes[_at(j, _A1, l)] + 2.0 * (nodes[_at(j, _SV, l)] + acc)
        nodes[_at(j, _PX, l)] = x + c[_K_TAU] * pv
        nodes[_at(j, _PV, l)] = v + c[_K_TAU] * acc
    else:
        nodes[_at(j, _X, l)] = x + c[_K_SIXTH] * (nodes[_at(j, _SX, l)] + pv)
        nodes[_at(j, _V, l)] = v + c[_K_SIXTH] * (nodes[_at(j, _SV, l)] + acc)


@jit_inline
def _observe_valve(obs, l, point, drive_lift, angle, sub_angle, first, c):
    """Running observations of lane ``l`` at a sub-step point, as in the one-case kernel.

    point      : (lift y [m], velocity ẏ [m/s], drive force before clipping [N], Ẏ [m/s],
                 retainer force F_N [N], surge deviation [m]) at the point.
    drive_lift : Y [m];  angle : cam angle of the point [rad];  sub_angle : sub-step [rad];
    first      : the run's first point. Selects only.
    """
    lift, velocity, drive, drive_velocity, retainer, deviation = point
    energy = obs[_O_ENERGY * LANES + l]
    power = positive_part(drive) * drive_velocity
    energy0 = energy if first else obs[_O_ENERGY0 * LANES + l]
    work = obs[_O_WORK * LANES + l]
    work = work if first else work + 0.5 * c[_K_TAU] * (power + obs[_O_PREV_POWER * LANES + l])
    obs[_O_ENERGY0 * LANES + l] = energy0
    obs[_O_WORK * LANES + l] = work
    obs[_O_WORK_MAX * LANES + l] = larger(obs[_O_WORK_MAX * LANES + l], abs(work))
    obs[_O_ENERGY_MAX * LANES + l] = larger(obs[_O_ENERGY_MAX * LANES + l], abs(energy))
    obs[_O_EXCESS * LANES + l] = larger(obs[_O_EXCESS * LANES + l], energy - energy0 - work)
    obs[_O_PREV_POWER * LANES + l] = power
    obs[_O_MAX_LIFT * LANES + l] = larger(obs[_O_MAX_LIFT * LANES + l], lift)
    obs[_O_MAX_V * LANES + l] = larger(obs[_O_MAX_V * LANES + l], velocity)
    obs[_O_MIN_V * LANES + l] = smaller(obs[_O_MIN_V * LANES + l], velocity)
    obs[_O_MAX_CONTACT * LANES + l] = larger(obs[_O_MAX_CONTACT * LANES + l], drive)
    static = c[_K_PRELOAD] + c[_K_SPRING_RATE] * lift
    obs[_O_MIN_RATIO * LANES + l] = smaller(obs[_O_MIN_RATIO * LANES + l], retainer / static)
    obs[_O_MAX_DEVIATION * LANES + l] = larger(
        obs[_O_MAX_DEVIATION * LANES + l], abs(retainer - static)
    )
    obs[_O_SURGE * LANES + l] = larger(obs[_O_SURGE * LANES + l], deviation)
    depth = c[_K_DEPTH]
    event = drive_lift > depth
    margin = obs[_O_MIN_MARGIN * LANES + l]
    obs[_O_MIN_MARGIN * LANES + l] = smaller(margin, drive) if event else margin
    jumping = event & (drive <= 0.0) & (lift > depth)
    start = obs[_O_JUMP_START * LANES + l]
    obs[_O_JUMP_START * LANES + l] = angle if jumping & math.isnan(start) else start
    obs[_O_JUMP_ANGLE * LANES + l] += sub_angle if jumping else 0.0
    gap = obs[_O_JUMP_GAP * LANES + l]
    obs[_O_JUMP_GAP * LANES + l] = larger(gap, lift - drive_lift) if jumping else gap
    _observe_seat(obs, l, lift, velocity, depth, first)


@jit_inline
def _observe_seat(obs, l, lift, velocity, depth, first):
    """Seat phase, bounces and seating velocity of lane ``l`` (the one-case kernel's branches
    as selects). lift y [m], velocity ẏ [m/s], depth δ0 [m]; first : the run's first point."""
    phase = obs[_O_PHASE * LANES + l]
    prev_lift = obs[_O_PREV_LIFT * LANES + l]
    prev_v = obs[_O_PREV_V * LANES + l]
    up = lift > depth
    reopened = up & (phase >= 2.0)
    obs[_O_BOUNCES * LANES + l] += 1.0 if reopened & (prev_lift <= depth) else 0.0
    height = obs[_O_BOUNCE_HEIGHT * LANES + l]
    obs[_O_BOUNCE_HEIGHT * LANES + l] = larger(height, lift - depth) if reopened else height
    closing = (not up) & (phase == 1.0) & (not first)
    fraction = (depth - prev_lift) / (lift - prev_lift)
    seating = abs(prev_v + fraction * (velocity - prev_v))
    obs[_O_SEATING * LANES + l] = seating if closing else obs[_O_SEATING * LANES + l]
    opened = 1.0 if up & (phase == 0.0) else phase
    obs[_O_PHASE * LANES + l] = 3.0 if reopened else (2.0 if closing else opened)
    obs[_O_PREV_LIFT * LANES + l] = lift
    obs[_O_PREV_V * LANES + l] = velocity


@jit_lanes
def _observe_lanes(coef, obs, nodes, n, drive_lift, slope, angle, sub_angle, first):
    """Observation sweep at a sub-step point: first RK4 stage of every node and lane at the
    state, energy, coil clash and valve observations, second stage points formed.

    n : N;  drive_lift Y [m], slope Y' [m/rad] at the point;  angle [rad];  sub_angle [rad];
    first : the run's first point.
    """
    for l in range(LANES):
        c = _k(coef, l)
        lift = nodes[_at(n + 1, _X, l)]
        velocity = nodes[_at(n + 1, _V, l)]
        obs[_O_ENERGY * LANES + l] = kinetic_energy(0.0, c[_K_VALVE_MASS], velocity) + (
            c[_K_PRELOAD] * lift
        )
        obs[_O_DEVIATION * LANES + l] = 0.0
        obs[_O_DRIVE_VELOCITY * LANES + l] = c[_K_SPEED] * slope
    for l in range(LANES):
        _observe_segment(obs, nodes, l, 0, _k(coef, l))
    for j in range(1, n + 1):
        for l in range(LANES):
            c = _k(coef, l)
            force = _observe_segment(obs, nodes, l, j, c)
            _first_point(nodes, l, j, (force - nodes[_at(j - 1, _F, l)]) * c[_K_INV_COIL], c)
    for j in range(1, n + 1):
        for l in range(LANES):
            c = _k(coef, l)
            obs[_O_ENERGY * LANES + l] = kinetic_energy(
                obs[_O_ENERGY * LANES + l], c[_K_COIL_MASS], nodes[_at(j, _V, l)]
            )
            deviation = coil_deviation(nodes[_at(j, _X, l)], nodes[_at(n + 1, _X, l)], j, n)
            obs[_O_DEVIATION * LANES + l] = larger(obs[_O_DEVIATION * LANES + l], deviation)
    for l in range(LANES):
        c = _k(coef, l)
        lift, velocity, drive, _, acc = _valve(
            nodes, l, n, _X, _V, drive_lift, obs[_O_DRIVE_VELOCITY * LANES + l], c
        )
        obs[_O_ENERGY * LANES + l] = contact_energy(
            obs[_O_ENERGY * LANES + l], lift, drive_lift, c[_K_K], c[_K_KZ], c[_K_DEPTH]
        )
        point = (
            lift,
            velocity,
            drive,
            obs[_O_DRIVE_VELOCITY * LANES + l],
            nodes[_at(n, _F, l)],
            obs[_O_DEVIATION * LANES + l],
        )
        _observe_valve(obs, l, point, drive_lift, angle, sub_angle, first, c)
        _first_point(nodes, l, n + 1, acc, c)


@jit_inline
def _stage_sweep(coef, obs, nodes, n, drive_lift, slope, stage):
    """Stage sweep: forces at the stage point of every node and lane, then ``_advance``.

    n : N;  drive_lift Y [m], slope Y' [m/rad] at the stage;  stage : 2, 3 or 4, a constant
    in each caller, so the compiler drops the other stages' branches from the lane loops.
    A coil's acceleration goes through its ``_ACC`` row, read in a second lane loop: it is
    then rounded before the RK4 sums add it, as in the one-case kernel (in one loop the
    compiler would fuse its product into those sums, a different rounding).
    """
    for l in range(LANES):
        c = _k(coef, l)
        _segment(nodes, l, 0, _PX, _PV, c)
        obs[_O_DRIVE_VELOCITY * LANES + l] = c[_K_SPEED] * slope
    for j in range(1, n + 1):
        for l in range(LANES):
            c = _k(coef, l)
            force, _ = _segment(nodes, l, j, _PX, _PV, c)
            nodes[_at(j, _ACC, l)] = (force - nodes[_at(j - 1, _F, l)]) * c[_K_INV_COIL]
        for l in range(LANES):
            _advance(nodes, l, j, nodes[_at(j, _ACC, l)], stage, _k(coef, l))
    for l in range(LANES):
        c = _k(coef, l)
        _, _, _, _, acc = _valve(
            nodes, l, n, _PX, _PV, drive_lift, obs[_O_DRIVE_VELOCITY * LANES + l], c
        )
        _advance(nodes, l, n + 1, acc, stage, c)


@jit_lanes
def _stage2_lanes(coef, obs, nodes, n, drive_lift, slope):
    """Second RK4 stage of every node and lane (``_stage_sweep``)."""
    _stage_sweep(coef, obs, nodes, n, drive_lift, slope, 2)


@jit_lanes
def _stage3_lanes(coef, obs, nodes, n, drive_lift, slope):
    """Third RK4 stage of every node and lane (``_stage_sweep``)."""
    _stage_sweep(coef, obs, nodes, n, drive_lift, slope, 3)


@jit_lanes
def _stage4_lanes(coef, obs, nodes, n, drive_lift, slope):
    """Fourth RK4 stage of every node and lane and the new state (``_stage_sweep``)."""
    _stage_sweep(coef, obs, nodes, n, drive_lift, slope, 4)


@jit
def start_chain_lanes(params, cases, masses, sub_angle, block):
    """Coefficients, time steps, initial state (static deflection line) and observations.

    params : 2-D array  ``SC_*`` rows;  cases : 1-D int64  Row of each of the ``LANES`` lanes.
    masses : int  N of every lane;  sub_angle : float  RK4 sub-step [rad];
    block  : tuple  Arrays of :func:`new_block`.
    """
    coef, obs, nodes = block
    n = masses
    for l in range(LANES):
        row = params[cases[l]]
        c = chain_coefficients(row)
        values = c[1:]  # the _K_* rows up to _K_SPEED, in order
        for r in range(len(values)):
            coef[r * LANES + l] = values[r]
        coef[_K_SPRING_RATE * LANES + l] = row[SC_SPRING_RATE]
        coef[_K_INV_COIL * LANES + l] = 1.0 / c[2]
        tau = sub_angle / c[15]
        coef[_K_TAU * LANES + l] = tau
        coef[_K_HALF * LANES + l] = 0.5 * tau
        coef[_K_SIXTH * LANES + l] = tau / 6.0
        for i in range(n + 1):
            share = (i + 1) / (n + 1)
            nodes[_at(i + 1, _X, l)] = share * row[SC_INITIAL_LIFT]
            nodes[_at(i + 1, _V, l)] = share * row[SC_INITIAL_VELOCITY]
        for r, value in (
            (_O_MAX_LIFT, -math.inf),
            (_O_MAX_V, -math.inf),
            (_O_MIN_V, math.inf),
            (_O_MIN_MARGIN, math.inf),
            (_O_MIN_RATIO, math.inf),
            (_O_JUMP_START, math.nan),
            (_O_SEATING, math.nan),
        ):
            obs[r * LANES + l] = value
        lift = nodes[_at(n + 1, _X, l)]
        obs[_O_PHASE * LANES + l] = 1.0 if lift > c[14] else 0.0
        obs[_O_PREV_LIFT * LANES + l] = lift
        obs[_O_PREV_V * LANES + l] = nodes[_at(n + 1, _V, l)]


@jit
def chain_lane_pass(excitation, table_step, table_start, masses, substeps, block):
    """Integrate every lane of a started block (:func:`start_chain_lanes`) over the table.

    excitation : 2-D array  (3, n) rows Y [m], Y' [m/rad], Y'' [m/rad²] at ``table_step``.
    table_step : float  Table spacing [rad]; the RK4 grid step is twice it.
    table_start : float  Cam angle of the first node [rad];  masses : int  N of every lane.
    substeps   : int    RK4 sub-steps per grid step, the same for every lane.
    """
    coef, obs, nodes = block
    n_steps = (excitation.shape[1] - 1) // 2
    sub_angle = 2.0 * table_step / substeps
    y0, slope0 = excitation_lift_slope(excitation, table_step, 0.0)
    total = n_steps * substeps
    for m in range(total + 1):
        position = 2.0 * m / substeps
        angle = table_start + position * table_step
        _observe_lanes(coef, obs, nodes, masses, y0, slope0, angle, sub_angle, m == 0)
        if m == total:
            break
        ym, slope_m = excitation_lift_slope(excitation, table_step, position + 1.0 / substeps)
        y1, slope1 = excitation_lift_slope(excitation, table_step, position + 2.0 / substeps)
        _stage2_lanes(coef, obs, nodes, masses, ym, slope_m)
        _stage3_lanes(coef, obs, nodes, masses, ym, slope_m)
        _stage4_lanes(coef, obs, nodes, masses, y1, slope1)
        y0, slope0 = y1, slope1


@jit
def finish_chain_lanes(block, count, masses, substeps, cases, out):
    """Write the ``CO_*`` outputs of the first ``count`` lanes into rows ``cases`` of ``out``
    (``CO_STEP_RATIO`` is left as the guard set it)."""
    _, obs, nodes = block
    n = masses
    for l in range(count):
        row = out[cases[l]]
        for column, r in (
            (CO_MAX_LIFT, _O_MAX_LIFT),
            (CO_MAX_VELOCITY, _O_MAX_V),
            (CO_MIN_VELOCITY, _O_MIN_V),
            (CO_JUMP_START, _O_JUMP_START),
            (CO_JUMP_DURATION, _O_JUMP_ANGLE),
            (CO_JUMP_GAP, _O_JUMP_GAP),
            (CO_BOUNCE_COUNT, _O_BOUNCES),
            (CO_BOUNCE_HEIGHT, _O_BOUNCE_HEIGHT),
            (CO_SEATING_VELOCITY, _O_SEATING),
            (CO_MAX_CONTACT_FORCE, _O_MAX_CONTACT),
            (CO_MIN_FORCE_MARGIN, _O_MIN_MARGIN),
            (CO_MIN_RETAINER_RATIO, _O_MIN_RATIO),
            (CO_MAX_RETAINER_DEVIATION, _O_MAX_DEVIATION),
            (CO_SURGE_AMPLITUDE, _O_SURGE),
        ):
            row[column] = obs[r * LANES + l]
        clashes = 0.0
        finite = True
        for j in range(n + 2):
            clashes += nodes[_at(j, _CLASHES, l)]
            finite = finite and math.isfinite(nodes[_at(j, _X, l)])
            finite = finite and math.isfinite(nodes[_at(j, _V, l)])
        row[CO_CLASH_COUNT] = clashes
        scale = max(obs[_O_ENERGY_MAX * LANES + l], obs[_O_WORK_MAX * LANES + l])
        excess = obs[_O_EXCESS * LANES + l]
        row[CO_ENERGY_EXCESS] = excess / scale if scale > 0.0 else 0.0
        row[CO_SUBSTEPS] = substeps
        row[CO_STATUS] = chain_status(finite, row[CO_ENERGY_EXCESS])
