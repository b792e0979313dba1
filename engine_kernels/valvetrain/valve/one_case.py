"""Valve-train dynamics: single-DOF valve driven through a compliant rocker (physics §4).

The model [V1], [V2] is in :mod:`engine_kernels.valvetrain.valve.model`, its data layout (``P_*``
parameters, ``O_*`` outputs, ``C_*`` curves, ``S_*`` settings, status codes) in
:mod:`engine_kernels.valvetrain.valve.layout`; this module integrates one case at a time. The
package :mod:`engine_kernels.valvetrain` re-exports the public API of the valve kernels, so
it is the one import a caller needs.

Integration is fixed-step classic RK4 over a cam-angle grid: the excitation table holds the
theoretical valve lift Y(θ) and its angle derivatives at half-step spacing (physics §9: RK4 step
0.5° cam, excitation every 0.25°), the time step is ``Δθ/ω`` and ``Ẏ = ω Y'``. The valve
starts at the initial lift and velocity of the parameter row (normally at rest on the seat).
The stability guard (:mod:`engine_kernels.valvetrain.valve.guard`) sub-steps or refuses a case before
integrating it; the running observations and the physics check of the run are in
:mod:`engine_kernels.valvetrain.valve.observations`; switch-aware stepping (settings
``switch_aware = 1``) is in :mod:`engine_kernels.valvetrain.valve.switching`. The step-halving
difference (``estimate_error = 1``) compares the lift over the grid with a second run at twice
the sub-steps (each sub-step half as long, so always within the stability bound); the scene
turns it into an error bar (:mod:`studies.scenes.valve.error_bar`).

:mod:`engine_kernels.valvetrain.valve.lanes` runs the same plain-RK4 integration, with the same
arithmetic and results, for blocks of cases in SIMD lanes: about 4× more cases per CPU-second
at the physics §9 step. Reference: physics §4 and the thesis data quoted there.
"""

from __future__ import annotations

import numpy as np

from engine_kernels._jit import batch, jit, jit_inline, prange
from engine_kernels.valvetrain.valve.energy_balance import ENERGY_INTERVAL, observe_energy
from engine_kernels.valvetrain.valve.guard import prepare_case
from engine_kernels.valvetrain.valve.layout import (
    C_ACCELERATION,
    C_DRIVE_FORCE,
    C_LIFT,
    C_SEAT_FORCE,
    C_VELOCITY,
    K_MASS,
    K_SEAT_DEPTH,
    K_SPEED,
    N_RECORD,
    O_ERROR_ESTIMATE,
    P_INITIAL_LIFT,
    P_INITIAL_VELOCITY,
    S_ESTIMATE_ERROR,
    S_SWITCH_AWARE,
    VALVE_CURVE_NAMES,
)
from engine_kernels.valvetrain.valve.located import jerk_at
from engine_kernels.valvetrain.valve.model import (
    case_coefficients,
    drive_push,
    excitation_lift_slope,
    lash_clip,
    specific_point,
    valve_coefficients,
)
from engine_kernels.valvetrain.valve.observations import (
    finish_observations,
    nose_position,
    observe_closure,
    observe_valve,
    record_closure_events,
    start_observations,
)
from engine_kernels.valvetrain.valve.step import rk4_valve_step, valve_time_steps
from engine_kernels.valvetrain.valve.switching import switch_aware_step


@jit_inline
def _observe_substep(record, excitation, table_step, prev, lift, past_nose):
    """Seat phase at an RK4 sub-step point inside a grid step (``observe_closure``).

    A contact with a stiff seat can begin and end between two grid points, but it lasts
    about half a period of the seat mode, π/ω, longer than a sub-step (the stability guard
    keeps h·ω ≤ 2): following the phase at every sub-step point sees every landing, so a
    rebound counts as a bounce, not as a jump. ``prev`` is the previous sub-step point:
    (table position [-], lift [m], velocity [m/s], acceleration [m/s²]); ``past_nose``: this
    one is at or past the cam's nose.
    """
    if observe_closure(record, 0, 1, lift, past_nose):
        _record_closure(record, excitation, table_step, prev)


@jit
def _record_closure(record, excitation, table_step, prev):
    """``record_closure_events`` with the previous point ``prev`` (see :func:`_observe_substep`)."""
    position, lift, velocity, acc = prev
    jerk = jerk_at(
        excitation, table_step, position, lift, velocity, acc, case_coefficients(record, 0, 1)
    )
    record_closure_events(record, 0, 1, lift, velocity, acc, jerk)


@jit
def _integrate(
    excitation,
    table_step,
    table_start,
    params,
    substeps,
    switch_aware,
    record,
    out,
    curves,
    trace,
    compare,
):
    """Integrate one case over the table with RK4 grid step ``2·table_step``.

    record : 1-D array  The case record (layout in :mod:`engine_kernels.valvetrain.valve.layout`),
                        coefficients ``K_*`` already written by ``valve_coefficients``.
    Fills ``out`` (``O_*`` rows from :func:`finish_observations`), the curves if
    ``curves`` has columns, and either records the lift at each grid point into ``trace`` or
    (``compare``) returns the largest difference from a trace recorded on the same grid.
    """
    half = 1
    n_steps = (excitation.shape[1] - 1) // (2 * half)
    grid_step = 2.0 * half * table_step
    valve_time_steps(record, 0, 1, grid_step, substeps)
    c = case_coefficients(record, 0, 1)
    speed = c[K_SPEED]
    mass = c[K_MASS]
    depth = c[K_SEAT_DEPTH]
    lift = params[P_INITIAL_LIFT]
    velocity = params[P_INITIAL_VELOCITY]
    prev = (0.0, lift, velocity, 0.0)  # set before it is read
    nose = nose_position(excitation)
    store = curves.shape[1] > 0
    record_trace = trace.shape[0] > 0
    difference = 0.0
    for n in range(n_steps + 1):
        node = 2 * half * n
        drive_lift, slope = lash_clip(excitation[0, node], excitation[1, node])
        drive_velocity = speed * slope
        drive, seat, acc = specific_point(lift, velocity, drive_lift, slope, c)
        angle = table_start + n * grid_step
        if n == 0:
            start_observations(
                record, 0, 1, angle, lift, velocity, acc, drive_lift, drive_velocity, drive, seat
            )
        elif observe_valve(
            record,
            0,
            1,
            angle,
            lift,
            velocity,
            acc,
            drive_lift,
            drive_velocity,
            drive,
            seat,
            node >= nose,
        ):
            _record_closure(record, excitation, table_step, prev)
        if n % ENERGY_INTERVAL == 0 or n == n_steps:
            observe_energy(record, 0, 1, lift, velocity, drive_lift, drive_velocity, drive)
        if store:
            curves[C_LIFT, n] = lift
            curves[C_VELOCITY, n] = velocity
            curves[C_ACCELERATION, n] = acc
            curves[C_DRIVE_FORCE, n] = mass * max(0.0, drive)
            seated = (seat > 0.0) & (lift < depth)
            curves[C_SEAT_FORCE, n] = mass * seat if seated else 0.0
        if record_trace:
            if compare:
                difference = max(difference, abs(lift - trace[n]))
            else:
                trace[n] = lift
        if n == n_steps:
            break
        prev = (float(node), lift, velocity, acc)
        if switch_aware:
            for j in range(substeps):
                start = node + 2.0 * half * j / substeps
                if j > 0:
                    y0, s0 = excitation_lift_slope(excitation, table_step, start)
                    _observe_substep(record, excitation, table_step, prev, lift, start >= nose)
                    prev = (start, lift, velocity, specific_point(lift, velocity, y0, s0, c)[2])
                stop = node + 2.0 * half * (j + 1) / substeps
                lift, velocity, _ = switch_aware_step(
                    excitation, table_step, start, stop, lift, velocity, params
                )
        elif substeps == 1:
            ym, sm = lash_clip(excitation[0, node + half], excitation[1, node + half])
            y1, s1 = lash_clip(excitation[0, node + 2 * half], excitation[1, node + 2 * half])
            lift, velocity = rk4_valve_step(
                lift, velocity, acc, drive_push(ym, sm, c), drive_push(y1, s1, c), c
            )
        else:
            for j in range(substeps):
                position = node + 2.0 * half * j / substeps
                y0, s0 = excitation_lift_slope(excitation, table_step, position)
                ym, sm = excitation_lift_slope(
                    excitation, table_step, node + 2.0 * half * (j + 0.5) / substeps
                )
                y1, s1 = excitation_lift_slope(
                    excitation, table_step, node + 2.0 * half * (j + 1) / substeps
                )
                _, _, a0 = specific_point(lift, velocity, y0, s0, c)
                if j > 0:
                    _observe_substep(record, excitation, table_step, prev, lift, position >= nose)
                    prev = (position, lift, velocity, a0)
                lift, velocity = rk4_valve_step(
                    lift,
                    velocity,
                    a0,
                    drive_push(ym, sm, c),
                    drive_push(y1, s1, c),
                    c,
                )
    finish_observations(record, 0, 1, grid_step, lift, velocity, out)
    return difference


@jit
def valve_response(excitation, table_step, table_start, params, settings, out, curves):
    """Valve dynamics of one case: fixed-step RK4 of [V2] with outputs ``O_*`` (physics §4).

    excitation  : 2-D array  (3, n) rows Y [m], Y' [m/rad], Y'' [m/rad²] of the theoretical
                             valve lift at spacing ``table_step`` (half the RK4 step).
    table_step  : float      Table spacing [rad cam]; the RK4 grid step is twice it.
    table_start : float      Cam angle of the first table node [rad].
    params      : 1-D array  Parameter row indexed by ``P_*`` (SI units, ``VALVE_PARAM_UNITS``).
    settings    : 1-D int64  ``S_*`` settings from :func:`valve_settings`.
    out         : 1-D array  (len(VALVE_OUTPUT_NAMES),) outputs, units ``VALVE_OUTPUT_UNITS``.
    curves      : 2-D array  (5, n_steps + 1) curves ``C_*`` at the grid points, or (5, 0).

    Outputs stay NaN when the case is not integrated (``STATUS_INVALID_INPUT``,
    ``STATUS_SUBSTEP_LIMIT``); ``O_SUBSTEPS`` and ``O_STEP_RATIO`` are always filled once the
    inputs are valid. Reference: physics §4.
    """
    substeps = prepare_case(excitation, table_step, params, settings, out)
    if substeps == 0:
        return
    switch_aware = settings[S_SWITCH_AWARE] != 0
    estimate = settings[S_ESTIMATE_ERROR] != 0 and excitation.shape[1] >= 5
    record = np.empty(N_RECORD)
    valve_coefficients(params, record, 0, 1)
    trace = np.empty((excitation.shape[1] - 1) // 2 + 1 if estimate else 0)
    _integrate(
        excitation,
        table_step,
        table_start,
        params,
        substeps,
        switch_aware,
        record,
        out,
        curves,
        trace,
        False,
    )
    if estimate:
        scratch = np.empty(out.shape[0])
        difference = _integrate(
            excitation,
            table_step,
            table_start,
            params,
            2 * substeps,
            switch_aware,
            record,
            scratch,
            curves[:, :0],
            trace,
            True,
        )
        out[O_ERROR_ESTIMATE] = difference


@batch
def valve_response_batch(excitation, table_step, table_start, params, settings, out):
    """:func:`valve_response` for many cases, one case per prange iteration (no curves).

    params : 2-D array  (n_cases, len(VALVE_PARAM_NAMES)) rows indexed by ``P_*``.
    out    : 2-D array  (n_cases, len(VALVE_OUTPUT_NAMES)) outputs.
    Other arguments as in :func:`valve_response`.
    """
    for i in prange(params.shape[0]):
        valve_response(
            excitation,
            table_step,
            table_start,
            params[i],
            settings,
            out[i],
            np.empty((len(VALVE_CURVE_NAMES), 0)),
        )


@batch
def valve_lift_batch(excitation, table_step, table_start, params, settings, out, lifts):
    """:func:`valve_response_batch` that also keeps each case's lift at every grid point.

    lifts : 2-D array  (n_cases, (excitation.shape[1] − 1)//2 + 1) lift y [m] per grid point,
                       NaN where the case is not integrated. The error bars of the scene
                       compare these between runs on differently refined grids.
    Other arguments as in :func:`valve_response_batch`.
    """
    for i in prange(params.shape[0]):
        curves = np.empty((len(VALVE_CURVE_NAMES), lifts.shape[1]))
        curves[C_LIFT, :] = np.nan
        valve_response(excitation, table_step, table_start, params[i], settings, out[i], curves)
        lifts[i, :] = curves[C_LIFT]
