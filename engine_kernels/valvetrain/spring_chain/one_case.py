"""Valve dynamics with the multi-mass spring [V4]: fixed-step RK4 per case, batch entry.

The chain model is in :mod:`engine_kernels.valvetrain.spring_chain.model`, its rows in
:mod:`engine_kernels.valvetrain.spring_chain.layout`. The excitation table and the cam-angle
grid are those of the lumped kernel (:func:`engine_kernels.valvetrain.valve_response`): rows
Y, Y', Y'' at spacing ``table_step``, RK4 grid step twice that, time step ``Δθ/ω``.

The stability guard (equal sub-steps from a bound on every contact state, cases past
``max_substeps`` refused) is in :mod:`engine_kernels.valvetrain.spring_chain.guard`. The run
itself is checked from the physics, not only for NaN: the energy may grow only by the cam's
work through the drive (``dE/dt ≤ F_drive Ẏ``), and an excess above ``ENERGY_SLACK`` of the
run's energy scale is ``STATUS_UNSTABLE``.

Observations are taken at every RK4 sub-step point (a coil clash or a seat landing can last
less than a grid step). The batch entry :func:`spring_chain_response_batch` runs blocks of
cases in SIMD lanes (:mod:`engine_kernels.valvetrain.spring_chain.lanes`), with the same
numbers. Reference: physics §4 [V2], [V4].
"""

from __future__ import annotations

import math

import numpy as np

from engine_kernels._jit import batch, jit, prange
from engine_kernels.valvetrain.spring_chain.guard import chain_status, prepare_chain_case
from engine_kernels.valvetrain.spring_chain.lane_batch import (
    MIN_BLOCK_CASES,
    block_key,
    lane_block,
)
from engine_kernels.valvetrain.spring_chain.layout import (
    CC_DRIVE_FORCE,
    CC_ENERGY,
    CC_LIFT,
    CC_RETAINER_FORCE,
    CC_SURGE,
    CC_VELOCITY,
    CHAIN_CURVE_NAMES,
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
from engine_kernels.valvetrain.spring_chain.model import (
    chain_accelerations,
    chain_coefficients,
    chain_energy,
    surge_displacement,
)
from engine_kernels.valvetrain.valve.lane_batch import block_schedule, scheduled_block
from engine_kernels.valvetrain.valve.model import excitation_lift_slope, positive_part

# Rows of the per-case scratch array: state, the three inner RK4 stages, segment forces.
_POS, _VEL, _ACC1, _P2, _V2, _ACC2, _P3, _V3, _ACC3, _P4, _V4, _ACC4, _FORCES = range(13)
_SCRATCH_ROWS = 13


@jit
def _rk4_substep(s, tau, ym, vm, y1, v1, c):
    """One classic RK4 step of the chain from the state and first stage in ``s`` (in place).

    s : 2-D scratch (rows ``_POS`` …); tau : float  h [s]; ym, vm / y1, v1 : float  Y [m],
    Ẏ [m/s] at the half step / step end; c : tuple of :func:`chain_coefficients`.
    """
    n = c[0]
    half = 0.5 * tau
    pos, vel = s[_POS], s[_VEL]
    for i in range(n + 1):
        s[_P2, i] = pos[i] + half * vel[i]
        s[_V2, i] = vel[i] + half * s[_ACC1, i]
    chain_accelerations(s[_P2], s[_V2], s[_ACC2], s[_FORCES], ym, vm, *c[:15])
    for i in range(n + 1):
        s[_P3, i] = pos[i] + half * s[_V2, i]
        s[_V3, i] = vel[i] + half * s[_ACC2, i]
    chain_accelerations(s[_P3], s[_V3], s[_ACC3], s[_FORCES], ym, vm, *c[:15])
    for i in range(n + 1):
        s[_P4, i] = pos[i] + tau * s[_V3, i]
        s[_V4, i] = vel[i] + tau * s[_ACC3, i]
    chain_accelerations(s[_P4], s[_V4], s[_ACC4], s[_FORCES], y1, v1, *c[:15])
    sixth = tau / 6.0
    for i in range(n + 1):
        pos[i] += sixth * (vel[i] + 2.0 * (s[_V2, i] + s[_V3, i]) + s[_V4, i])
        vel[i] += sixth * (s[_ACC1, i] + 2.0 * (s[_ACC2, i] + s[_ACC3, i]) + s[_ACC4, i])


@jit
def spring_chain_response(excitation, table_step, table_start, params, settings, out, curves):
    """Valve dynamics of one case with the N-mass spring [V4], fixed-step RK4 (physics §4).

    excitation  : 2-D array  (3, n) rows Y [m], Y' [m/rad], Y'' [m/rad²] at ``table_step``.
    table_step  : float      Table spacing [rad cam]; the RK4 grid step is twice it.
    table_start : float      Cam angle of the first table node [rad].
    params      : 1-D array  ``SC_*`` row (SI units, ``CHAIN_PARAM_UNITS``).
    settings    : 1-D int64  ``S_*`` settings (:func:`~engine_kernels.valvetrain.valve_settings`;
                             only ``max_substeps`` and ``stability_guard`` apply).
    out         : 1-D array  (len(CHAIN_OUTPUT_NAMES),) outputs ``CO_*``.
    curves      : 2-D array  (6, n_steps + 1) curves ``CC_*`` at the grid points, or (6, 0).

    The coils start on the static deflection line of the initial lift and velocity. Outputs
    stay NaN when the case is not integrated (invalid input or sub-step limit).
    """
    substeps = prepare_chain_case(excitation, table_step, params, settings, out)
    if substeps == 0:
        return
    c = chain_coefficients(params)
    n, valve_mass, coil_mass, rate, _, gap, kc, _, k, _, kz, _, _, preload, depth, speed = c
    spring_rate = params[SC_SPRING_RATE]
    s = np.zeros((_SCRATCH_ROWS, n + 1))
    clashing = np.zeros(n + 1, dtype=np.bool_)
    pos, vel, forces = s[_POS], s[_VEL], s[_FORCES]
    for i in range(n + 1):
        share = (i + 1) / (n + 1)
        pos[i] = share * params[SC_INITIAL_LIFT]
        vel[i] = share * params[SC_INITIAL_VELOCITY]
    n_steps = (excitation.shape[1] - 1) // 2
    sub_angle = 2.0 * table_step / substeps
    tau = sub_angle / speed
    store = curves.shape[1] > 0
    max_lift, max_v, min_v, max_contact = -math.inf, -math.inf, math.inf, 0.0
    min_margin, min_ratio, max_deviation, surge = math.inf, math.inf, 0.0, 0.0
    jump_start, jump_angle, jump_gap = math.nan, 0.0, 0.0
    phase = 1 if pos[n] > depth else 0  # 0 seated, 1 open, 2 closed again, 3 bouncing
    seating, bounces, bounce_height, clashes = math.nan, 0, 0.0, 0
    energy0, work, work_max, excess, energy_max = 0.0, 0.0, 0.0, 0.0, 0.0
    prev_lift, prev_v, prev_power = pos[n], vel[n], 0.0
    y0, slope0 = excitation_lift_slope(excitation, table_step, 0.0)
    total = n_steps * substeps
    for m in range(total + 1):
        position = 2.0 * m / substeps
        lift, velocity = pos[n], vel[n]
        v0 = speed * slope0
        drive, _ = chain_accelerations(pos, vel, s[_ACC1], forces, y0, v0, *c[:15])
        retainer = forces[n]
        energy = chain_energy(
            pos, vel, y0, n, valve_mass, coil_mass, rate, preload, gap, kc, k, kz, depth
        )
        power = positive_part(drive) * v0
        if m == 0:
            energy0 = energy
        else:
            work += 0.5 * tau * (power + prev_power)
        work_max = max(work_max, abs(work))
        energy_max = max(energy_max, abs(energy))
        excess = max(excess, energy - energy0 - work)
        prev_power = power
        max_lift = max(max_lift, lift)
        max_v = max(max_v, velocity)
        min_v = min(min_v, velocity)
        max_contact = max(max_contact, drive)
        static = preload + spring_rate * lift
        min_ratio = min(min_ratio, retainer / static)
        max_deviation = max(max_deviation, abs(retainer - static))
        deviation = surge_displacement(pos, n)
        surge = max(surge, deviation)
        event = y0 > depth
        if event:
            min_margin = min(min_margin, drive)
            if drive <= 0.0 and lift > depth:
                if math.isnan(jump_start):
                    jump_start = table_start + position * table_step
                jump_angle += sub_angle
                jump_gap = max(jump_gap, lift - y0)
        lower = 0.0
        for j in range(n + 1):
            solid = pos[j] - lower > gap
            if solid and not clashing[j]:
                clashes += 1
            clashing[j] = solid
            lower = pos[j]
        if lift > depth:
            if phase == 0:
                phase = 1
            elif phase >= 2:
                if prev_lift <= depth:
                    bounces += 1
                phase = 3
                bounce_height = max(bounce_height, lift - depth)
        elif phase == 1 and m > 0:
            fraction = (depth - prev_lift) / (lift - prev_lift)
            seating = abs(prev_v + fraction * (velocity - prev_v))
            phase = 2
        prev_lift, prev_v = lift, velocity
        if store and m % substeps == 0:
            g = m // substeps
            curves[CC_LIFT, g] = lift
            curves[CC_VELOCITY, g] = velocity
            curves[CC_DRIVE_FORCE, g] = max(drive, 0.0)
            curves[CC_RETAINER_FORCE, g] = retainer
            curves[CC_SURGE, g] = deviation
            curves[CC_ENERGY, g] = energy
        if m == total:
            break
        ym, slope_m = excitation_lift_slope(excitation, table_step, position + 1.0 / substeps)
        y1, slope1 = excitation_lift_slope(excitation, table_step, position + 2.0 / substeps)
        _rk4_substep(s, tau, ym, speed * slope_m, y1, speed * slope1, c)
        y0, slope0 = y1, slope1
    out[CO_MAX_LIFT] = max_lift
    out[CO_MAX_VELOCITY] = max_v
    out[CO_MIN_VELOCITY] = min_v
    out[CO_JUMP_START] = jump_start
    out[CO_JUMP_DURATION] = jump_angle
    out[CO_JUMP_GAP] = jump_gap
    off_seat = prev_lift > depth  # at the window's end: its bounces are unknown, the coils
    # can feed energy back into the valve (physics §4)
    out[CO_BOUNCE_COUNT] = math.nan if off_seat else bounces
    out[CO_BOUNCE_HEIGHT] = math.nan if off_seat else bounce_height
    out[CO_SEATING_VELOCITY] = seating
    out[CO_MAX_CONTACT_FORCE] = max_contact
    out[CO_MIN_FORCE_MARGIN] = min_margin
    out[CO_MIN_RETAINER_RATIO] = min_ratio
    out[CO_MAX_RETAINER_DEVIATION] = max_deviation
    out[CO_SURGE_AMPLITUDE] = surge
    out[CO_CLASH_COUNT] = clashes
    scale = max(energy_max, work_max)
    out[CO_ENERGY_EXCESS] = excess / scale if scale > 0.0 else 0.0
    out[CO_SUBSTEPS] = substeps
    finite = True
    for i in range(n + 1):
        finite = finite and math.isfinite(pos[i]) and math.isfinite(vel[i])
    out[CO_STATUS] = chain_status(finite, out[CO_ENERGY_EXCESS])


@batch
def spring_chain_one_case_batch(excitation, table_step, table_start, params, settings, out):
    """:func:`spring_chain_response` for many cases, one per prange iteration (no curves).

    params : 2-D array  (n_cases, len(CHAIN_PARAM_NAMES)) ``SC_*`` rows (N may differ per row).
    out    : 2-D array  (n_cases, len(CHAIN_OUTPUT_NAMES)) outputs ``CO_*``.
    Other arguments as in :func:`spring_chain_response`. The reference of the lane kernel; the
    batch entry is :func:`spring_chain_response_batch`.
    """
    for i in prange(params.shape[0]):
        spring_chain_response(
            excitation,
            table_step,
            table_start,
            params[i],
            settings,
            out[i],
            np.empty((len(CHAIN_CURVE_NAMES), 0)),
        )


@batch
def spring_chain_response_batch(excitation, table_step, table_start, params, settings, out):
    """Valve dynamics with the N-mass spring for many cases: the batch entry (no curves).

    The outputs of :func:`spring_chain_one_case_batch`, bit for bit, from ``LANES`` cases per
    SIMD block (:mod:`engine_kernels.valvetrain.spring_chain.lane_batch`); a block of fewer
    than ``MIN_BLOCK_CASES`` runs its cases one at a time, where the lanes would cost more.
    params : 2-D array  (n_cases, len(CHAIN_PARAM_NAMES)) ``SC_*`` rows (N may differ per row).
    out    : 2-D array  (n_cases, len(CHAIN_OUTPUT_NAMES)) outputs ``CO_*``.
    Other arguments as in :func:`spring_chain_response`. Reference: physics §4 [V4]; STYLE "Hot
    integrators".
    """
    n_cases = params.shape[0]
    keys = np.empty(n_cases, dtype=np.int64)
    for i in prange(n_cases):
        substeps = prepare_chain_case(excitation, table_step, params[i], settings, out[i])
        keys[i] = block_key(substeps, params[i])
    order, starts, schedule = block_schedule(keys)
    for i in prange(schedule.shape[0]):
        block = scheduled_block(order, starts, schedule, i)
        if block.shape[0] >= MIN_BLOCK_CASES:
            lane_block(excitation, table_step, table_start, params, block, keys[block[0]], out)
            continue
        for case in block:
            spring_chain_response(
                excitation,
                table_step,
                table_start,
                params[case],
                settings,
                out[case],
                np.empty((len(CHAIN_CURVE_NAMES), 0)),
            )
