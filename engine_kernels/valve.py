"""Valve-train dynamics: single-DOF valve driven through a compliant rocker (SPEC §4).

Model [V2], in time, with the valve lift y measured from the closed position where the seat
is pre-compressed by ``δ0 = Ps0/kz``::

    M ÿ = max(0, k (Y − y) + b (Ẏ − ẏ))                   drive; ≤ 0 means SEPARATION
        + max(0, kz (δ0 − y) − bz ẏ)   while y < δ0        seat; never pulls
        − ks y − Ps0 − γ ẏ

integrated with fixed-step classic RK4 over a cam-angle grid: the excitation table holds the
theoretical valve lift Y(θ) and its angle derivatives at half-step spacing (SPEC §9: RK4 step
0.5° cam, excitation every 0.25°), the time step is ``Δθ/ω`` and ``Ẏ = ω Y'``. The valve
starts at the initial lift and velocity of the parameter row (normally at rest on the seat).

Stability guard (SPEC §4): before integrating, the largest eigenvalue modulus over the four
linear modes (contact+seat, contact, seat, free) sets the number of equal sub-steps that keeps
``|h λ| ≤ STEP_RATIO_TARGET`` (2.0, a margin under ``RK4_STABILITY_BOUND`` = 2.6); past ``max_substeps`` the case is not integrated and its
status is ``STATUS_SUBSTEP_LIMIT`` (with the needed count in ``O_SUBSTEPS``). Independently, the
run is checked from the physics: the valve-train energy may never exceed its start value plus
the work the cam did through the drive, and may only fall once the valve has closed on the
base circle (checked every ``ENERGY_INTERVAL`` grid points); mode transitions must stay few (``STATUS_UNSTABLE``); a NaN gives ``STATUS_NONFINITE``. An
unstable step clipped by the one-sided seat shows up as chatter and pumped energy, not NaN.

Switch-aware stepping (settings ``switch_aware = 1``) holds the contact and seat modes fixed
inside a step, locates every mode switch (end-of-step sign test and a cubic Hermite of the
switching function through its values and time derivatives), re-takes the RK4 step to just
past the root, switches and finishes the step: this restores fourth order (SPEC §4,
"Integrators and the speed–accuracy trade"). The step-doubling error estimate
(``estimate_error = 1``) compares the lift with a run at twice the step (divided by 2⁴ − 1);
it is NaN where the doubled step would break the stability bound.

Parameters are rows indexed by the ``P_*`` constants, outputs by the ``O_*`` constants,
integer settings by the ``S_*`` constants (build them with :func:`valve_settings`).
Reference: SPEC §4 and the motorcycle OHC valve-train thesis data quoted there.
"""

from __future__ import annotations

import math

import numpy as np

from engine_kernels._jit import batch, jit, prange
from engine_kernels.rk4 import (
    hermite_value,
    oscillator_spectral_radius,
    stable_substeps,
)

P_SPEED = 0
P_MASS = 1
P_DRIVE_STIFFNESS = 2
P_DRIVE_DAMPING = 3
P_SPRING_RATE = 4
P_PRELOAD = 5
P_SEAT_STIFFNESS = 6
P_SEAT_DAMPING = 7
P_EXTERNAL_DAMPING = 8
P_INITIAL_LIFT = 9
P_INITIAL_VELOCITY = 10
VALVE_PARAM_NAMES = (
    "camshaft_speed",
    "equivalent_mass",
    "drive_stiffness",
    "drive_damping",
    "spring_rate",
    "spring_preload",
    "seat_stiffness",
    "seat_damping",
    "external_damping",
    "initial_lift",
    "initial_velocity",
)
VALVE_PARAM_UNITS = ("rad/s", "kg", "N/m", "N s/m", "N/m", "N", "N/m", "N s/m", "N s/m", "m", "m/s")

O_MAX_LIFT = 0
O_MAX_VELOCITY = 1
O_MIN_VELOCITY = 2
O_MAX_ACCELERATION = 3
O_MIN_ACCELERATION = 4
O_JUMP_START = 5
O_JUMP_DURATION = 6
O_JUMP_GAP = 7
O_BOUNCE_COUNT = 8
O_BOUNCE_HEIGHT = 9
O_SEATING_VELOCITY = 10
O_MAX_CONTACT_FORCE = 11
O_SUBSTEPS = 12
O_STEP_RATIO = 13
O_TRANSITIONS = 14
O_STATUS = 15
O_ERROR_ESTIMATE = 16
VALVE_OUTPUT_NAMES = (
    "max_lift",
    "max_opening_velocity",
    "max_closing_velocity",
    "max_acceleration",
    "min_acceleration",
    "jump_start",
    "jump_duration",
    "jump_max_gap",
    "bounce_count",
    "bounce_height",
    "seating_velocity",
    "max_contact_force",
    "substeps",
    "step_ratio",
    "mode_transitions",
    "status",
    "error_estimate",
)
VALVE_OUTPUT_UNITS = (
    "m",
    "m/s",
    "m/s",
    "m/s^2",
    "m/s^2",
    "rad",
    "rad",
    "m",
    "1",
    "m",
    "m/s",
    "N",
    "1",
    "1",
    "1",
    "1",
    "m",
)

C_LIFT = 0
C_VELOCITY = 1
C_ACCELERATION = 2
C_DRIVE_FORCE = 3
C_SEAT_FORCE = 4
VALVE_CURVE_NAMES = ("lift", "velocity", "acceleration", "drive_force", "seat_force")
VALVE_CURVE_UNITS = ("m", "m/s", "m/s^2", "N", "N")

S_MAX_SUBSTEPS = 0
S_SWITCH_AWARE = 1
S_ESTIMATE_ERROR = 2
S_STABILITY_GUARD = 3
DEFAULT_MAX_SUBSTEPS = 256
# Sub-steps keep |h λ| at or below this, with a margin under RK4_STABILITY_BOUND: each linear
# mode is stable up to the bound, but the switching, clipped system still pumps energy at
# hard seat impacts when a mode sits right at it.
STEP_RATIO_TARGET = 2.0

STATUS_OK = 0
STATUS_SUBSTEP_LIMIT = 1
STATUS_UNSTABLE = 2
STATUS_NONFINITE = 3
STATUS_INVALID_INPUT = 4
VALVE_STATUS_NAMES = ("ok", "substep_limit", "unstable", "nonfinite", "invalid_input")

ENERGY_SLACK = 0.05
ENERGY_REST_RISE = 0.25
ENERGY_FLOOR_FRACTION = 1e-3
TRANSITION_LIMIT = 200
ENERGY_INTERVAL = 8
TRANSITION_BAND = 1e-6
ERROR_ORDER_DIVISOR = 15.0
SWITCH_OVERSHOOT = 1e-9
SWITCHES_PER_STEP = 8

# Running observations of one case (rows of the flat per-lane statistics array).
_MAX_LIFT = 0
_MAX_V = 1
_MIN_V = 2
_MAX_A = 3
_MIN_A = 4
_MAX_FORCE = 5
_JUMPED = 6
_JUMP_START = 7
_JUMP_STEPS = 8
_JUMP_GAP = 9
_OPENED = 10
_CLOSED = 11
_BOUNCES = 12
_BOUNCE_HEIGHT = 13
_SEAT_Y0 = 14
_SEAT_V0 = 15
_SEAT_Y1 = 16
_SEAT_V1 = 17
_PREV_Y = 18
_PREV_V = 19
_PREV_CONTACT = 20
_PREV_SEATED = 21
_TRANSITIONS = 22
_ENERGY0 = 23
_EXCESS = 24
_IN_BOUNCE = 25
_WORK_MAX = 26
_POWER_PREV = 27
_POWER_SUM = 28
_REST_ENERGY = 29
_REST_RISE = 30
N_STATS = 31


def valve_settings(
    max_substeps=DEFAULT_MAX_SUBSTEPS,
    switch_aware=False,
    estimate_error=False,
    stability_guard=True,
):
    """Integer settings array for the valve kernels (plain Python, builds the ``S_*`` row).

    max_substeps    : int   Hard cap on RK4 sub-steps per grid step (stability guard).
    switch_aware    : bool  Locate contact and seat switches inside steps (one-case kernel).
    estimate_error  : bool  Step-doubling error estimate in ``O_ERROR_ESTIMATE``.
    stability_guard : bool  False integrates with one sub-step whatever the bound says: only
                            to demonstrate the physics-based instability detection.
    """
    return np.array(
        [max_substeps, int(switch_aware), int(estimate_error), int(stability_guard)], dtype=np.int64
    )


@jit
def equivalent_mass(valve_group_mass, spring_mass, rocker_inertia, valve_arm):
    """Equivalent mass on the valve axis ``M = m_valve + m_spring/3 + I_rocker/l_v²`` [V1].

    valve_group_mass : float  Valve, retainer, cotters, spring seat [kg].
    spring_mass      : float  Valve-spring mass [kg] (a third moves with the valve).
    rocker_inertia   : float  Rocker moment of inertia about its pivot [kg m²].
    valve_arm        : float  Lever arm reducing it to the valve axis [m].
    """
    return valve_group_mass + spring_mass / 3.0 + rocker_inertia / (valve_arm * valve_arm)


@jit
def valve_acceleration(
    lift,
    velocity,
    drive_lift,
    drive_velocity,
    inv_mass,
    drive_stiffness,
    drive_damping,
    spring_rate,
    preload,
    seat_stiffness,
    seat_damping,
    external_damping,
    seat_depth,
):
    """Valve acceleration ÿ from the one-sided drive and seat forces [V2].

    lift, velocity   : float  Valve lift y [m] and velocity ẏ [m/s].
    drive_lift       : float  Theoretical valve lift Y (drive side) [m].
    drive_velocity   : float  Ẏ = ω Y' [m/s].
    inv_mass         : float  1/M [1/kg].
    drive_stiffness  : float  k [N/m];  drive_damping : float  b [N s/m].
    spring_rate      : float  ks [N/m]; preload       : float  Ps0 [N].
    seat_stiffness   : float  kz [N/m]; seat_damping  : float  bz [N s/m].
    external_damping : float  γ [N s/m].
    seat_depth       : float  Seat pre-compression δ0 = Ps0/kz [m].
    """
    drive = drive_stiffness * (drive_lift - lift) + drive_damping * (drive_velocity - velocity)
    drive = max(0.0, drive)
    seat = seat_stiffness * (seat_depth - lift) - seat_damping * velocity
    seat = seat if (seat > 0.0 and lift < seat_depth) else 0.0
    return (drive + seat - spring_rate * lift - preload - external_damping * velocity) * inv_mass


@jit
def valve_spectral_radius(
    mass,
    drive_stiffness,
    drive_damping,
    spring_rate,
    seat_stiffness,
    seat_damping,
    external_damping,
):
    """Largest eigenvalue modulus over the four linear modes of [V2] [1/s].

    Modes: contact+seat ``(k + kz + ks, b + bz + γ)``, contact ``(k + ks, b + γ)``, seat
    ``(kz + ks, bz + γ)``, free ``(ks, γ)`` (SPEC §4, stability). Arguments as in
    :func:`valve_acceleration` ([kg], [N/m], [N s/m]).
    """
    radius = oscillator_spectral_radius(
        mass,
        drive_damping + seat_damping + external_damping,
        drive_stiffness + seat_stiffness + spring_rate,
    )
    radius = max(
        radius,
        oscillator_spectral_radius(
            mass, drive_damping + external_damping, drive_stiffness + spring_rate
        ),
    )
    radius = max(
        radius,
        oscillator_spectral_radius(
            mass, seat_damping + external_damping, seat_stiffness + spring_rate
        ),
    )
    return max(radius, oscillator_spectral_radius(mass, external_damping, spring_rate))


@jit
def valve_energy(
    lift,
    velocity,
    drive_lift,
    mass,
    drive_stiffness,
    spring_rate,
    preload,
    seat_stiffness,
    seat_depth,
):
    """Valve-train energy above the rest state [J].

    ``E = ½Mẏ² + ½ks y² + Ps0 y + ½kz ((δ0 − y)²·[y < δ0] − δ0²) + ½k (Y − y)²·[Y > y]``.
    Along any solution of [V2] ``dE/dt ≤ F_drive·Ẏ``: the one-sided drive and seat, with
    their dampers, only ever remove energy, so E can grow only by the work the cam does
    through the drive. Arguments as in :func:`valve_acceleration` ([m], [m/s], [kg], [N/m],
    [N]).
    """
    seat = seat_depth - lift if lift < seat_depth else 0.0
    drive = drive_lift - lift if drive_lift > lift else 0.0
    return (
        0.5 * mass * velocity * velocity
        + 0.5 * spring_rate * lift * lift
        + preload * lift
        + 0.5 * seat_stiffness * (seat * seat - seat_depth * seat_depth)
        + 0.5 * drive_stiffness * drive * drive
    )


@jit
def reset_observations(stats, base, lane, width, lift, velocity):
    """Initial values of the running observations of one lane (see :func:`observe_valve`)."""
    at = base + lane
    for row in range(N_STATS):
        stats[at + row * width] = 0.0
    stats[at + _MAX_LIFT * width] = -math.inf
    stats[at + _MAX_V * width] = -math.inf
    stats[at + _MIN_V * width] = math.inf
    stats[at + _MAX_A * width] = -math.inf
    stats[at + _MIN_A * width] = math.inf
    stats[at + _JUMP_START * width] = math.nan
    stats[at + _ENERGY0 * width] = math.nan
    stats[at + _EXCESS * width] = -math.inf
    stats[at + _POWER_PREV * width] = math.nan
    stats[at + _REST_ENERGY * width] = math.nan
    stats[at + _REST_RISE * width] = -math.inf
    stats[at + _PREV_Y * width] = lift
    stats[at + _PREV_V * width] = velocity
    stats[at + _PREV_CONTACT * width] = -1.0
    stats[at + _PREV_SEATED * width] = -1.0


@jit
def observe_valve(
    stats,
    base,
    lane,
    width,
    angle,
    lift,
    velocity,
    acceleration,
    drive_lift,
    drive_velocity,
    drive_damping,
    drive_stiffness,
    preload,
    seat_stiffness,
    seat_damping,
    seat_depth,
):
    """Update the running observations of one lane at a grid point.

    Tracks extremes, separation (drive force ≤ 0 while off the seat), first closure (the grid
    points around it, for the seating velocity), bounces (re-opening after first closure) and
    mode transitions, and the cam's power for the energy balance. ``stats`` is a flat array holding row ``r`` of lane ``l`` at
    ``base + r·width + l``: one flat array lets the compiler see that lanes and rows never
    overlap. ``angle`` [rad]; state, excitation and coefficients in SI units as in
    :func:`valve_acceleration`. The work is done by five small branch-free pieces, each small
    enough to be inlined into a loop over lanes, which then vectorises.
    """
    at = base + lane
    drive = drive_stiffness * (drive_lift - lift) + drive_damping * (drive_velocity - velocity)
    seat = seat_stiffness * (seat_depth - lift) - seat_damping * velocity
    observe_extremes(stats, at, width, lift, velocity, acceleration, drive)
    observe_separation(stats, at, width, angle, lift, drive_lift, drive, seat_depth)
    observe_closure(stats, at, width, lift, velocity, seat_depth)
    observe_transitions(stats, at, width, lift, drive, seat, seat_depth, TRANSITION_BAND * preload)
    observe_power(stats, at, width, drive, drive_velocity)


@jit
def observe_extremes(stats, at, w, lift, velocity, acceleration, drive):
    """Running extremes of lift, velocity, acceleration and drive force (observe_valve)."""
    value = stats[at + _MAX_LIFT * w]
    stats[at + _MAX_LIFT * w] = max(value, lift)
    value = stats[at + _MAX_V * w]
    stats[at + _MAX_V * w] = max(value, velocity)
    value = stats[at + _MIN_V * w]
    stats[at + _MIN_V * w] = min(value, velocity)
    value = stats[at + _MAX_A * w]
    stats[at + _MAX_A * w] = max(value, acceleration)
    value = stats[at + _MIN_A * w]
    stats[at + _MIN_A * w] = min(value, acceleration)
    value = stats[at + _MAX_FORCE * w]
    stats[at + _MAX_FORCE * w] = max(value, drive)


@jit
def observe_separation(stats, at, w, angle, lift, drive_lift, drive, seat_depth):
    """Jump: drive force ≤ 0 while the valve is off its seat (observe_valve)."""
    separated = (lift > seat_depth) & (drive <= 0.0)
    jumped = stats[at + _JUMPED * w]
    start = stats[at + _JUMP_START * w]
    stats[at + _JUMP_START * w] = angle if separated & (jumped == 0.0) else start
    stats[at + _JUMPED * w] = 1.0 if separated else jumped
    stats[at + _JUMP_STEPS * w] += 1.0 if separated else 0.0
    gap = lift - drive_lift
    value = stats[at + _JUMP_GAP * w]
    stats[at + _JUMP_GAP * w] = gap if separated & (gap > value) else value


@jit
def observe_closure(stats, at, w, lift, velocity, seat_depth):
    """First closure (grid points around it) and bounces after it (observe_valve)."""
    off_seat = lift > seat_depth
    was_closed = stats[at + _CLOSED * w] == 1.0
    closing = (stats[at + _OPENED * w] == 1.0) & (not was_closed) & (not off_seat)
    value = stats[at + _SEAT_Y0 * w]
    stats[at + _SEAT_Y0 * w] = stats[at + _PREV_Y * w] if closing else value
    value = stats[at + _SEAT_V0 * w]
    stats[at + _SEAT_V0 * w] = stats[at + _PREV_V * w] if closing else value
    value = stats[at + _SEAT_Y1 * w]
    stats[at + _SEAT_Y1 * w] = lift if closing else value
    value = stats[at + _SEAT_V1 * w]
    stats[at + _SEAT_V1 * w] = velocity if closing else value
    stats[at + _CLOSED * w] = 1.0 if closing | was_closed else 0.0
    stats[at + _OPENED * w] = 1.0 if off_seat else stats[at + _OPENED * w]
    bouncing = was_closed & off_seat
    stats[at + _BOUNCES * w] += 1.0 if bouncing & (stats[at + _IN_BOUNCE * w] == 0.0) else 0.0
    stats[at + _IN_BOUNCE * w] = 1.0 if bouncing else 0.0
    height = lift - seat_depth
    value = stats[at + _BOUNCE_HEIGHT * w]
    stats[at + _BOUNCE_HEIGHT * w] = height if bouncing & (height > value) else value
    stats[at + _PREV_Y * w] = lift
    stats[at + _PREV_V * w] = velocity


@jit
def observe_transitions(stats, at, w, lift, drive, seat, seat_depth, band):
    """Count changes of the contact and seat modes between grid points (observe_valve).

    A mode only changes once its force leaves a dead band ``±band`` around zero, so round-off
    in a force that is zero on the base circle is not counted as chatter.
    """
    previous = stats[at + _PREV_CONTACT * w]
    before = stats[at + _PREV_SEATED * w]
    known = previous >= 0.0
    contact = 1.0 if drive > band else (0.0 if drive < -band else previous)
    contact = contact if known else (1.0 if drive > 0.0 else 0.0)
    seat = seat if lift < seat_depth else -math.inf
    seated = 1.0 if seat > band else (0.0 if seat < -band else before)
    seated = seated if known else (1.0 if seat > 0.0 else 0.0)
    changes = abs(contact - previous) + abs(seated - before)
    stats[at + _TRANSITIONS * w] += changes if known else 0.0
    stats[at + _PREV_CONTACT * w] = contact
    stats[at + _PREV_SEATED * w] = seated


@jit
def observe_power(stats, at, w, drive, drive_velocity):
    """Accumulate the cam's power into the drive, ``F_drive·Ẏ``, for the energy balance.

    Sums ``P_{n−1} + P_n`` over grid points; half the time step times the sum is the
    trapezoidal work (see :func:`observe_energy`). Layout as in :func:`observe_valve`.
    """
    power = (max(0.0, drive)) * drive_velocity
    previous = stats[at + _POWER_PREV * w]
    stats[at + _POWER_SUM * w] += 0.0 if math.isnan(previous) else previous + power
    stats[at + _POWER_PREV * w] = power


@jit
def observe_energy(
    stats,
    base,
    lane,
    width,
    time_step,
    lift,
    velocity,
    drive_lift,
    drive_velocity,
    mass,
    drive_stiffness,
    spring_rate,
    preload,
    seat_stiffness,
    seat_depth,
):
    """Energy checks (every ``ENERGY_INTERVAL`` grid points and at the end).

    The exact solution keeps ``E(t) − E(0) ≤ W(t)``, the work done by the cam through the
    drive (:func:`valve_energy`); once the valve has closed and the cam is on its base circle
    (Y = Ẏ = 0), E can only fall. An unstable RK4 step pumps energy in from nowhere: a gross
    blow-up breaks the first law, chatter on a too-stiff seat (clipped by the one-sided seat,
    so it never becomes NaN) breaks the second. Growth is exponential, so sampling every few
    grid points loses nothing. Keeps the largest excess ``E − E(0) − W``, the largest
    ``|W|`` and the largest rise of the resting energy between checks beyond
    ``ENERGY_REST_RISE`` for :func:`finish_observations`.

    time_step : float  Grid time step Δθ/ω [s]; other arguments as in :func:`observe_valve`.
    """
    at = base + lane
    w = width
    energy = valve_energy(
        lift,
        velocity,
        drive_lift,
        mass,
        drive_stiffness,
        spring_rate,
        preload,
        seat_stiffness,
        seat_depth,
    )
    initial = stats[at + _ENERGY0 * w]
    initial = energy if math.isnan(initial) else initial
    stats[at + _ENERGY0 * w] = initial
    work = 0.5 * time_step * stats[at + _POWER_SUM * w]
    stats[at + _EXCESS * w] = max(stats[at + _EXCESS * w], energy - initial - work)
    stats[at + _WORK_MAX * w] = max(stats[at + _WORK_MAX * w], abs(work))

    resting = (stats[at + _CLOSED * w] == 1.0) & (drive_lift == 0.0) & (drive_velocity == 0.0)
    before = stats[at + _REST_ENERGY * w]
    rise = energy - (1.0 + ENERGY_REST_RISE) * before
    rise = rise if resting & (not math.isnan(before)) else -math.inf
    stats[at + _REST_RISE * w] = max(stats[at + _REST_RISE * w], rise)
    stats[at + _REST_ENERGY * w] = energy if resting else math.nan


@jit
def finish_observations(
    stats, base, lane, width, step_angle, lift, velocity, preload, seat_depth, out
):
    """Write the ``O_*`` outputs of one lane from its observations and final state.

    step_angle : float  Grid step Δθ [rad] (jump duration = separated grid points × Δθ).
    The status is ``STATUS_NONFINITE`` for a non-finite final state, ``STATUS_UNSTABLE`` if
    the energy ever exceeded its start value plus the cam's work by more than
    ``ENERGY_SLACK`` times the largest work, or the resting energy after closure rose by more
    than ``ENERGY_REST_RISE`` between checks (both plus ``ENERGY_FLOOR_FRACTION·Ps0·δ0``), or
    mode transitions exceed ``TRANSITION_LIMIT``, else ``STATUS_OK``. Layout of ``stats`` as in
    :func:`observe_valve`.
    """
    at = base + lane
    w = width
    out[O_MAX_LIFT] = stats[at + _MAX_LIFT * w]
    out[O_MAX_VELOCITY] = stats[at + _MAX_V * w]
    out[O_MIN_VELOCITY] = stats[at + _MIN_V * w]
    out[O_MAX_ACCELERATION] = stats[at + _MAX_A * w]
    out[O_MIN_ACCELERATION] = stats[at + _MIN_A * w]
    out[O_JUMP_START] = stats[at + _JUMP_START * w]
    out[O_JUMP_DURATION] = stats[at + _JUMP_STEPS * w] * step_angle
    out[O_JUMP_GAP] = stats[at + _JUMP_GAP * w]
    out[O_BOUNCE_COUNT] = stats[at + _BOUNCES * w]
    out[O_BOUNCE_HEIGHT] = stats[at + _BOUNCE_HEIGHT * w]
    # Velocity where the lift crosses δ0, linear between the grid points around closure.
    out[O_SEATING_VELOCITY] = math.nan
    if stats[at + _CLOSED * w] == 1.0:
        y0 = stats[at + _SEAT_Y0 * w]
        v0 = stats[at + _SEAT_V0 * w]
        fraction = (y0 - seat_depth) / (y0 - stats[at + _SEAT_Y1 * w])
        out[O_SEATING_VELOCITY] = abs(v0 + (stats[at + _SEAT_V1 * w] - v0) * fraction)
    out[O_MAX_CONTACT_FORCE] = stats[at + _MAX_FORCE * w]
    out[O_TRANSITIONS] = stats[at + _TRANSITIONS * w]
    floor = ENERGY_FLOOR_FRACTION * preload * seat_depth
    pumped = stats[at + _EXCESS * w] > ENERGY_SLACK * stats[at + _WORK_MAX * w] + floor
    pumped = pumped or stats[at + _REST_RISE * w] > floor
    status = STATUS_OK
    if pumped or stats[at + _TRANSITIONS * w] > TRANSITION_LIMIT:
        status = STATUS_UNSTABLE
    if not (math.isfinite(lift) and math.isfinite(velocity)):
        status = STATUS_NONFINITE
    out[O_STATUS] = status


@jit
def valid_valve_parameters(params, excitation):
    """True if the parameter row and excitation table can be integrated (SPEC §4 inputs)."""
    for c in range(params.shape[0]):
        if not math.isfinite(params[c]):
            return False
    if params[P_SPEED] <= 0.0 or params[P_MASS] <= 0.0 or params[P_SEAT_STIFFNESS] <= 0.0:
        return False
    for c in (
        P_DRIVE_STIFFNESS,
        P_DRIVE_DAMPING,
        P_SPRING_RATE,
        P_SEAT_DAMPING,
        P_EXTERNAL_DAMPING,
    ):
        if params[c] < 0.0:
            return False
    return excitation.shape[1] >= 3


@jit
def stability_substeps(params, grid_step):
    """Sub-steps per grid step needed by the RK4 bound, and ``|h λ|_max`` of the full step.

    params    : 1-D array  Parameter row (``P_*``).
    grid_step : float      Grid step Δθ [rad]; the time step is Δθ/ω.
    """
    radius = valve_spectral_radius(
        params[P_MASS],
        params[P_DRIVE_STIFFNESS],
        params[P_DRIVE_DAMPING],
        params[P_SPRING_RATE],
        params[P_SEAT_STIFFNESS],
        params[P_SEAT_DAMPING],
        params[P_EXTERNAL_DAMPING],
    )
    step = grid_step / params[P_SPEED]
    return stable_substeps(step, radius, STEP_RATIO_TARGET), step * radius


@jit
def prepare_case(excitation, table_step, params, settings, out):
    """Validate one case and apply the stability guard before integrating it.

    Sets every output to NaN, then ``O_SUBSTEPS`` and ``O_STEP_RATIO`` (|h λ|_max per
    sub-step), and the status if the case cannot run. Returns the RK4 sub-steps per grid step,
    or 0 when the case must not be integrated (``STATUS_INVALID_INPUT`` or
    ``STATUS_SUBSTEP_LIMIT``, the needed count left in ``O_SUBSTEPS``). Arguments as in
    :func:`valve_response`.
    """
    out[:] = math.nan
    if not valid_valve_parameters(params, excitation):
        out[O_STATUS] = STATUS_INVALID_INPUT
        return 0
    needed, ratio = stability_substeps(params, 2.0 * table_step)
    guard = settings[S_STABILITY_GUARD] != 0
    substeps = needed if guard else 1
    out[O_SUBSTEPS] = needed
    out[O_STEP_RATIO] = ratio / substeps
    if guard and needed > settings[S_MAX_SUBSTEPS]:
        out[O_STATUS] = STATUS_SUBSTEP_LIMIT
        return 0
    out[O_SUBSTEPS] = substeps
    return substeps


@jit
def error_estimate_is_stable(params, table_step, substeps, settings):
    """True if the step-doubling run (each sub-step twice as long) keeps the RK4 bound.

    Where it would not, the estimate means nothing and ``O_ERROR_ESTIMATE`` stays NaN.
    """
    coarse, _ = stability_substeps(params, 4.0 * table_step)
    return coarse <= substeps or settings[S_STABILITY_GUARD] == 0


@jit
def excitation_at(excitation, table_step, position, speed):
    """Excitation (Y, Ẏ) at a fractional table position by cubic Hermite interpolation.

    excitation : 2-D array  Rows Y [m], Y' [m/rad], Y'' [m/rad²] at spacing ``table_step``.
    table_step : float      Table spacing [rad].
    position   : float      Position in table intervals from the first node [-].
    speed      : float      Camshaft speed ω [rad/s].
    """
    last = excitation.shape[1] - 1
    index = min(int(position), last - 1)
    s = position - index
    lift = hermite_value(
        excitation[0, index],
        excitation[1, index],
        excitation[0, index + 1],
        excitation[1, index + 1],
        table_step,
        s,
    )
    slope = hermite_value(
        excitation[1, index],
        excitation[2, index],
        excitation[1, index + 1],
        excitation[2, index + 1],
        table_step,
        s,
    )
    return lift, speed * slope


@jit
def _guards(
    lift,
    velocity,
    acceleration,
    drive_lift,
    drive_velocity,
    drive_acceleration,
    contact,
    seated,
    k,
    b,
    kz,
    bz,
    depth,
):
    """Switching guards of the current mode and their time derivatives.

    A guard is positive while the mode is consistent: contact ``±(k(Y − y) + b(Ẏ − ẏ))``;
    seated ``δ0 − y`` and ``kz(δ0 − y) − bz ẏ``; unseated the negative of whichever of the
    two is still positive.
    """
    sign = 1.0 if contact else -1.0
    g0 = sign * (k * (drive_lift - lift) + b * (drive_velocity - velocity))
    d0 = sign * (k * (drive_velocity - velocity) + b * (drive_acceleration - acceleration))
    gap = depth - lift
    force = kz * gap - bz * velocity
    force_rate = -kz * velocity - bz * acceleration
    if seated:
        return g0, d0, gap, -velocity, force, force_rate
    if gap <= 0.0:
        return g0, d0, -gap, velocity, math.inf, 0.0
    return g0, d0, -force, -force_rate, math.inf, 0.0


@jit
def _cubic_root(g0, d0, g1, d1):
    """First root in (0, 1] of the cubic Hermite through (g0, d0) and (g1, d1), or −1.

    Values at both ends, slopes per unit of the step fraction; g0 ≥ 0 at the start.
    """
    end = 1.0
    if g1 > 0.0:
        # look for an interior dip below zero at the critical points of the cubic
        a = 6.0 * (g0 - g1) + 3.0 * (d0 + d1)
        bq = -6.0 * (g0 - g1) - 4.0 * d0 - 2.0 * d1
        c = d0
        end = -1.0
        disc = bq * bq - 4.0 * a * c
        if disc >= 0.0 and a != 0.0:
            root = math.sqrt(disc)
            for cand in ((-bq - root) / (2.0 * a), (-bq + root) / (2.0 * a)):
                if 0.0 < cand < 1.0 and hermite_value(g0, d0, g1, d1, 1.0, cand) < 0.0:
                    end = cand if end < 0.0 else min(end, cand)
        elif a == 0.0 and bq != 0.0:
            cand = -c / bq
            if 0.0 < cand < 1.0 and hermite_value(g0, d0, g1, d1, 1.0, cand) < 0.0:
                end = cand
        if end < 0.0:
            return -1.0
    lo = 0.0
    hi = end
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        if hermite_value(g0, d0, g1, d1, 1.0, mid) > 0.0:
            lo = mid
        else:
            hi = mid
    return hi


@jit
def _mode_acceleration(
    lift,
    velocity,
    drive_lift,
    drive_velocity,
    contact,
    seated,
    inv_mass,
    k,
    b,
    ks,
    ps0,
    kz,
    bz,
    gamma,
    depth,
):
    """Acceleration with the contact and seat modes held fixed (no clipping) [m/s²]."""
    force = -ks * lift - ps0 - gamma * velocity
    if contact:
        force += k * (drive_lift - lift) + b * (drive_velocity - velocity)
    if seated:
        force += kz * (depth - lift) - bz * velocity
    return force * inv_mass


@jit
def _mode_step(
    excitation,
    table_step,
    start,
    stop,
    speed,
    lift,
    velocity,
    contact,
    seated,
    inv_mass,
    k,
    b,
    ks,
    ps0,
    kz,
    bz,
    gamma,
    depth,
):
    """One RK4 step in a fixed mode between two table positions; returns the end state."""
    tau = (stop - start) * table_step / speed
    y0, yd0 = excitation_at(excitation, table_step, start, speed)
    ym, ydm = excitation_at(excitation, table_step, 0.5 * (start + stop), speed)
    y1, yd1 = excitation_at(excitation, table_step, stop, speed)
    a1 = _mode_acceleration(
        lift, velocity, y0, yd0, contact, seated, inv_mass, k, b, ks, ps0, kz, bz, gamma, depth
    )
    p2 = lift + 0.5 * tau * velocity
    v2 = velocity + 0.5 * tau * a1
    a2 = _mode_acceleration(
        p2, v2, ym, ydm, contact, seated, inv_mass, k, b, ks, ps0, kz, bz, gamma, depth
    )
    p3 = lift + 0.5 * tau * v2
    v3 = velocity + 0.5 * tau * a2
    a3 = _mode_acceleration(
        p3, v3, ym, ydm, contact, seated, inv_mass, k, b, ks, ps0, kz, bz, gamma, depth
    )
    p4 = lift + tau * v3
    v4 = velocity + tau * a3
    a4 = _mode_acceleration(
        p4, v4, y1, yd1, contact, seated, inv_mass, k, b, ks, ps0, kz, bz, gamma, depth
    )
    return (
        lift + tau / 6.0 * (velocity + 2.0 * v2 + 2.0 * v3 + v4),
        velocity + tau / 6.0 * (a1 + 2.0 * a2 + 2.0 * a3 + a4),
    )


@jit
def _consistent_modes(
    lift, velocity, drive_lift, drive_velocity, contact, seated, k, b, kz, bz, depth
):
    """Modes implied by the state; an exact zero keeps the current mode."""
    drive = k * (drive_lift - lift) + b * (drive_velocity - velocity)
    if drive != 0.0:
        contact = drive > 0.0
    gap = depth - lift
    seat = kz * gap - bz * velocity
    if gap != 0.0 and seat != 0.0:
        seated = gap > 0.0 and seat > 0.0
    return contact, seated


@jit
def _guard_values(
    excitation,
    table_step,
    position,
    speed,
    lift,
    velocity,
    contact,
    seated,
    inv_mass,
    k,
    b,
    ks,
    ps0,
    kz,
    bz,
    gamma,
    depth,
):
    """Guards and time derivatives at a table position (see :func:`_guards`)."""
    drive_lift, drive_velocity = excitation_at(excitation, table_step, position, speed)
    index = min(int(position), excitation.shape[1] - 2)
    s = position - index
    drive_acc = (
        speed
        * speed
        * (excitation[2, index] + s * (excitation[2, index + 1] - excitation[2, index]))
    )
    acc = _mode_acceleration(
        lift,
        velocity,
        drive_lift,
        drive_velocity,
        contact,
        seated,
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
    return _guards(
        lift,
        velocity,
        acc,
        drive_lift,
        drive_velocity,
        drive_acc,
        contact,
        seated,
        k,
        b,
        kz,
        bz,
        depth,
    )


@jit
def _switch_aware_step(
    excitation,
    table_step,
    start,
    stop,
    speed,
    lift,
    velocity,
    inv_mass,
    k,
    b,
    ks,
    ps0,
    kz,
    bz,
    gamma,
    depth,
):
    """RK4 from table position ``start`` to ``stop`` with located contact and seat switches.

    Returns the end state and the number of located switches.
    """
    drive_lift, drive_velocity = excitation_at(excitation, table_step, start, speed)
    contact, seated = _consistent_modes(
        lift, velocity, drive_lift, drive_velocity, False, lift < depth, k, b, kz, bz, depth
    )
    position = start
    switches = 0
    for _ in range(SWITCHES_PER_STEP + 1):
        span = stop - position
        tau = span * table_step / speed
        new_lift, new_velocity = _mode_step(
            excitation,
            table_step,
            position,
            stop,
            speed,
            lift,
            velocity,
            contact,
            seated,
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
        if switches == SWITCHES_PER_STEP:
            return new_lift, new_velocity, switches
        ga0, da0, gb0, db0, gc0, dc0 = _guard_values(
            excitation,
            table_step,
            position,
            speed,
            lift,
            velocity,
            contact,
            seated,
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
        ga1, da1, gb1, db1, gc1, dc1 = _guard_values(
            excitation,
            table_step,
            stop,
            speed,
            new_lift,
            new_velocity,
            contact,
            seated,
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
        first = 2.0
        which = -1
        for g0, d0, g1, d1, label in (
            (ga0, da0, ga1, da1, 0),
            (gb0, db0, gb1, db1, 1),
            (gc0, dc0, gc1, dc1, 2),
        ):
            if math.isinf(g0):
                continue
            root = _cubic_root(max(g0, 0.0), d0 * tau, g1, d1 * tau)
            if 0.0 <= root < first:
                first = root
                which = label
        if which < 0:
            return new_lift, new_velocity, switches
        fraction = min(first + SWITCH_OVERSHOOT, 1.0)
        for _newton in range(4):
            target = position + fraction * span
            trial_lift, trial_velocity = _mode_step(
                excitation,
                table_step,
                position,
                target,
                speed,
                lift,
                velocity,
                contact,
                seated,
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
            guards = _guard_values(
                excitation,
                table_step,
                target,
                speed,
                trial_lift,
                trial_velocity,
                contact,
                seated,
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
            g = guards[2 * which]
            dg = guards[2 * which + 1] * tau
            if g < 0.0 or dg >= 0.0 or fraction >= 1.0:
                break
            fraction = min(fraction - g / dg + SWITCH_OVERSHOOT, 1.0)
        position = target
        lift = trial_lift
        velocity = trial_velocity
        switches += 1
        drive_lift, drive_velocity = excitation_at(excitation, table_step, position, speed)
        new_contact, new_seated = _consistent_modes(
            lift, velocity, drive_lift, drive_velocity, contact, seated, k, b, kz, bz, depth
        )
        if new_contact == contact and new_seated == seated:
            if which == 0:
                new_contact = not contact
            else:
                new_seated = not seated
        contact = new_contact
        seated = new_seated
        if position >= stop:
            return lift, velocity, switches
    return lift, velocity, switches


@jit
def _integrate(
    excitation,
    table_step,
    table_start,
    stride,
    params,
    substeps,
    switch_aware,
    stats,
    out,
    curves,
    trace,
    compare,
):
    """Integrate one case over the table with RK4 grid step ``2·stride·table_step``.

    Fills ``out`` (``O_*`` rows from :func:`finish_observations`), the curves if
    ``curves`` has columns, and either records the lift at each grid point into ``trace`` or
    (``compare``) returns the largest difference from a trace recorded at half this step.
    """
    speed = params[P_SPEED]
    mass = params[P_MASS]
    k = params[P_DRIVE_STIFFNESS]
    b = params[P_DRIVE_DAMPING]
    ks = params[P_SPRING_RATE]
    ps0 = params[P_PRELOAD]
    kz = params[P_SEAT_STIFFNESS]
    bz = params[P_SEAT_DAMPING]
    gamma = params[P_EXTERNAL_DAMPING]
    inv_mass = 1.0 / mass
    depth = ps0 / kz
    half = stride
    n_steps = (excitation.shape[1] - 1) // (2 * half)
    grid_step = 2.0 * half * table_step
    tau = grid_step / speed / substeps
    lift = params[P_INITIAL_LIFT]
    velocity = params[P_INITIAL_VELOCITY]
    reset_observations(stats, 0, 0, 1, lift, velocity)
    store = curves.shape[1] > 0
    record = trace.shape[0] > 0
    difference = 0.0
    for n in range(n_steps + 1):
        node = 2 * half * n
        drive_lift = excitation[0, node]
        drive_velocity = speed * excitation[1, node]
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
        observe_valve(
            stats,
            0,
            0,
            1,
            table_start + n * grid_step,
            lift,
            velocity,
            acc,
            drive_lift,
            drive_velocity,
            b,
            k,
            ps0,
            kz,
            bz,
            depth,
        )
        if n % ENERGY_INTERVAL == 0 or n == n_steps:
            observe_energy(
                stats,
                0,
                0,
                1,
                grid_step / speed,
                lift,
                velocity,
                drive_lift,
                drive_velocity,
                mass,
                k,
                ks,
                ps0,
                kz,
                depth,
            )
        if store:
            curves[C_LIFT, n] = lift
            curves[C_VELOCITY, n] = velocity
            curves[C_ACCELERATION, n] = acc
            drive = k * (drive_lift - lift) + b * (drive_velocity - velocity)
            curves[C_DRIVE_FORCE, n] = max(0.0, drive)
            seat = kz * (depth - lift) - bz * velocity
            curves[C_SEAT_FORCE, n] = seat if (seat > 0.0 and lift < depth) else 0.0
        if record:
            if compare:
                difference = max(difference, abs(lift - trace[2 * n]))
            else:
                trace[n] = lift
        if n == n_steps:
            break
        if switch_aware:
            for j in range(substeps):
                start = node + 2.0 * half * j / substeps
                stop = node + 2.0 * half * (j + 1) / substeps
                lift, velocity, _ = _switch_aware_step(
                    excitation,
                    table_step,
                    start,
                    stop,
                    speed,
                    lift,
                    velocity,
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
        elif substeps == 1:
            mid_lift = excitation[0, node + half]
            mid_velocity = speed * excitation[1, node + half]
            end_lift = excitation[0, node + 2 * half]
            end_velocity = speed * excitation[1, node + 2 * half]
            lift, velocity = _rk4_step(
                lift,
                velocity,
                acc,
                tau,
                mid_lift,
                mid_velocity,
                end_lift,
                end_velocity,
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
        else:
            for j in range(substeps):
                start = node + 2.0 * half * j / substeps
                y0, yd0 = excitation_at(excitation, table_step, start, speed)
                ym, ydm = excitation_at(
                    excitation, table_step, node + 2.0 * half * (j + 0.5) / substeps, speed
                )
                y1, yd1 = excitation_at(
                    excitation, table_step, node + 2.0 * half * (j + 1) / substeps, speed
                )
                a0 = valve_acceleration(
                    lift, velocity, y0, yd0, inv_mass, k, b, ks, ps0, kz, bz, gamma, depth
                )
                lift, velocity = _rk4_step(
                    lift,
                    velocity,
                    a0,
                    tau,
                    ym,
                    ydm,
                    y1,
                    yd1,
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
    finish_observations(stats, 0, 0, 1, grid_step, lift, velocity, ps0, depth, out)
    return difference


@jit
def _rk4_step(
    lift, velocity, acc, tau, ym, ydm, y1, yd1, inv_mass, k, b, ks, ps0, kz, bz, gamma, depth
):
    """One classic RK4 step of [V2] given the first-stage acceleration ``acc`` [m/s²]."""
    p2 = lift + 0.5 * tau * velocity
    v2 = velocity + 0.5 * tau * acc
    a2 = valve_acceleration(p2, v2, ym, ydm, inv_mass, k, b, ks, ps0, kz, bz, gamma, depth)
    p3 = lift + 0.5 * tau * v2
    v3 = velocity + 0.5 * tau * a2
    a3 = valve_acceleration(p3, v3, ym, ydm, inv_mass, k, b, ks, ps0, kz, bz, gamma, depth)
    p4 = lift + tau * v3
    v4 = velocity + tau * a3
    a4 = valve_acceleration(p4, v4, y1, yd1, inv_mass, k, b, ks, ps0, kz, bz, gamma, depth)
    return (
        lift + tau / 6.0 * (velocity + 2.0 * v2 + 2.0 * v3 + v4),
        velocity + tau / 6.0 * (acc + 2.0 * a2 + 2.0 * a3 + a4),
    )


@jit
def valve_response(excitation, table_step, table_start, params, settings, out, curves):
    """Valve dynamics of one case: fixed-step RK4 of [V2] with outputs ``O_*`` (SPEC §4).

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
    inputs are valid. Reference: SPEC §4.
    """
    substeps = prepare_case(excitation, table_step, params, settings, out)
    if substeps == 0:
        return
    switch_aware = settings[S_SWITCH_AWARE] != 0
    estimate = settings[S_ESTIMATE_ERROR] != 0 and excitation.shape[1] >= 5
    stats = np.empty(N_STATS)
    trace = np.empty((excitation.shape[1] - 1) // 2 + 1 if estimate else 0)
    _integrate(
        excitation,
        table_step,
        table_start,
        1,
        params,
        substeps,
        switch_aware,
        stats,
        out,
        curves,
        trace,
        False,
    )
    if estimate and error_estimate_is_stable(params, table_step, substeps, settings):
        scratch = np.empty(out.shape[0])
        difference = _integrate(
            excitation,
            table_step,
            table_start,
            2,
            params,
            substeps,
            switch_aware,
            stats,
            scratch,
            curves[:, :0],
            trace,
            True,
        )
        out[O_ERROR_ESTIMATE] = difference / ERROR_ORDER_DIVISOR


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


JUMP_FOUND = 0
JUMP_NONE_IN_RANGE = 1
JUMP_AT_LOWER_BOUND = 2
JUMP_RUN_FAILED = 3
JUMP_STATUS_NAMES = ("found", "none_in_range", "at_lower_bound", "run_failed")


@jit
def jump_speed(
    excitation,
    table_step,
    table_start,
    params,
    settings,
    speed_low,
    speed_high,
    scan_points,
    tolerance,
):
    """Lowest camshaft speed at which the valve separates from the drive (SPEC §4).

    Scans ``scan_points`` geometrically spaced speeds from ``speed_low`` to ``speed_high``
    for the first one with a jump (``O_JUMP_DURATION > 0``), then bisects between it and
    the previous scan point until the bracket is narrower than ``tolerance`` times its
    upper end. Returns ``(speed [rad/s], code)`` with code ``JUMP_FOUND``,
    ``JUMP_NONE_IN_RANGE`` (speed NaN), ``JUMP_AT_LOWER_BOUND`` (separates already at
    ``speed_low``) or ``JUMP_RUN_FAILED`` (a run did not finish with ``STATUS_OK``).

    params      : 1-D array  Parameter row (``P_*``); its speed entry is ignored.
    speed_low   : float      Lower end of the search [rad/s].
    speed_high  : float      Upper end of the search [rad/s].
    scan_points : int        Number of scan speeds (≥ 2).
    tolerance   : float      Relative bracket width at which bisection stops [-].
    Other arguments as in :func:`valve_response`.
    """
    work = params.copy()
    out = np.empty(len(VALVE_OUTPUT_NAMES))
    no_curves = np.empty((len(VALVE_CURVE_NAMES), 0))
    below = speed_low
    above = math.nan
    for i in range(scan_points):
        speed = speed_low * (speed_high / speed_low) ** (i / (scan_points - 1))
        work[P_SPEED] = speed
        valve_response(excitation, table_step, table_start, work, settings, out, no_curves)
        if out[O_STATUS] != STATUS_OK:
            return math.nan, JUMP_RUN_FAILED
        if out[O_JUMP_DURATION] > 0.0:
            if i == 0:
                return speed, JUMP_AT_LOWER_BOUND
            above = speed
            break
        below = speed
    if math.isnan(above):
        return math.nan, JUMP_NONE_IN_RANGE
    while above - below > tolerance * above:
        work[P_SPEED] = 0.5 * (below + above)
        valve_response(excitation, table_step, table_start, work, settings, out, no_curves)
        if out[O_STATUS] != STATUS_OK:
            return math.nan, JUMP_RUN_FAILED
        if out[O_JUMP_DURATION] > 0.0:
            above = work[P_SPEED]
        else:
            below = work[P_SPEED]
    return above, JUMP_FOUND
