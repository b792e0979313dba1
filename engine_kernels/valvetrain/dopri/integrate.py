"""Adaptive Dormand–Prince 5(4) for the valve model [V2] with located switches (physics §4).

One case at a time: the pair of :mod:`engine_kernels.valvetrain.dopri.step` steps in time
with the drive contact and the seat contact held fixed inside each step; its step size
follows an absolute lift tolerance (and a velocity tolerance scaled by the camshaft speed,
see :func:`dopri_response`), so a stiff seat sets short steps only while it is excited. After each accepted step the drive force and the seat function are sampled on the
step's dense output; at the first sample past a switch the crossing is located on the dense
output, the step is redone from its start to just past it and the mode changes there. Unlike
the RK4 kernels, the excitation table is an input of its own spacing: it is read by cubic
Hermite interpolation at every stage, and the observations are taken on a separate grid of
cam angles (the study's curve grid) by dense output, with the same running observations as
the RK4 kernels (:mod:`engine_kernels.valvetrain.valve.observations`), the seat phase also being
followed at every step end. No stability guard is needed: the error estimate of the pair
keeps the steps inside its stability region.

Reference: Hairer, Nørsett & Wanner, *Solving ODEs I*, §II.4 (step-size control), §II.6
(dense output); physics §4.
"""

from __future__ import annotations

import math

import numpy as np

from engine_kernels._jit import batch, jit, prange
from engine_kernels.valvetrain.dopri.observe import (
    grid_points,
    observe_grid_point,
    observe_inside_step,
    observe_point,
    observe_turn,
    record_closure,
    stop_run,
)
from engine_kernels.valvetrain.dopri.step import (
    SWITCH_ANGLE_TOLERANCE,
    dense_state,
    dopri_step,
    locate_switch,
    mode_acceleration,
    mode_violation,
    switching_functions,
    velocity_turn,
)
from engine_kernels.valvetrain.valve.guard import valid_valve_parameters
from engine_kernels.valvetrain.valve.layout import (
    C_LIFT,
    K_SEAT_DEPTH,
    N_RECORD,
    O_STATUS,
    O_STEP_RATIO,
    O_SUBSTEPS,
    P_INITIAL_LIFT,
    P_INITIAL_VELOCITY,
    P_PRELOAD,
    P_SPEED,
    STATUS_INVALID_INPUT,
    STATUS_NONFINITE,
    STATUS_SUBSTEP_LIMIT,
    VALVE_CURVE_NAMES,
)
from engine_kernels.valvetrain.valve.model import (
    TRANSITION_BAND,
    case_coefficients,
    excitation_lift_slope,
    valve_coefficients,
    valve_spectral_radius,
)
from engine_kernels.valvetrain.valve.observations import (
    finish_observations,
    nose_position,
    observe_closure,
)
from engine_kernels.valvetrain.valve.step import valve_time_steps

SAFETY = 0.9
FAC_MIN = 0.2
FAC_MAX = 5.0
SWITCH_SAMPLES = 8
"""Points of a step's dense output (equally spaced, the end included) where the switching
functions are checked and the seat phase is followed (a bounce shorter than a step): a switch that is crossed and crossed back between two of them (a
grazing contact) is missed. On 48 random points at 1e-8 m per step, 4 points missed one
grazing contact (0.63 µm error at one point); 8 and 16 did not, at ~10 % more cost."""
DEFAULT_MAX_STEPS = 1_000_000
"""Step attempts (accepted, rejected and redone at a switch) after which a case stops with
``STATUS_SUBSTEP_LIMIT``."""


@jit
def _initial_mode(lift, velocity, drive_lift, slope, c):
    """Contact and seat modes of a state: each on while its switching function is positive."""
    drive, seat = switching_functions(lift, velocity, drive_lift, slope, c)
    return drive > 0.0, seat > 0.0


@jit
def dopri_response(
    excitation,
    table_step,
    table_start,
    grid_step,
    params,
    tolerance,
    max_step,
    max_steps,
    out,
    curves,
):
    """Valve dynamics of one case by adaptive DP5(4) with located switches, outputs ``O_*``.

    excitation  : 2-D array  (3, n) rows Y [m], Y' [m/rad], Y'' [m/rad²] of the theoretical
                             valve lift at spacing ``table_step``, from ``table_start``.
    table_step  : float      Table spacing [rad cam], independent of the grid and the steps.
    table_start : float      Cam angle of the first node [rad]; the run starts there.
    grid_step   : float      Spacing [rad] of the observation grid (from ``table_start`` to the
                             last grid point inside the table, :func:`grid_points`).
    params      : 1-D array  Parameter row (``P_*``, SI units).
    tolerance   : float      Absolute lift tolerance per step [m]; the velocity tolerance is
                             ``tolerance·ω`` [m/s]: a velocity error kept through a free
                             flight of about a radian of cam grows into a lift error of
                             that size.
    max_step    : float      Longest step [rad of cam], 0 for none: without it the steps grow
                             fivefold per step while the valve rests, and a step then spans
                             tens of degrees; the error bar's companion run caps its steps
                             so that its switch detection does not share the run's long steps.
    max_steps   : int        Step attempts allowed before ``STATUS_SUBSTEP_LIMIT``.
    out         : 1-D array  Outputs ``O_*``: as :func:`engine_kernels.valvetrain.valve_response`,
                             but ``O_SUBSTEPS`` holds the accepted DP5 steps and
                             ``O_STEP_RATIO`` the largest ``h·|λ|_max`` of one.
    curves      : 2-D array  (5, n_grid) curves ``C_*`` at the grid points, or (5, 0).

    Outputs stay NaN when the case does not finish (``STATUS_INVALID_INPUT``, the step limit
    ``STATUS_SUBSTEP_LIMIT``, ``STATUS_NONFINITE`` when the step size collapses on a
    non-finite state). Reference: physics §4.
    """
    out[:] = math.nan
    if not (valid_valve_parameters(params, excitation) and tolerance > 0.0 and grid_step > 0.0):
        out[O_STATUS] = STATUS_INVALID_INPUT
        return
    speed = params[P_SPEED]
    n_grid = grid_points(excitation, table_step, grid_step)
    grid_time = grid_step / speed
    end = (n_grid - 1) * grid_time
    record = np.empty(N_RECORD)
    valve_coefficients(params, record, 0, 1)
    valve_time_steps(record, 0, 1, grid_step, 1)
    c = case_coefficients(record, 0, 1)
    band = TRANSITION_BAND * params[P_PRELOAD]
    velocity_tolerance = tolerance * speed
    radius = valve_spectral_radius(params)
    nose = table_start + nose_position(excitation) * table_step
    lift, velocity = params[P_INITIAL_LIFT], params[P_INITIAL_VELOCITY]
    drive_lift, slope = excitation_lift_slope(excitation, table_step, 0.0)
    mode = _initial_mode(lift, velocity, drive_lift, slope, c)
    acc = mode_acceleration(lift, velocity, drive_lift, slope, mode[0], mode[1], c)
    prev = (
        lift,
        velocity,
        observe_grid_point(
            record,
            0,
            n_grid - 1,
            table_start,
            table_start >= nose,
            lift,
            velocity,
            drive_lift,
            slope,
            curves,
        )[0],
        0.0,
    )
    longest = max_step / speed if max_step > 0.0 else end
    h = min(end, longest, 1.0 / radius) if radius > 0.0 else min(end, longest)
    dense = np.empty(10)
    time = 0.0
    next_grid = 1
    attempts = 0
    switched = -1
    fresh = False
    accepted = 0
    largest_ratio = 0.0
    while next_grid < n_grid:
        if attempts >= max_steps:
            stop_run(out, curves, STATUS_SUBSTEP_LIMIT)
            return
        attempts += 1
        last = h >= end - time
        if last:
            h = end - time
        new_lift, new_velocity, new_acc, error_lift, error_velocity = dopri_step(
            excitation, table_step, speed, time, h, lift, velocity, acc, mode, c, dense
        )
        error = max(abs(error_lift) / tolerance, abs(error_velocity) / velocity_tolerance)
        if not error <= 1.0:
            h *= max(FAC_MIN, SAFETY * error**-0.2) if math.isfinite(error) else FAC_MIN
            if h <= 1e-14 * end:
                stop_run(out, curves, STATUS_NONFINITE)
                return
            continue
        length = h
        which = -1
        lo = 0.0
        for j in range(1, SWITCH_SAMPLES + 1):
            s = j / SWITCH_SAMPLES
            past = mode_violation(excitation, table_step, speed, time, h, dense, s, mode, band, c)
            first = 2.0
            for index in range(2):
                # Right after a switch the new mode may start a hair inside the dead band
                # of the old side (the redone step ends near, not on, the interpolant's
                # root): that guard is not searched from the start of this step.
                if past[index] > 0.0 and not (j == 1 and index == switched and fresh):
                    root = locate_switch(
                        excitation,
                        table_step,
                        speed,
                        time,
                        h,
                        dense,
                        lo,
                        s,
                        index,
                        mode,
                        band,
                        c,
                    )
                    if root < first:
                        first, which = root, index
            if which >= 0:
                length = first * h
                last = False
                new_lift, new_velocity, new_acc, _, _ = dopri_step(
                    excitation,
                    table_step,
                    speed,
                    time,
                    length,
                    lift,
                    velocity,
                    acc,
                    mode,
                    c,
                    dense,
                )
                attempts += 1
                break
            lo = s
        fresh = False
        stop = end if last else time + length
        on_grid = False
        # a maximum of the lift inside the step: located on the dense output and observed as a
        # point of its own, in time order among the grid points
        turn = (
            time + length * velocity_turn(dense, SWITCH_ANGLE_TOLERANCE / (length * speed))
            if velocity > 0.0 and not new_velocity > 0.0
            else math.inf
        )
        # Inside a step the valve can cross the seat plane unseen only while off its seat
        # with an end of the step below the plane (a landing is a located switch).
        sample = 1 if not mode[1] and min(lift, new_lift) <= c[K_SEAT_DEPTH] else SWITCH_SAMPLES
        while next_grid < n_grid and next_grid * grid_time <= stop:
            at = next_grid * grid_time
            on_grid = at == stop
            while sample < SWITCH_SAMPLES and sample * length < SWITCH_SAMPLES * (at - time):
                prev = observe_inside_step(
                    record,
                    excitation,
                    table_step,
                    table_start,
                    nose,
                    time,
                    length,
                    dense,
                    sample / SWITCH_SAMPLES,
                    prev,
                )
                sample += 1
            if turn < at:
                observe_turn(record, excitation, table_step, table_start, time, length, dense, turn)
                turn = math.inf
            y, v = dense_state(dense, (at - time) / length)
            angle = table_start + next_grid * grid_step
            drive_lift, slope = excitation_lift_slope(
                excitation, table_step, next_grid * grid_step / table_step
            )
            acc_here, event = observe_grid_point(
                record,
                next_grid,
                n_grid - 1,
                angle,
                angle >= nose,
                y,
                v,
                drive_lift,
                slope,
                curves,
            )
            if event:
                record_closure(record, excitation, table_step, prev)
            prev = (y, v, acc_here, at)
            next_grid += 1
        for inside in range(sample, SWITCH_SAMPLES):
            prev = observe_inside_step(
                record,
                excitation,
                table_step,
                table_start,
                nose,
                time,
                length,
                dense,
                inside / SWITCH_SAMPLES,
                prev,
            )
        if turn < math.inf:
            observe_turn(record, excitation, table_step, table_start, time, length, dense, turn)
        accepted += 1
        largest_ratio = max(largest_ratio, length * radius)
        time = stop
        lift, velocity, acc = new_lift, new_velocity, new_acc
        if not (math.isfinite(lift) and math.isfinite(velocity)):
            stop_run(out, curves, STATUS_NONFINITE)
            return
        if not on_grid and next_grid < n_grid:
            if which >= 0:
                observe_point(
                    record,
                    excitation,
                    table_step,
                    table_start,
                    time,
                    lift,
                    velocity,
                    which == 0,
                    which == 0 and mode[0],
                )
            if observe_closure(record, 0, 1, lift, table_start + time * speed >= nose):
                # A located seat switch ends this step on the seat plane: the seating
                # velocity is read there, not extrapolated over a whole step.
                if which == 1:
                    prev = (lift, velocity, acc, time)
                record_closure(record, excitation, table_step, prev)
            prev = (lift, velocity, acc, time)
        if which >= 0:
            drive_lift, slope = excitation_lift_slope(
                excitation, table_step, time * speed / table_step
            )
            changed = _initial_mode(lift, velocity, drive_lift, slope, c)
            contact, seated = changed
            if changed[which] == mode[which]:
                if which == 0:
                    contact = not mode[0]
                else:
                    seated = not mode[1]
            mode = (contact, seated)
            acc = mode_acceleration(lift, velocity, drive_lift, slope, contact, seated, c)
            switched = which
            fresh = True
        h *= min(FAC_MAX, max(FAC_MIN, SAFETY * error**-0.2)) if error > 0.0 else FAC_MAX
        h = min(h, longest)
    finish_observations(record, 0, 1, grid_step, lift, velocity, out, tolerance)
    out[O_SUBSTEPS] = accepted
    out[O_STEP_RATIO] = largest_ratio


@batch
def dopri_batch(
    excitation,
    table_step,
    table_start,
    grid_step,
    params,
    tolerance,
    max_step,
    max_steps,
    out,
    lifts,
):
    """:func:`dopri_response` for many cases, one case per prange iteration.

    params : 2-D array  (n_cases, len(VALVE_PARAM_NAMES)) rows indexed by ``P_*``.
    out    : 2-D array  (n_cases, len(VALVE_OUTPUT_NAMES)) outputs.
    lifts  : 2-D array  (n_cases, n_grid) out: lift y [m] at every grid point (NaN where the
                        case did not finish), or (n_cases, 0) for none.
    Other arguments as in :func:`dopri_response`.
    """
    for i in prange(params.shape[0]):
        curves = np.empty((len(VALVE_CURVE_NAMES), lifts.shape[1]))
        curves[:, :] = np.nan
        dopri_response(
            excitation,
            table_step,
            table_start,
            grid_step,
            params[i],
            tolerance,
            max_step,
            max_steps,
            out[i],
            curves,
        )
        if lifts.shape[1] > 0:
            lifts[i, :] = curves[C_LIFT]
