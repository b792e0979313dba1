"""Energy balance of a valve run: the physics check behind ``STATUS_UNSTABLE`` (physics §4).

The valve-train energy may never exceed its start value plus the work the cam did through the
drive, and may only fall once the valve has closed on the base circle (checked every
``ENERGY_INTERVAL`` grid points), else the run is ``STATUS_UNSTABLE``. An unstable step
clipped by the one-sided seat shows up as chatter and pumped energy, not NaN. Energy, work and
power are per unit mass [J/kg], [W/kg]; the running values are ``ST_*`` rows of the
observations (:mod:`engine_kernels.valvetrain.valve.observations`).
"""

from __future__ import annotations

import math

import numpy as np

from engine_kernels._jit import jit, jit_inline
from engine_kernels.valvetrain.valve.layout import (
    K_PRELOAD,
    K_SEAT_DEPTH,
    K_TIME_STEP,
    PHASE_CLOSED,
    ST_ENERGY0,
    ST_EXCESS,
    ST_PHASE,
    ST_POWER_FIRST,
    ST_POWER_SUM,
    ST_REST_ENERGY,
    ST_REST_RISE,
    ST_WORK_MAX,
)
from engine_kernels.valvetrain.valve.model import (
    HALF,
    INF,
    NAN,
    ONE,
    TWO,
    ZERO,
    case_coefficients,
    larger,
    positive_part,
    valve_energy,
)

ENERGY_SLACK = 0.05
ENERGY_REST_RISE = np.float32(0.25)
ENERGY_FLOOR_FRACTION = 1e-3
ENERGY_INTERVAL = 8


@jit_inline
def drive_power(drive, drive_velocity):
    """Cam power into the drive per unit mass, ``max(0, F_drive/M)·Ẏ`` [W/kg].

    drive          : float  Drive force per unit mass before clipping [N/kg].
    drive_velocity : float  Ẏ [m/s].
    """
    return positive_part(drive) * drive_velocity


@jit_inline
def observe_energy(record, at, w, lift, velocity, drive_lift, drive_velocity, drive):
    """Energy checks (every ``ENERGY_INTERVAL`` grid points and at the end).

    The exact solution keeps ``E(t) − E(0) ≤ W(t)``, the work done by the cam through the
    drive (:func:`engine_kernels.valvetrain.valve.model.valve_energy`); once the valve has closed and the
    cam is on its base circle (Y = Ẏ = 0), E can only fall. An unstable RK4 step pumps energy
    in from nowhere: a gross blow-up breaks the first law, chatter on a too-stiff seat
    (clipped by the one-sided seat, so it never becomes NaN) breaks the second. Growth is
    exponential, so sampling every few grid points loses nothing. Keeps the largest excess
    ``E − E(0) − W``, the largest ``|W|`` and the largest rise of the resting energy between
    checks beyond ``ENERGY_REST_RISE`` for :func:`finish_observations`. Energy and work are
    per unit mass [J/kg]; W is the trapezoidal sum of the power over the grid points.

    The grid time step Δθ/ω is the record's ``K_TIME_STEP`` row; arguments as in
    :func:`engine_kernels.valvetrain.valve.observations.start_observations`.
    """
    energy = valve_energy(lift, velocity, drive_lift, case_coefficients(record, at, w))
    initial = record[at + ST_ENERGY0 * w]
    initial = energy if math.isnan(initial) else initial
    record[at + ST_ENERGY0 * w] = initial
    power = drive_power(drive, drive_velocity)
    trapezoid = TWO * record[at + ST_POWER_SUM * w] - record[at + ST_POWER_FIRST * w] - power
    work = HALF * record[at + K_TIME_STEP * w] * trapezoid
    record[at + ST_EXCESS * w] = larger(record[at + ST_EXCESS * w], energy - initial - work)
    record[at + ST_WORK_MAX * w] = larger(record[at + ST_WORK_MAX * w], abs(work))

    closed = record[at + ST_PHASE * w] >= PHASE_CLOSED
    resting = closed & (drive_lift == ZERO) & (drive_velocity == ZERO)
    before = record[at + ST_REST_ENERGY * w]
    rise = energy - (ONE + ENERGY_REST_RISE) * before
    rise = rise if resting & (not math.isnan(before)) else -INF
    record[at + ST_REST_RISE * w] = larger(record[at + ST_REST_RISE * w], rise)
    record[at + ST_REST_ENERGY * w] = energy if resting else NAN


@jit
def energy_pumped(record, at, w, resolution):
    """True if a run broke the energy balance checked by :func:`observe_energy`.

    That is, if the energy ever exceeded its start value plus the cam's work by more than
    ``ENERGY_SLACK`` times the largest work, or the resting energy after closure rose by more
    than ``ENERGY_REST_RISE`` between checks (both plus the floor
    ``Ps0'·(ENERGY_FLOOR_FRACTION·δ0 + resolution)``).

    record, at, w : Record of the case (see :func:`observe_energy`); Ps0' and δ0 set the floor.
    resolution    : float  Lift the integrator resolves [m]: 0 for fixed-step RK4, the lift
                    tolerance per step for ``dopri``. A lift error ε moves the energy per
                    unit mass by Ps0'·ε, so a change below Ps0'·resolution is no evidence:
                    on a 1e8 N/mm seat with no seat damping (δ0 = 2 nm) the resting valve's
                    energy moved by 6e-8 J/kg, 25 % of itself, in a ``dopri`` run at 1e-7 m
                    whose bounces agreed with scipy's, and the run read unstable.
    """
    preload = record[at + K_PRELOAD * w]
    floor = preload * (ENERGY_FLOOR_FRACTION * record[at + K_SEAT_DEPTH * w] + resolution)
    pumped = record[at + ST_EXCESS * w] > ENERGY_SLACK * record[at + ST_WORK_MAX * w] + floor
    return pumped or record[at + ST_REST_RISE * w] > floor
