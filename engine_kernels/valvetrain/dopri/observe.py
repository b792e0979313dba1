"""Observations of a Dormand–Prince valve run on its grid of cam angles (physics §4).

The adaptive steps of :mod:`engine_kernels.valvetrain.dopri.integrate` do not fall on the study's grid;
its dense output gives the state at every grid point, and these helpers feed it to the
running observations of the RK4 kernels (:mod:`engine_kernels.valvetrain.valve.observations`), so
max lift, jump, bounce, seating velocity and the energy check mean the same for every
integrator.
"""

from __future__ import annotations

import math

from engine_kernels._jit import jit
from engine_kernels.valvetrain.dopri.step import dense_state
from engine_kernels.valvetrain.valve.energy_balance import ENERGY_INTERVAL, observe_energy
from engine_kernels.valvetrain.valve.layout import (
    C_ACCELERATION,
    C_DRIVE_FORCE,
    C_LIFT,
    C_SEAT_FORCE,
    C_VELOCITY,
    K_MASS,
    K_SEAT_DEPTH,
    K_SPEED,
    O_STATUS,
    ST_PREV_ANGLE,
)
from engine_kernels.valvetrain.valve.located import (
    drive_force_rate,
    excitation_curvature,
    jerk_at,
    observe_peak,
    remember_point,
)
from engine_kernels.valvetrain.valve.model import (
    case_coefficients,
    excitation_lift_slope,
    specific_point,
)
from engine_kernels.valvetrain.valve.observations import (
    observe_closure,
    observe_valve,
    record_closure_events,
    start_observations,
)


@jit
def grid_points(excitation, table_step, grid_step):
    """Number of grid points ``θ_0 + i·grid_step`` [-] inside the excitation table's span."""
    span = (excitation.shape[1] - 1) * table_step
    return int(span / grid_step * (1.0 + 1e-12)) + 1


@jit
def observe_grid_point(
    record, n, last, angle, past_nose, lift, velocity, drive_lift, slope, curves
):
    """The running observations at grid point ``n`` and its curve column.

    record          : 1-D array  The case record (``K_*`` rows written, ``ST_*`` updated).
    n, last         : int        Index of this grid point and of the last one [-].
    angle           : float      Its cam angle [rad]; past_nose: at or past the cam's nose.
    lift, velocity  : float      Valve state there [m], [m/s] (from the dense output).
    drive_lift      : float      Excitation Y [m]; slope: Y' [m/rad].
    curves          : 2-D array  (5, n_grid) curves ``C_*`` written at column n, or (5, 0).
    Returns ÿ [m/s²] and whether the seat phase changed in a way
    :func:`engine_kernels.valvetrain.valve.observations.record_closure_events` must record.
    """
    c = case_coefficients(record, 0, 1)
    speed = record[K_SPEED]
    drive, seat, acc = specific_point(lift, velocity, drive_lift, slope, c)
    event = False
    if n == 0:
        start_observations(
            record, 0, 1, angle, lift, velocity, acc, drive_lift, speed * slope, drive, seat
        )
    else:
        event = observe_valve(
            record,
            0,
            1,
            angle,
            lift,
            velocity,
            acc,
            drive_lift,
            speed * slope,
            drive,
            seat,
            past_nose,
        )
    if n % ENERGY_INTERVAL == 0 or n == last:
        observe_energy(record, 0, 1, lift, velocity, drive_lift, speed * slope, drive)
    if curves.shape[1] > 0:
        mass = record[K_MASS]
        curves[C_LIFT, n] = lift
        curves[C_VELOCITY, n] = velocity
        curves[C_ACCELERATION, n] = acc
        curves[C_DRIVE_FORCE, n] = mass * max(0.0, drive)
        seated = (seat > 0.0) & (lift < record[K_SEAT_DEPTH])
        curves[C_SEAT_FORCE, n] = mass * seat if seated else 0.0
    return acc, event


@jit
def stop_run(out, curves, status):
    """End a run that did not finish: every output (``O_*`` row) and curve NaN, ``status``
    (a ``STATUS_*`` code) in ``O_STATUS``."""
    out[:] = math.nan
    curves[:, :] = math.nan
    out[O_STATUS] = status


@jit
def observe_inside_step(
    record, excitation, table_step, table_start, nose, time, length, dense, s, prev
):
    """Follow the seat phase at the fraction ``s`` of a step (a bounce can begin and end
    between grid points and step ends); returns the state there for the next point.

    record : 1-D array  The case record; excitation, table_step [rad], table_start [rad]: the
             excitation table; nose: the nose's cam angle [rad]; time [s], length [s], dense:
             the step's start, length and dense output
             (:func:`engine_kernels.valvetrain.dopri.step.dopri_step`); prev: (lift [m],
             velocity [m/s], acceleration [m/s²], time [s]) at the previous observed point
             (:func:`record_closure`).
    """
    lift, velocity = dense_state(dense, s)
    speed = record[K_SPEED]
    at = time + s * length
    angle = table_start + at * speed
    drive_lift, slope = excitation_lift_slope(excitation, table_step, at * speed / table_step)
    acc = specific_point(lift, velocity, drive_lift, slope, case_coefficients(record, 0, 1))[2]
    if observe_closure(record, 0, 1, lift, angle >= nose):
        record_closure(record, excitation, table_step, prev)
    return lift, velocity, acc, at


@jit
def record_closure(record, excitation, table_step, prev):
    """``record_closure_events`` with the previous observed point ``prev`` = (lift [m],
    velocity [m/s], acceleration [m/s²], time [s] from the table's start)."""
    lift, velocity, acc, time = prev
    position = time * record[K_SPEED] / table_step
    c = case_coefficients(record, 0, 1)
    jerk = jerk_at(excitation, table_step, position, lift, velocity, acc, c)
    record_closure_events(record, 0, 1, lift, velocity, acc, jerk)


@jit
def observe_point(
    record, excitation, table_step, table_start, time, lift, velocity, drive_root, leaving
):
    """A located switch or maximum as an observed point: the lift's maximum since the previous
    point is located (:func:`engine_kernels.valvetrain.valve.located.observe_peak`) and this point
    becomes the previous one. At the root of the drive force (``drive_root``: a located drive
    switch) its drive force is taken as zero, so a separation starting there is dated to it.
    ``time`` [s] from the table's start; lift [m], velocity [m/s] there.

    The contact is left (``leaving``) where the drive force has fallen through the mode dead
    band (``TRANSITION_BAND``·preload below zero), not where it reached zero: about
    band/|dF/dθ| later, 8.7e-6–6.5e-5° on four separating points of a random sample
    (docs/accuracy.md; the scipy reference switches at 1e-9 N). The point is therefore moved back, linearly at the
    rate the drive force falls there, to the root (at most to the previous observed point), so
    a jump is dated where the drive force reached zero. It falls continuously: only a rising
    drive force jumps (at the lash take-up, where Y' jumps)."""
    speed = record[K_SPEED]
    angle = table_start + time * speed
    position = time * speed / table_step
    c = case_coefficients(record, 0, 1)
    drive_lift, slope, curvature = excitation_curvature(excitation, table_step, position)
    drive, _, acc = specific_point(lift, velocity, drive_lift, slope, c)
    rate = drive_force_rate(velocity, acc, slope, curvature, c)
    if leaving and drive < 0.0 and rate < 0.0:
        back = min(drive / rate, (angle - record[ST_PREV_ANGLE]) / speed)
        angle -= back * speed
        lift -= back * velocity
        velocity -= back * acc
    observe_peak(record, 0, 1, angle, lift, velocity)
    remember_point(record, 0, 1, angle, lift, velocity, 0.0 if drive_root else drive)


@jit
def observe_turn(record, excitation, table_step, table_start, time, length, dense, turn):
    """The lift's maximum located at time ``turn`` [s] inside the step from ``time`` [s] of
    length ``length`` [s] (dense output ``dense``) as an observed point (:func:`observe_point`)."""
    lift, velocity = dense_state(dense, (turn - time) / length)
    observe_point(record, excitation, table_step, table_start, turn, lift, velocity, False, False)
