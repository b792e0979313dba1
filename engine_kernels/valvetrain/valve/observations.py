"""Running observations of a valve run: extremes, jump, bounce, mode changes, outputs.

Every grid point of a run updates a handful of running values with branch-free arithmetic
(maxima, minima, counters and selects): the same helpers serve the one-case kernel and the
SIMD lane kernel, where they are inlined into a loop over lanes that then vectorises. Rare
events are found by comparing the current state with the previous one, never by branching:
the seat phase (seated, open, closed, bouncing) changes once at first closure and twice per
bounce, and only then does :func:`record_closure_events` (scalar, branchy) record the state
before the closure and count the bounce. The seat phase is also followed at every RK4
sub-step point inside a grid step (:func:`observe_closure` alone), because a landing on a
stiff seat can begin and end between grid points, though not between sub-step points.

Forces and power are per unit mass (the integrators work with the coefficients of [V2]
divided by M, see :func:`engine_kernels.valvetrain.valve.model.specific_forces`); the outputs are
scaled back to newtons. The observations of a case are the ``ST_*`` rows of its record
(:mod:`engine_kernels.valvetrain.valve.layout`), beside the coefficients ``K_*`` they read: row ``r``
of lane ``l`` sits at ``at + r·w`` of a flat array, with ``at = l`` and ``w`` the lanes per
block; one flat array with compile-time row offsets lets the compiler see that lanes and rows
never overlap. The one-case kernel uses ``at = 0`` and ``w = 1``.

The status of a run comes from the physics: the energy balance
(:mod:`engine_kernels.valvetrain.valve.energy_balance`) and a finite end state. The count of
mode transitions is reported but does not set the status: a stiff seat really bounces tens of
times, and a finer grid sees more of those transitions, so a limit on their number flagged
converged runs as unstable (every unstable run of tests/engine_kernels/test_valve.py breaks
an energy check anyway).
"""

from __future__ import annotations

import math

import numpy as np

from engine_kernels._jit import jit, jit_inline
from engine_kernels.valvetrain.valve.energy_balance import drive_power, energy_pumped
from engine_kernels.valvetrain.valve.layout import (
    K_BAND,
    K_MASS,
    K_PRELOAD,
    K_SEAT_DEPTH,
    K_SEAT_STIFFNESS,
    K_SPEED,
    K_STIFFNESS,
    N_RECORD,
    O_BOUNCE_COUNT,
    O_BOUNCE_HEIGHT,
    O_JUMP_DURATION,
    O_JUMP_GAP,
    O_JUMP_START,
    O_MAX_ACCELERATION,
    O_MAX_CONTACT_FORCE,
    O_MAX_LIFT,
    O_MAX_VELOCITY,
    O_MIN_ACCELERATION,
    O_MIN_VELOCITY,
    O_SEATING_VELOCITY,
    O_STATUS,
    O_TRANSITIONS,
    PHASE_BOUNCING,
    PHASE_CLOSED,
    PHASE_OPEN,
    PHASE_SEATED,
    ST_BOUNCE_HEIGHT,
    ST_BOUNCES,
    ST_CAPTURED,
    ST_CONTACT,
    ST_ENERGY0,
    ST_EXCESS,
    ST_INVERSE_SPEED,
    ST_JUMP_GAP,
    ST_JUMP_START,
    ST_JUMP_STEPS,
    ST_MAX_A,
    ST_MAX_FORCE,
    ST_MAX_LIFT,
    ST_MAX_V,
    ST_MIN_A,
    ST_MIN_V,
    ST_PHASE,
    ST_POWER_FIRST,
    ST_POWER_SUM,
    ST_REST_ENERGY,
    ST_REST_RISE,
    ST_SEAT_A0,
    ST_SEAT_J0,
    ST_SEAT_V0,
    ST_SEAT_Y0,
    ST_SEATED,
    ST_TRANSITIONS,
    STATUS_NONFINITE,
    STATUS_OK,
    STATUS_UNSTABLE,
)
from engine_kernels.valvetrain.valve.located import (
    observe_peak,
    remember_point,
    seating_speed,
    separation_angle,
)
from engine_kernels.valvetrain.valve.model import (
    INF,
    NAN,
    ONE,
    ZERO,
    larger,
    smaller,
)


@jit_inline
def start_observations(
    record,
    at,
    w,
    angle,
    lift,
    velocity,
    acceleration,
    drive_lift,
    drive_velocity,
    drive,
    seat,
):
    """Start the observations of one case with its first grid point.

    record         : 1-D array  Flat case records; this case's rows at ``at + r·w``
                                (coefficients ``K_*`` read, observations ``ST_*`` written).
    at, w          : int        Offset of row 0 and row stride (lanes per block) [-].
    angle          : float      Cam angle of the grid point [rad].
    lift, velocity : float      Valve lift y [m] and velocity ẏ [m/s].
    acceleration   : float      ÿ [m/s²].
    drive_lift     : float      Theoretical valve lift Y [m]; drive_velocity: Ẏ [m/s].
    drive, seat    : float      Drive and seat forces per unit mass before clipping [N/kg]
                                (:func:`engine_kernels.valvetrain.valve.model.specific_forces`).
    The contact and seat modes start from the sign of their forces (no dead band yet).
    """
    seat_depth = record[at + K_SEAT_DEPTH * w]
    for row in range(ST_MAX_LIFT, N_RECORD):  # the observation rows
        record[at + row * w] = ZERO
    record[at + ST_MAX_LIFT * w] = -INF
    record[at + ST_MAX_V * w] = -INF
    record[at + ST_MIN_V * w] = INF
    record[at + ST_MAX_A * w] = -INF
    record[at + ST_MIN_A * w] = INF
    record[at + ST_JUMP_START * w] = INF
    record[at + ST_ENERGY0 * w] = NAN
    record[at + ST_EXCESS * w] = -INF
    record[at + ST_REST_ENERGY * w] = NAN
    record[at + ST_REST_RISE * w] = -INF
    record[at + ST_INVERSE_SPEED * w] = ONE / record[at + K_SPEED * w]
    record[at + ST_PHASE * w] = PHASE_OPEN if lift > seat_depth else PHASE_SEATED
    record[at + ST_CONTACT * w] = ONE if drive > ZERO else ZERO
    seat = seat if lift < seat_depth else -INF
    record[at + ST_SEATED * w] = ONE if seat > ZERO else ZERO
    power = drive_power(drive, drive_velocity)
    record[at + ST_POWER_SUM * w] = power
    record[at + ST_POWER_FIRST * w] = power
    observe_extremes(record, at, w, lift, velocity, acceleration, drive)
    observe_separation(record, at, w, angle, lift, drive_lift, drive)
    remember_point(record, at, w, angle, lift, velocity, drive)


@jit_inline
def observe_valve(
    record,
    at,
    w,
    angle,
    lift,
    velocity,
    acceleration,
    drive_lift,
    drive_velocity,
    drive,
    seat,
    past_nose,
):
    """Update the running observations of one case at a grid point after the first.

    Tracks extremes, separation (drive force ≤ 0 while off the seat, before the first
    closure), the seat phase and
    bounce height, mode transitions, and the cam's work for the energy balance. Returns True
    if the seat phase changed in a way :func:`record_closure_events` must record.

    past_nose : bool   The cam is at or past its nose (see :func:`observe_closure`).
    Other arguments as in :func:`start_observations`.
    """
    observe_extremes(record, at, w, lift, velocity, acceleration, drive)
    observe_peak(record, at, w, angle, lift, velocity)
    start = separation_angle(record, at, w, angle, drive)
    observe_separation(record, at, w, start, lift, drive_lift, drive)
    event = observe_closure(record, at, w, lift, past_nose)
    observe_transitions(record, at, w, lift, drive, seat)
    record[at + ST_POWER_SUM * w] += drive_power(drive, drive_velocity)
    remember_point(record, at, w, angle, lift, velocity, drive)
    return event


@jit_inline
def observe_extremes(record, at, w, lift, velocity, acceleration, drive):
    """Running extremes of lift, velocity, acceleration and drive force (observe_valve)."""
    record[at + ST_MAX_LIFT * w] = larger(record[at + ST_MAX_LIFT * w], lift)
    record[at + ST_MAX_V * w] = larger(record[at + ST_MAX_V * w], velocity)
    record[at + ST_MIN_V * w] = smaller(record[at + ST_MIN_V * w], velocity)
    record[at + ST_MAX_A * w] = larger(record[at + ST_MAX_A * w], acceleration)
    record[at + ST_MIN_A * w] = smaller(record[at + ST_MIN_A * w], acceleration)
    record[at + ST_MAX_FORCE * w] = larger(record[at + ST_MAX_FORCE * w], drive)


@jit_inline
def observe_separation(record, at, w, start, lift, drive_lift, drive):
    """Jump: drive force ≤ 0 while the valve is off its seat before its first closure.

    ``start`` [rad] is where the drive force reached zero, located between the previous point
    and this one (:func:`engine_kernels.valvetrain.valve.located.separation_angle`): the jump start
    when this point is the first separated one.

    After the first closure the cam is on its base circle and leaving the seat is a bounce
    (:func:`observe_closure`), not a jump: counting it here would turn the jump speed into a
    bounce speed. The angle only grows, so the first separated angle is the smallest one.
    """
    not_closed = record[at + ST_PHASE * w] < PHASE_CLOSED
    separated = (lift > record[at + K_SEAT_DEPTH * w]) & (drive <= ZERO) & not_closed
    start = start if separated else INF
    record[at + ST_JUMP_START * w] = smaller(record[at + ST_JUMP_START * w], start)
    record[at + ST_JUMP_STEPS * w] += ONE if separated else ZERO
    gap = lift - drive_lift if separated else ZERO
    record[at + ST_JUMP_GAP * w] = larger(record[at + ST_JUMP_GAP * w], gap)


@jit_inline
def observe_closure(record, at, w, lift, past_nose):
    """Seat phase and bounce height (observe_valve); True at first closure or a bounce.

    past_nose : bool  The cam angle is at or past the nose, the first maximum of Y
                      (:func:`nose_position`).
    Closure is the first return onto the seat (y ≤ δ0) after opening with the cam past its
    nose; a bounce starts when the valve leaves the seat again after it. A return onto the
    seat before the nose (the valve kicked off the seat by the lash impact, falling back
    while the cam still rises) puts the phase back to seated: the event has not ended.
    """
    seat_depth = record[at + K_SEAT_DEPTH * w]
    phase = record[at + ST_PHASE * w]
    off_seat = lift > seat_depth
    closed = phase >= PHASE_CLOSED
    closing = (phase == PHASE_OPEN) & (not off_seat) & past_nose
    on_seat_phase = PHASE_CLOSED if closed | closing else PHASE_SEATED
    off_seat_phase = PHASE_BOUNCING if closed else PHASE_OPEN
    record[at + ST_PHASE * w] = off_seat_phase if off_seat else on_seat_phase
    height = lift - seat_depth if off_seat & closed else ZERO
    record[at + ST_BOUNCE_HEIGHT * w] = larger(record[at + ST_BOUNCE_HEIGHT * w], height)
    rising = (phase == PHASE_CLOSED) & off_seat
    return closing | rising


@jit
def nose_position(excitation):
    """Table index of the nose: the first maximum of the theoretical lift Y (row 0)."""
    return np.argmax(excitation[0])


@jit
def record_closure_events(record, at, w, prev_lift, prev_velocity, prev_acceleration, prev_jerk):
    """Record first closure and count bounces after :func:`observe_closure` flagged an event.

    prev_lift, prev_velocity : float  State at the previous (sub-)step point [m], [m/s].
    prev_acceleration        : float  ÿ there [m/s²].
    prev_jerk                : float  ⃛y there [m/s³] (off the seat,
                                      :func:`engine_kernels.valvetrain.valve.located.specific_jerk`).
    The point before the first closure gives the seating velocity (see
    :func:`finish_observations`); a bounce is the phase turning to bouncing from on the seat.
    Harmless on points without an event.
    """
    phase = record[at + ST_PHASE * w]
    if phase >= PHASE_CLOSED and record[at + ST_CAPTURED * w] == ZERO:
        record[at + ST_SEAT_Y0 * w] = prev_lift
        record[at + ST_SEAT_V0 * w] = prev_velocity
        record[at + ST_SEAT_A0 * w] = prev_acceleration
        record[at + ST_SEAT_J0 * w] = prev_jerk
        record[at + ST_CAPTURED * w] = ONE
    if phase == PHASE_BOUNCING and not prev_lift > record[at + K_SEAT_DEPTH * w]:
        record[at + ST_BOUNCES * w] += ONE


@jit_inline
def observe_transitions(record, at, w, lift, drive, seat):
    """Count changes of the contact and seat modes between grid points (observe_valve).

    A mode only changes once its force leaves a dead band ``±band`` around zero, so round-off
    in a force that is zero on the base circle is not counted as chatter (``K_BAND``).
    """
    band = record[at + K_BAND * w]
    previous = record[at + ST_CONTACT * w]
    before = record[at + ST_SEATED * w]
    contact = previous if drive >= -band else ZERO
    contact = ONE if drive > band else contact
    seat = seat if lift < record[at + K_SEAT_DEPTH * w] else -INF
    seated = before if seat >= -band else ZERO
    seated = ONE if seat > band else seated
    record[at + ST_TRANSITIONS * w] += abs(contact - previous) + abs(seated - before)
    record[at + ST_CONTACT * w] = contact
    record[at + ST_SEATED * w] = seated


@jit
def settling_energy(record, at, w, lift, velocity):
    """Energy per unit mass [J/kg] of the valve at ``lift`` [m] and ``velocity`` [m/s] when the
    window ends, counted from the seat plane δ0: ½ẏ² + g′(y − δ0), g′ = P_s0/M, plus the
    energy its springs hold below it: ½k_z′(δ0 − y)² in the seat (y < δ0) and ½k′y² in the
    drive, which after the cam has closed (Y ≤ 0) pushes only where y < Y ≤ 0. Nothing else
    gives energy (the dampers take it), so the valve can rise at most this/g′ above δ0 (the
    spring rate only lowers it) and can leave its seat only where this is > 0. At rest on its
    seat it is −½g′δ0.
    """
    depth = record[at + K_SEAT_DEPTH * w]
    energy = 0.5 * velocity * velocity + record[at + K_PRELOAD * w] * (lift - depth)
    if lift < depth:
        energy += 0.5 * record[at + K_SEAT_STIFFNESS * w] * (depth - lift) ** 2
    if lift < 0.0:
        energy += 0.5 * record[at + K_STIFFNESS * w] * lift * lift
    return energy


@jit
def finish_observations(record, at, w, step_angle, lift, velocity, out, resolution=0.0):
    """Write the ``O_*`` outputs of one case from its observations and final state.

    step_angle : float      Grid step Δθ [rad] (jump duration = separated grid points × Δθ).
    resolution : float      Lift the integrator resolves [m] (0 for RK4; see
                            :func:`engine_kernels.valvetrain.valve.energy_balance.energy_pumped`).
    out        : 1-D array  Output row (``O_*``).
    Bounce count and height are unknown (NaN) where the valve's energy when the window ends
    (:func:`settling_energy`) could still lift it off its seat, and above its largest bounce.
    The status is ``STATUS_NONFINITE`` for a non-finite final state, ``STATUS_UNSTABLE`` if
    the energy balance was broken (:func:`engine_kernels.valvetrain.valve.energy_balance.energy_pumped`),
    else ``STATUS_OK``. Other arguments as in :func:`start_observations`.
    """
    out[O_MAX_LIFT] = record[at + ST_MAX_LIFT * w]
    out[O_MAX_VELOCITY] = record[at + ST_MAX_V * w]
    out[O_MIN_VELOCITY] = record[at + ST_MIN_V * w]
    out[O_MAX_ACCELERATION] = record[at + ST_MAX_A * w]
    out[O_MIN_ACCELERATION] = record[at + ST_MIN_A * w]
    start = record[at + ST_JUMP_START * w]
    out[O_JUMP_START] = start if start < math.inf else math.nan
    out[O_JUMP_DURATION] = record[at + ST_JUMP_STEPS * w] * step_angle
    out[O_JUMP_GAP] = record[at + ST_JUMP_GAP * w]
    out[O_BOUNCE_COUNT] = record[at + ST_BOUNCES * w]
    out[O_BOUNCE_HEIGHT] = record[at + ST_BOUNCE_HEIGHT * w]
    energy = settling_energy(record, at, w, lift, velocity)
    if energy > 0.0:  # it can still (or does) leave the seat: more bounces may follow
        out[O_BOUNCE_COUNT] = math.nan
    if energy > record[at + K_PRELOAD * w] * out[O_BOUNCE_HEIGHT]:  # and rise above them
        out[O_BOUNCE_HEIGHT] = math.nan
    # Speed where the lift reaches δ0, from the last point above the seat along the motion
    # there (engine_kernels.valvetrain.valve.located.seating_speed): no seat force acts before the
    # crossing, while after it a stiff seat reverses the valve within a step, so
    # interpolating towards the next point would understate the speed
    # (tests/engine_kernels/test_valve.py measures it against the scipy reference).
    out[O_SEATING_VELOCITY] = math.nan
    if record[at + ST_CAPTURED * w] == 1.0:
        out[O_SEATING_VELOCITY] = seating_speed(
            record[at + ST_SEAT_Y0 * w] - record[at + K_SEAT_DEPTH * w],
            record[at + ST_SEAT_V0 * w],
            record[at + ST_SEAT_A0 * w],
            record[at + ST_SEAT_J0 * w],
        )
    out[O_MAX_CONTACT_FORCE] = record[at + K_MASS * w] * record[at + ST_MAX_FORCE * w]
    out[O_TRANSITIONS] = record[at + ST_TRANSITIONS * w]
    status = STATUS_OK
    if energy_pumped(record, at, w, resolution):
        status = STATUS_UNSTABLE
    if not (math.isfinite(lift) and math.isfinite(velocity)):
        status = STATUS_NONFINITE
    out[O_STATUS] = status
