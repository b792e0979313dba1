"""Data layout of the multi-mass spring lane kernel [V4]: a block's rows, its start and outputs.

A block of ``LANES`` cases that share N (:mod:`engine_kernels.valvetrain.spring_chain.lanes`)
keeps three flat arrays, row ``r`` of lane ``l`` at ``r·LANES + l`` in each (STYLE "Hot
integrators", as :mod:`engine_kernels.valvetrain.valve.lanes`):

* coefficients and time steps ``LK_*`` [SI] (those of
  :func:`~engine_kernels.valvetrain.spring_chain.model.chain_coefficients`, then ks, 1/m_c, h, h/2,
  h/6), read once at the top of every lane-loop body;
* running observations ``LO_*`` (the one-case kernel's locals; seat phase 0 seated, 1 open,
  2 closed again, 3 bouncing, as ``engine_kernels.valvetrain.valve.layout.PHASE_*``);
* one block of ``NODE_ROWS`` rows per node j = 0 … N+1 (0 the fixed head, always zero; 1 … N
  the coils; N+1 the valve), field ``NODE_*``: the state x [m], v [m/s]; the current RK4
  stage point; the running RK4 sums; the first-stage and current acceleration [m/s²]; the
  force of segment j (nodes j, j+1) [N], its clash state and count of clash onsets. The
  2(N+1) state rows per lane are the x, v rows of nodes 1 … N+1.

Within a node sweep the rows a lane loop touches in one array sit a compile-time number of
rows apart, so the compiler sees that they never overlap; across the three arrays it checks
once per loop at run time. Reference: physics §4 [V4].
"""

from __future__ import annotations

import math

import numpy as np

from engine_kernels._jit import jit, jit_inline
from engine_kernels.valvetrain.spring_chain.guard import chain_status
from engine_kernels.valvetrain.spring_chain.layout import (
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
from engine_kernels.valvetrain.spring_chain.model import chain_coefficients
from engine_kernels.valvetrain.valve.lanes import LANES

# Coefficients (chain_coefficients without N) and time steps of each lane [SI].
(LK_VALVE_MASS, LK_COIL_MASS, LK_RATE, LK_DAMPER, LK_GAP, LK_KC, LK_CC) = range(7)
(LK_K, LK_B, LK_KZ, LK_BZ, LK_GAMMA, LK_PRELOAD, LK_DEPTH, LK_SPEED) = range(7, 15)
(LK_SPRING_RATE, LK_INV_COIL) = range(15, 17)
LK_TAU, LK_HALF, LK_SIXTH = range(17, 20)
# Running observations of each lane (seat phase as in engine_kernels.valvetrain.valve.layout).
(LO_MAX_LIFT, LO_MAX_V, LO_MIN_V, LO_MAX_CONTACT, LO_MIN_MARGIN) = range(5)
(LO_MIN_RATIO, LO_MAX_DEVIATION, LO_SURGE, LO_JUMP_START, LO_JUMP_ANGLE) = range(5, 10)
(LO_JUMP_GAP, LO_PHASE, LO_SEATING, LO_BOUNCES, LO_BOUNCE_HEIGHT) = range(10, 15)
(LO_ENERGY0, LO_WORK, LO_WORK_MAX, LO_EXCESS, LO_ENERGY_MAX) = range(15, 20)
(LO_PREV_LIFT, LO_PREV_V, LO_PREV_POWER, LO_ENERGY, LO_DEVIATION) = range(20, 25)
LO_DRIVE_VELOCITY = 25
N_COEFFICIENTS = 20
N_OBSERVATIONS = 26
# Rows of a node block: state, stage point, RK4 sums, first-stage and current acceleration,
# upper segment force [N], its clash state (1: closed) and count of clash onsets.
(
    NODE_X,
    NODE_V,
    NODE_PX,
    NODE_PV,
    NODE_SX,
    NODE_SV,
    NODE_A1,
    NODE_ACC,
    NODE_F,
    NODE_SOLID,
    NODE_CLASHES,
) = range(11)
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
def node_at(j, field, l):
    """Index of ``field`` of node ``j`` for lane ``l``, unsigned: Numba then adds no
    negative-index wraparound, which would hide the affine address from the vectoriser."""
    return np.uint64((j * NODE_ROWS + field) * LANES + l)


@jit_inline
def lane_coefficients(coef, l):
    """Coefficients and time steps of lane ``l`` (``LK_*`` order), read once per loop body."""
    return (
        coef[LK_VALVE_MASS * LANES + l],
        coef[LK_COIL_MASS * LANES + l],
        coef[LK_RATE * LANES + l],
        coef[LK_DAMPER * LANES + l],
        coef[LK_GAP * LANES + l],
        coef[LK_KC * LANES + l],
        coef[LK_CC * LANES + l],
        coef[LK_K * LANES + l],
        coef[LK_B * LANES + l],
        coef[LK_KZ * LANES + l],
        coef[LK_BZ * LANES + l],
        coef[LK_GAMMA * LANES + l],
        coef[LK_PRELOAD * LANES + l],
        coef[LK_DEPTH * LANES + l],
        coef[LK_SPEED * LANES + l],
        coef[LK_SPRING_RATE * LANES + l],
        coef[LK_INV_COIL * LANES + l],
        coef[LK_TAU * LANES + l],
        coef[LK_HALF * LANES + l],
        coef[LK_SIXTH * LANES + l],
    )


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
        values = c[1:]  # rows LK_VALVE_MASS … LK_SPEED, in chain_coefficients order
        for r in range(len(values)):
            coef[r * LANES + l] = values[r]
        coil_mass, depth, speed = c[2], c[14], c[15]
        coef[LK_SPRING_RATE * LANES + l] = row[SC_SPRING_RATE]
        coef[LK_INV_COIL * LANES + l] = 1.0 / coil_mass
        tau = sub_angle / speed
        coef[LK_TAU * LANES + l] = tau
        coef[LK_HALF * LANES + l] = 0.5 * tau
        coef[LK_SIXTH * LANES + l] = tau / 6.0
        for i in range(n + 1):
            share = (i + 1) / (n + 1)
            nodes[node_at(i + 1, NODE_X, l)] = share * row[SC_INITIAL_LIFT]
            nodes[node_at(i + 1, NODE_V, l)] = share * row[SC_INITIAL_VELOCITY]
        for r, value in (
            (LO_MAX_LIFT, -math.inf),
            (LO_MAX_V, -math.inf),
            (LO_MIN_V, math.inf),
            (LO_MIN_MARGIN, math.inf),
            (LO_MIN_RATIO, math.inf),
            (LO_JUMP_START, math.nan),
            (LO_SEATING, math.nan),
        ):
            obs[r * LANES + l] = value
        lift = nodes[node_at(n + 1, NODE_X, l)]
        obs[LO_PHASE * LANES + l] = 1.0 if lift > depth else 0.0
        obs[LO_PREV_LIFT * LANES + l] = lift
        obs[LO_PREV_V * LANES + l] = nodes[node_at(n + 1, NODE_V, l)]


@jit
def finish_chain_lanes(block, count, masses, substeps, cases, out):
    """Write the ``CO_*`` outputs of the first ``count`` lanes into rows ``cases`` of ``out``
    (``CO_STEP_RATIO`` is left as the guard set it)."""
    _, obs, nodes = block
    n = masses
    for l in range(count):
        row = out[cases[l]]
        for column, r in (
            (CO_MAX_LIFT, LO_MAX_LIFT),
            (CO_MAX_VELOCITY, LO_MAX_V),
            (CO_MIN_VELOCITY, LO_MIN_V),
            (CO_JUMP_START, LO_JUMP_START),
            (CO_JUMP_DURATION, LO_JUMP_ANGLE),
            (CO_JUMP_GAP, LO_JUMP_GAP),
            (CO_BOUNCE_COUNT, LO_BOUNCES),
            (CO_BOUNCE_HEIGHT, LO_BOUNCE_HEIGHT),
            (CO_SEATING_VELOCITY, LO_SEATING),
            (CO_MAX_CONTACT_FORCE, LO_MAX_CONTACT),
            (CO_MIN_FORCE_MARGIN, LO_MIN_MARGIN),
            (CO_MIN_RETAINER_RATIO, LO_MIN_RATIO),
            (CO_MAX_RETAINER_DEVIATION, LO_MAX_DEVIATION),
            (CO_SURGE_AMPLITUDE, LO_SURGE),
        ):
            row[column] = obs[r * LANES + l]
        if obs[LO_PREV_LIFT * LANES + l] > block[0][LK_DEPTH * LANES + l]:  # off its seat
            row[CO_BOUNCE_COUNT] = math.nan  # at the window's end: bounces unknown (physics §4)
            row[CO_BOUNCE_HEIGHT] = math.nan
        clashes = 0.0
        finite = True
        for j in range(n + 2):
            clashes += nodes[node_at(j, NODE_CLASHES, l)]
            finite = finite and math.isfinite(nodes[node_at(j, NODE_X, l)])
            finite = finite and math.isfinite(nodes[node_at(j, NODE_V, l)])
        row[CO_CLASH_COUNT] = clashes
        scale = max(obs[LO_ENERGY_MAX * LANES + l], obs[LO_WORK_MAX * LANES + l])
        excess = obs[LO_EXCESS * LANES + l]
        row[CO_ENERGY_EXCESS] = excess / scale if scale > 0.0 else 0.0
        row[CO_SUBSTEPS] = substeps
        row[CO_STATUS] = chain_status(finite, row[CO_ENERGY_EXCESS])
