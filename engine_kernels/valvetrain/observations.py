"""Running observations of a valve run: extremes, jump, bounce, energy balance, status.

Every grid point of a run updates a handful of running values with branch-free arithmetic
(maxima, minima, counters and selects): the same helpers serve the one-case kernel and the
SIMD lane kernel, where they are inlined into a loop over lanes that then vectorises. Rare
events are found by comparing the current state with the previous one, never by branching:
the seat phase (seated, open, closed, bouncing) changes once at first closure and twice per
bounce, and only then does :func:`record_closure_events` (scalar, branchy) record the state
before the closure and count the bounce. The seat phase is also followed at every RK4
sub-step point inside a grid step (:func:`observe_closure` alone), because a landing on a
stiff seat can begin and end between grid points, though not between sub-step points.

Forces, power and energy are per unit mass (the integrators work with the coefficients of
[V2] divided by M, see :func:`engine_kernels.valve_model.specific_forces`); the outputs are
scaled back to newtons. The observations of a case are rows of a flat array: row ``r`` of lane ``l`` sits at
``at + r·width`` with ``at = base + l``; one flat array with compile-time row offsets lets the
compiler see that lanes and rows never overlap. The one-case kernel uses ``width = 1``.

Status from the physics (SPEC §4, stability): the valve-train energy may never exceed its
start value plus the work the cam did through the drive, and may only fall once the valve has
closed on the base circle (checked every ``ENERGY_INTERVAL`` grid points), else
``STATUS_UNSTABLE``; a non-finite end state gives ``STATUS_NONFINITE``. An unstable step
clipped by the one-sided seat shows up as chatter and pumped energy, not NaN. The count of
mode transitions is reported but does not set the status: a stiff seat really bounces tens of
times, and a finer grid sees more of those transitions, so a limit on their number flagged
converged runs as unstable (every unstable run of tests/engine_kernels/test_valve.py breaks
an energy check anyway).
"""

from __future__ import annotations

import math

import numpy as np

from engine_kernels._jit import jit, jit_inline
from engine_kernels.valve_model import (
    HALF,
    INF,
    NAN,
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
    ONE,
    STATUS_NONFINITE,
    STATUS_OK,
    STATUS_UNSTABLE,
    TWO,
    ZERO,
    larger,
    positive_part,
    smaller,
    valve_energy,
)

ENERGY_SLACK = 0.05
ENERGY_REST_RISE = np.float32(0.25)
ENERGY_FLOOR_FRACTION = 1e-3
ENERGY_INTERVAL = 8
TRANSITION_BAND = 1e-6

# Seat phase of a run: not yet lifted off the seat, open, closed again after opening, and off
# the seat again after that closure (bouncing).
PHASE_SEATED = np.float32(0.0)
PHASE_OPEN = np.float32(1.0)
PHASE_CLOSED = np.float32(2.0)
PHASE_BOUNCING = np.float32(3.0)

# Rows of the observations of one case.
_MAX_LIFT = 0
_MAX_V = 1
_MIN_V = 2
_MAX_A = 3
_MIN_A = 4
_MAX_FORCE = 5
_JUMP_START = 6
_JUMP_STEPS = 7
_JUMP_GAP = 8
_PHASE = 9
_BOUNCE_HEIGHT = 10
_CONTACT = 11
_SEATED = 12
_TRANSITIONS = 13
_POWER_SUM = 14
_POWER_FIRST = 15
_SEAT_Y0 = 16
_SEAT_V0 = 17
_SEAT_A0 = 18
_CAPTURED = 19
_BOUNCES = 20
_ENERGY0 = 21
_EXCESS = 22
_WORK_MAX = 23
_REST_ENERGY = 24
_REST_RISE = 25
N_STATS = 26


@jit_inline
def drive_power(drive, drive_velocity):
    """Cam power into the drive per unit mass, ``max(0, F_drive/M)·Ẏ`` [W/kg].

    drive          : float  Drive force per unit mass before clipping [N/kg].
    drive_velocity : float  Ẏ [m/s].
    """
    return positive_part(drive) * drive_velocity


@jit_inline
def start_observations(
    stats,
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
    seat_depth,
):
    """Start the observations of one case with its first grid point.

    stats          : 1-D array  Flat observations; this case's rows at ``at + r·w``.
    at, w          : int        Offset of row 0 and row stride (lanes per block) [-].
    angle          : float      Cam angle of the grid point [rad].
    lift, velocity : float      Valve lift y [m] and velocity ẏ [m/s].
    acceleration   : float      ÿ [m/s²].
    drive_lift     : float      Theoretical valve lift Y [m]; drive_velocity: Ẏ [m/s].
    drive, seat    : float      Drive and seat forces per unit mass before clipping [N/kg]
                                (:func:`engine_kernels.valve_model.specific_forces`).
    seat_depth     : float      δ0 = Ps0/kz [m].
    The contact and seat modes start from the sign of their forces (no dead band yet).
    """
    for row in range(N_STATS):
        stats[at + row * w] = ZERO
    stats[at + _MAX_LIFT * w] = -INF
    stats[at + _MAX_V * w] = -INF
    stats[at + _MIN_V * w] = INF
    stats[at + _MAX_A * w] = -INF
    stats[at + _MIN_A * w] = INF
    stats[at + _JUMP_START * w] = INF
    stats[at + _ENERGY0 * w] = NAN
    stats[at + _EXCESS * w] = -INF
    stats[at + _REST_ENERGY * w] = NAN
    stats[at + _REST_RISE * w] = -INF
    stats[at + _PHASE * w] = PHASE_OPEN if lift > seat_depth else PHASE_SEATED
    stats[at + _CONTACT * w] = ONE if drive > ZERO else ZERO
    seat = seat if lift < seat_depth else -INF
    stats[at + _SEATED * w] = ONE if seat > ZERO else ZERO
    power = drive_power(drive, drive_velocity)
    stats[at + _POWER_SUM * w] = power
    stats[at + _POWER_FIRST * w] = power
    observe_extremes(stats, at, w, lift, velocity, acceleration, drive)
    observe_separation(stats, at, w, angle, lift, drive_lift, drive, seat_depth)


@jit_inline
def observe_valve(
    stats,
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
    seat_depth,
    band,
    past_nose,
):
    """Update the running observations of one case at a grid point after the first.

    Tracks extremes, separation (drive force ≤ 0 while off the seat, before the first
    closure), the seat phase and
    bounce height, mode transitions, and the cam's work for the energy balance. Returns True
    if the seat phase changed in a way :func:`record_closure_events` must record.

    band      : float  Dead band of the mode changes per unit mass [N/kg].
    past_nose : bool   The cam is at or past its nose (see :func:`observe_closure`).
    Other arguments as in :func:`start_observations`.
    """
    observe_extremes(stats, at, w, lift, velocity, acceleration, drive)
    observe_separation(stats, at, w, angle, lift, drive_lift, drive, seat_depth)
    event = observe_closure(stats, at, w, lift, seat_depth, past_nose)
    observe_transitions(stats, at, w, lift, drive, seat, seat_depth, band)
    stats[at + _POWER_SUM * w] += drive_power(drive, drive_velocity)
    return event


@jit_inline
def observe_extremes(stats, at, w, lift, velocity, acceleration, drive):
    """Running extremes of lift, velocity, acceleration and drive force (observe_valve)."""
    stats[at + _MAX_LIFT * w] = larger(stats[at + _MAX_LIFT * w], lift)
    stats[at + _MAX_V * w] = larger(stats[at + _MAX_V * w], velocity)
    stats[at + _MIN_V * w] = smaller(stats[at + _MIN_V * w], velocity)
    stats[at + _MAX_A * w] = larger(stats[at + _MAX_A * w], acceleration)
    stats[at + _MIN_A * w] = smaller(stats[at + _MIN_A * w], acceleration)
    stats[at + _MAX_FORCE * w] = larger(stats[at + _MAX_FORCE * w], drive)


@jit_inline
def observe_separation(stats, at, w, angle, lift, drive_lift, drive, seat_depth):
    """Jump: drive force ≤ 0 while the valve is off its seat before its first closure.

    After the first closure the cam is on its base circle and leaving the seat is a bounce
    (:func:`observe_closure`), not a jump: counting it here would turn the jump speed into a
    bounce speed. The angle only grows, so the first separated angle is the smallest one.
    """
    not_closed = stats[at + _PHASE * w] < PHASE_CLOSED
    separated = (lift > seat_depth) & (drive <= ZERO) & not_closed
    start = angle if separated else INF
    stats[at + _JUMP_START * w] = smaller(stats[at + _JUMP_START * w], start)
    stats[at + _JUMP_STEPS * w] += ONE if separated else ZERO
    gap = lift - drive_lift if separated else ZERO
    stats[at + _JUMP_GAP * w] = larger(stats[at + _JUMP_GAP * w], gap)


@jit_inline
def observe_closure(stats, at, w, lift, seat_depth, past_nose):
    """Seat phase and bounce height (observe_valve); True at first closure or a bounce.

    past_nose : bool  The cam angle is at or past the nose, the first maximum of Y
                      (:func:`nose_position`).
    Closure is the first return onto the seat (y ≤ δ0) after opening with the cam past its
    nose; a bounce starts when the valve leaves the seat again after it. A return onto the
    seat before the nose (the valve kicked off the seat by the lash impact, falling back
    while the cam still rises) puts the phase back to seated: the event has not ended.
    """
    phase = stats[at + _PHASE * w]
    off_seat = lift > seat_depth
    closed = phase >= PHASE_CLOSED
    closing = (phase == PHASE_OPEN) & (not off_seat) & past_nose
    on_seat_phase = PHASE_CLOSED if closed | closing else PHASE_SEATED
    off_seat_phase = PHASE_BOUNCING if closed else PHASE_OPEN
    stats[at + _PHASE * w] = off_seat_phase if off_seat else on_seat_phase
    height = lift - seat_depth if off_seat & closed else ZERO
    stats[at + _BOUNCE_HEIGHT * w] = larger(stats[at + _BOUNCE_HEIGHT * w], height)
    rising = (phase == PHASE_CLOSED) & off_seat
    return closing | rising


@jit
def nose_position(excitation):
    """Table index of the nose: the first maximum of the theoretical lift Y (row 0)."""
    return np.argmax(excitation[0])


@jit
def record_closure_events(stats, at, w, prev_lift, prev_velocity, prev_acceleration, seat_depth):
    """Record first closure and count bounces after :func:`observe_closure` flagged an event.

    prev_lift, prev_velocity : float  State at the previous (sub-)step point [m], [m/s].
    prev_acceleration        : float  ÿ there [m/s²].
    The point before the first closure gives the seating velocity (see
    :func:`finish_observations`); a bounce is the phase turning to bouncing from on the seat.
    Harmless on points without an event.
    """
    phase = stats[at + _PHASE * w]
    if phase >= PHASE_CLOSED and stats[at + _CAPTURED * w] == ZERO:
        stats[at + _SEAT_Y0 * w] = prev_lift
        stats[at + _SEAT_V0 * w] = prev_velocity
        stats[at + _SEAT_A0 * w] = prev_acceleration
        stats[at + _CAPTURED * w] = ONE
    if phase == PHASE_BOUNCING and not prev_lift > seat_depth:
        stats[at + _BOUNCES * w] += ONE


@jit_inline
def observe_transitions(stats, at, w, lift, drive, seat, seat_depth, band):
    """Count changes of the contact and seat modes between grid points (observe_valve).

    A mode only changes once its force leaves a dead band ``±band`` around zero, so round-off
    in a force that is zero on the base circle is not counted as chatter.
    """
    previous = stats[at + _CONTACT * w]
    before = stats[at + _SEATED * w]
    contact = previous if drive >= -band else ZERO
    contact = ONE if drive > band else contact
    seat = seat if lift < seat_depth else -INF
    seated = before if seat >= -band else ZERO
    seated = ONE if seat > band else seated
    stats[at + _TRANSITIONS * w] += abs(contact - previous) + abs(seated - before)
    stats[at + _CONTACT * w] = contact
    stats[at + _SEATED * w] = seated


@jit_inline
def observe_energy(
    stats,
    at,
    w,
    time_step,
    lift,
    velocity,
    drive_lift,
    drive_velocity,
    drive,
    stiffness,
    spring_rate,
    preload,
    seat_stiffness,
    seat_depth,
):
    """Energy checks (every ``ENERGY_INTERVAL`` grid points and at the end).

    The exact solution keeps ``E(t) − E(0) ≤ W(t)``, the work done by the cam through the
    drive (:func:`engine_kernels.valve_model.valve_energy`); once the valve has closed and the
    cam is on its base circle (Y = Ẏ = 0), E can only fall. An unstable RK4 step pumps energy
    in from nowhere: a gross blow-up breaks the first law, chatter on a too-stiff seat
    (clipped by the one-sided seat, so it never becomes NaN) breaks the second. Growth is
    exponential, so sampling every few grid points loses nothing. Keeps the largest excess
    ``E − E(0) − W``, the largest ``|W|`` and the largest rise of the resting energy between
    checks beyond ``ENERGY_REST_RISE`` for :func:`finish_observations`. Energy and work are
    per unit mass [J/kg]; W is the trapezoidal sum of the power over the grid points.

    time_step      : float  Grid time step Δθ/ω [s].
    stiffness      : float  k' = k/M [1/s²];  spring_rate : float  ks' = ks/M [1/s²].
    preload        : float  Ps0' = Ps0/M [m/s²]; seat_stiffness : float  kz' = kz/M [1/s²].
    Other arguments as in :func:`start_observations`.
    """
    energy = valve_energy(
        lift,
        velocity,
        drive_lift,
        ONE,
        stiffness,
        spring_rate,
        preload,
        seat_stiffness,
        seat_depth,
    )
    initial = stats[at + _ENERGY0 * w]
    initial = energy if math.isnan(initial) else initial
    stats[at + _ENERGY0 * w] = initial
    power = drive_power(drive, drive_velocity)
    trapezoid = TWO * stats[at + _POWER_SUM * w] - stats[at + _POWER_FIRST * w] - power
    work = HALF * time_step * trapezoid
    stats[at + _EXCESS * w] = larger(stats[at + _EXCESS * w], energy - initial - work)
    stats[at + _WORK_MAX * w] = larger(stats[at + _WORK_MAX * w], abs(work))

    closed = stats[at + _PHASE * w] >= PHASE_CLOSED
    resting = closed & (drive_lift == ZERO) & (drive_velocity == ZERO)
    before = stats[at + _REST_ENERGY * w]
    rise = energy - (ONE + ENERGY_REST_RISE) * before
    rise = rise if resting & (not math.isnan(before)) else -INF
    stats[at + _REST_RISE * w] = larger(stats[at + _REST_RISE * w], rise)
    stats[at + _REST_ENERGY * w] = energy if resting else NAN


@jit
def finish_observations(stats, at, w, step_angle, lift, velocity, mass, preload, seat_depth, out):
    """Write the ``O_*`` outputs of one case from its observations and final state.

    step_angle : float      Grid step Δθ [rad] (jump duration = separated grid points × Δθ).
    mass       : float      Equivalent mass M [kg] (forces back to newtons).
    preload    : float      Ps0' = Ps0/M [m/s²].
    out        : 1-D array  Output row (``O_*``).
    The status is ``STATUS_NONFINITE`` for a non-finite final state, ``STATUS_UNSTABLE`` if
    the energy ever exceeded its start value plus the cam's work by more than
    ``ENERGY_SLACK`` times the largest work, or the resting energy after closure rose by more
    than ``ENERGY_REST_RISE`` between checks (both plus ``ENERGY_FLOOR_FRACTION·Ps0·δ0``),
    else ``STATUS_OK``. Other arguments as in
    :func:`start_observations`.
    """
    out[O_MAX_LIFT] = stats[at + _MAX_LIFT * w]
    out[O_MAX_VELOCITY] = stats[at + _MAX_V * w]
    out[O_MIN_VELOCITY] = stats[at + _MIN_V * w]
    out[O_MAX_ACCELERATION] = stats[at + _MAX_A * w]
    out[O_MIN_ACCELERATION] = stats[at + _MIN_A * w]
    start = stats[at + _JUMP_START * w]
    out[O_JUMP_START] = start if start < math.inf else math.nan
    out[O_JUMP_DURATION] = stats[at + _JUMP_STEPS * w] * step_angle
    out[O_JUMP_GAP] = stats[at + _JUMP_GAP * w]
    out[O_BOUNCE_COUNT] = stats[at + _BOUNCES * w]
    out[O_BOUNCE_HEIGHT] = stats[at + _BOUNCE_HEIGHT * w]
    # Speed where the lift reaches δ0, at constant acceleration from the last point above the
    # seat: no seat force acts before the crossing, while after it a stiff seat reverses the
    # valve within a step, so interpolating towards the next point would understate the
    # speed (tests/engine_kernels/test_valve.py measures it against the scipy reference).
    out[O_SEATING_VELOCITY] = math.nan
    if stats[at + _CAPTURED * w] == 1.0:
        y0 = stats[at + _SEAT_Y0 * w]
        v0 = stats[at + _SEAT_V0 * w]
        squared = v0 * v0 + 2.0 * stats[at + _SEAT_A0 * w] * (seat_depth - y0)
        out[O_SEATING_VELOCITY] = math.sqrt(max(squared, 0.0))
    out[O_MAX_CONTACT_FORCE] = mass * stats[at + _MAX_FORCE * w]
    out[O_TRANSITIONS] = stats[at + _TRANSITIONS * w]
    floor = ENERGY_FLOOR_FRACTION * preload * seat_depth
    pumped = stats[at + _EXCESS * w] > ENERGY_SLACK * stats[at + _WORK_MAX * w] + floor
    pumped = pumped or stats[at + _REST_RISE * w] > floor
    status = STATUS_OK
    if pumped:
        status = STATUS_UNSTABLE
    if not (math.isfinite(lift) and math.isfinite(velocity)):
        status = STATUS_NONFINITE
    out[O_STATUS] = status
