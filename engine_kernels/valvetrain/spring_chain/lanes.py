"""Valve dynamics with the multi-mass spring [V4] stepped for a block of cases in SIMD lanes.

Same model, fixed-step RK4, observations and arithmetic as
:func:`engine_kernels.valvetrain.spring_chain.one_case.spring_chain_response` (no curves), for
``LANES`` cases that share the number of coil masses N and the RK4 sub-step count; the batch
driver that forms such blocks is :mod:`engine_kernels.valvetrain.spring_chain.lane_batch`.
The force laws, energy terms and valve balance are the inlined select helpers of
:mod:`engine_kernels.valvetrain.spring_chain.model`, shared with the one-case kernel.

The block's rows are described in :mod:`engine_kernels.valvetrain.spring_chain.lane_layout`.
A sub-step is four sweeps over the nodes with loops over the lanes inside: the observation
sweep evaluates the forces at the state (first RK4 stage, energy, clash and valve
observations) and forms the second stage point; each stage sweep evaluates the forces at the
stage point, keeps the RK4 sums and forms the next point, the last one the new state. A
segment's force needs the points of its two nodes only, so a node is advanced as soon as the
force of the segment above it is known.

Same numbers as the one-case kernel, bit for bit (tests/engine_kernels/
test_spring_chain_lanes.py): the RK4 sums keep its order (``v + 2(V₂ + V₃) + V₄``, doubling
being exact) and every product is rounded where it is rounded there, since fused
multiply-adds (``fastmath={'contract'}``) form wherever a product meets a sum in one basic
block: the drive velocity ω·Y' and the coil accelerations pass through rows. What keeps the
lane loops vectorised (checked in the tests): inlined helpers (``jit_inline``) with selects,
no calls; unsigned node indices (no wraparound branch); the stage a constant of each sweep;
NumPy's error model (``jit_lanes``: no divide-by-zero branch).
Reference: physics §4 [V2], [V4].
"""

from __future__ import annotations

from engine_kernels._jit import jit, jit_inline, jit_lanes
from engine_kernels.valvetrain.spring_chain.lane_layout import (
    LANES,
    LK_B,
    LK_BZ,
    LK_CC,
    LK_COIL_MASS,
    LK_DAMPER,
    LK_DEPTH,
    LK_GAMMA,
    LK_GAP,
    LK_HALF,
    LK_INV_COIL,
    LK_K,
    LK_KC,
    LK_KZ,
    LK_PRELOAD,
    LK_RATE,
    LK_SIXTH,
    LK_SPEED,
    LK_TAU,
    LK_VALVE_MASS,
    LO_DEVIATION,
    LO_DRIVE_VELOCITY,
    LO_ENERGY,
    NODE_A1,
    NODE_ACC,
    NODE_CLASHES,
    NODE_F,
    NODE_PV,
    NODE_PX,
    NODE_SOLID,
    NODE_SV,
    NODE_SX,
    NODE_V,
    NODE_X,
    lane_coefficients,
    node_at,
)
from engine_kernels.valvetrain.spring_chain.lane_observations import observe_valve
from engine_kernels.valvetrain.spring_chain.model import (
    coil_deviation,
    contact_energy,
    kinetic_energy,
    segment_energy,
    segment_force,
    valve_balance,
)
from engine_kernels.valvetrain.valve.model import excitation_lift_slope, larger


@jit_inline
def _segment(nodes, l, j, x, v, c):
    """Force F_j [N] of segment j from fields ``x``, ``v`` of nodes j and j+1 (stored in
    ``NODE_F``) and its compression d_j [m]."""
    d = nodes[node_at(j + 1, x, l)] - nodes[node_at(j, x, l)]
    rate = nodes[node_at(j + 1, v, l)] - nodes[node_at(j, v, l)]
    force = segment_force(
        d, c[LK_RATE], c[LK_DAMPER], c[LK_PRELOAD], c[LK_GAP], c[LK_KC], c[LK_CC], rate
    )
    nodes[node_at(j, NODE_F, l)] = force
    return force, d


@jit_inline
def _observe_segment(obs, nodes, l, j, c):
    """First stage of segment j at the state: force, strain energy, clash onsets; returns F_j."""
    force, d = _segment(nodes, l, j, NODE_X, NODE_V, c)
    obs[LO_ENERGY * LANES + l] = segment_energy(
        obs[LO_ENERGY * LANES + l], d, c[LK_RATE], c[LK_GAP], c[LK_KC]
    )
    solid = d > c[LK_GAP]
    onset = solid & (nodes[node_at(j, NODE_SOLID, l)] == 0.0)
    nodes[node_at(j, NODE_CLASHES, l)] += 1.0 if onset else 0.0
    nodes[node_at(j, NODE_SOLID, l)] = 1.0 if solid else 0.0
    return force


@jit_inline
def _valve(nodes, l, n, x, v, drive_lift, drive_velocity, c):
    """Valve (node N+1) at fields ``x``, ``v``: lift [m], velocity [m/s], drive and seat
    forces [N] and acceleration [m/s²] for excitation Y [m], Ẏ [m/s]."""
    lift = nodes[node_at(n + 1, x, l)]
    velocity = nodes[node_at(n + 1, v, l)]
    drive, seat, acc = valve_balance(
        lift,
        velocity,
        drive_lift,
        drive_velocity,
        nodes[node_at(n, NODE_F, l)],
        c[LK_VALVE_MASS],
        c[LK_K],
        c[LK_B],
        c[LK_KZ],
        c[LK_BZ],
        c[LK_GAMMA],
        c[LK_PRELOAD],
        c[LK_DEPTH],
    )
    return lift, velocity, drive, seat, acc


@jit_inline
def _first_point(nodes, l, j, acc, c):
    """Keep the first-stage acceleration of node j and form its second-stage point."""
    nodes[node_at(j, NODE_A1, l)] = acc
    nodes[node_at(j, NODE_PX, l)] = (
        nodes[node_at(j, NODE_X, l)] + c[LK_HALF] * nodes[node_at(j, NODE_V, l)]
    )
    nodes[node_at(j, NODE_PV, l)] = nodes[node_at(j, NODE_V, l)] + c[LK_HALF] * acc


@jit_inline
def _advance(nodes, l, j, acc, stage, c):
    """Node j after the forces of RK4 stage 2, 3 or 4 (acceleration ``acc``) [m, m/s]."""
    x = nodes[node_at(j, NODE_X, l)]
    v = nodes[node_at(j, NODE_V, l)]
    pv = nodes[node_at(j, NODE_PV, l)]
    if stage == 2:
        nodes[node_at(j, NODE_SX, l)] = pv
        nodes[node_at(j, NODE_SV, l)] = acc
        nodes[node_at(j, NODE_PX, l)] = x + c[LK_HALF] * pv
        nodes[node_at(j, NODE_PV, l)] = v + c[LK_HALF] * acc
    elif stage == 3:
        nodes[node_at(j, NODE_SX, l)] = v + 2.0 * (nodes[node_at(j, NODE_SX, l)] + pv)
        nodes[node_at(j, NODE_SV, l)] = nodes[node_at(j, NODE_A1, l)] + 2.0 * (
            nodes[node_at(j, NODE_SV, l)] + acc
        )
        nodes[node_at(j, NODE_PX, l)] = x + c[LK_TAU] * pv
        nodes[node_at(j, NODE_PV, l)] = v + c[LK_TAU] * acc
    else:
        nodes[node_at(j, NODE_X, l)] = x + c[LK_SIXTH] * (nodes[node_at(j, NODE_SX, l)] + pv)
        nodes[node_at(j, NODE_V, l)] = v + c[LK_SIXTH] * (nodes[node_at(j, NODE_SV, l)] + acc)


@jit_lanes
def _observe_lanes(coef, obs, nodes, n, drive_lift, slope, angle, sub_angle, first):
    """Observation sweep at a sub-step point: first RK4 stage of every node and lane at the
    state, energy, coil clash and valve observations, second stage points formed.

    n : N;  drive_lift Y [m], slope Y' [m/rad] at the point;  angle [rad];  sub_angle [rad];
    first : the run's first point.
    """
    for l in range(LANES):
        c = lane_coefficients(coef, l)
        lift = nodes[node_at(n + 1, NODE_X, l)]
        velocity = nodes[node_at(n + 1, NODE_V, l)]
        obs[LO_ENERGY * LANES + l] = kinetic_energy(0.0, c[LK_VALVE_MASS], velocity) + (
            c[LK_PRELOAD] * lift
        )
        obs[LO_DEVIATION * LANES + l] = 0.0
        obs[LO_DRIVE_VELOCITY * LANES + l] = c[LK_SPEED] * slope
    for l in range(LANES):
        _observe_segment(obs, nodes, l, 0, lane_coefficients(coef, l))
    for j in range(1, n + 1):
        for l in range(LANES):
            c = lane_coefficients(coef, l)
            force = _observe_segment(obs, nodes, l, j, c)
            _first_point(
                nodes, l, j, (force - nodes[node_at(j - 1, NODE_F, l)]) * c[LK_INV_COIL], c
            )
    for j in range(1, n + 1):
        for l in range(LANES):
            c = lane_coefficients(coef, l)
            obs[LO_ENERGY * LANES + l] = kinetic_energy(
                obs[LO_ENERGY * LANES + l], c[LK_COIL_MASS], nodes[node_at(j, NODE_V, l)]
            )
            deviation = coil_deviation(
                nodes[node_at(j, NODE_X, l)], nodes[node_at(n + 1, NODE_X, l)], j, n
            )
            obs[LO_DEVIATION * LANES + l] = larger(obs[LO_DEVIATION * LANES + l], deviation)
    for l in range(LANES):
        c = lane_coefficients(coef, l)
        lift, velocity, drive, _, acc = _valve(
            nodes, l, n, NODE_X, NODE_V, drive_lift, obs[LO_DRIVE_VELOCITY * LANES + l], c
        )
        obs[LO_ENERGY * LANES + l] = contact_energy(
            obs[LO_ENERGY * LANES + l], lift, drive_lift, c[LK_K], c[LK_KZ], c[LK_DEPTH]
        )
        point = (
            lift,
            velocity,
            drive,
            obs[LO_DRIVE_VELOCITY * LANES + l],
            nodes[node_at(n, NODE_F, l)],
            obs[LO_DEVIATION * LANES + l],
        )
        observe_valve(obs, l, point, drive_lift, angle, sub_angle, first, c)
        _first_point(nodes, l, n + 1, acc, c)


@jit_inline
def _stage_sweep(coef, obs, nodes, n, drive_lift, slope, stage):
    """Stage sweep: forces at the stage point of every node and lane, then ``_advance``.

    n : N;  drive_lift Y [m], slope Y' [m/rad] at the stage;  stage : 2, 3 or 4, a constant
    in each caller, so the compiler drops the other stages' branches from the lane loops.
    A coil's acceleration goes through its ``NODE_ACC`` row, read in a second lane loop: it is
    then rounded before the RK4 sums add it, as in the one-case kernel (in one loop the
    compiler would fuse its product into those sums, a different rounding).
    """
    for l in range(LANES):
        c = lane_coefficients(coef, l)
        _segment(nodes, l, 0, NODE_PX, NODE_PV, c)
        obs[LO_DRIVE_VELOCITY * LANES + l] = c[LK_SPEED] * slope
    for j in range(1, n + 1):
        for l in range(LANES):
            c = lane_coefficients(coef, l)
            force, _ = _segment(nodes, l, j, NODE_PX, NODE_PV, c)
            nodes[node_at(j, NODE_ACC, l)] = (force - nodes[node_at(j - 1, NODE_F, l)]) * c[
                LK_INV_COIL
            ]
        for l in range(LANES):
            _advance(nodes, l, j, nodes[node_at(j, NODE_ACC, l)], stage, lane_coefficients(coef, l))
    for l in range(LANES):
        c = lane_coefficients(coef, l)
        _, _, _, _, acc = _valve(
            nodes, l, n, NODE_PX, NODE_PV, drive_lift, obs[LO_DRIVE_VELOCITY * LANES + l], c
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
def chain_lane_pass(excitation, table_step, table_start, masses, substeps, block):
    """Integrate every lane of a started block over the table, as the one-case kernel does.

    excitation  : 2-D array  (3, n) rows Y [m], Y' [m/rad], Y'' [m/rad²] at ``table_step``.
    table_step  : float  Table spacing [rad]; the RK4 grid step is twice it.
    table_start : float  Cam angle of the first node [rad];  masses : int  N of every lane.
    substeps    : int    RK4 sub-steps per grid step, the same for every lane.
    block       : tuple  Arrays of ``spring_chain_lane_layout.new_block`` after
                         ``start_chain_lanes``; ``finish_chain_lanes`` reads the outputs.
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
