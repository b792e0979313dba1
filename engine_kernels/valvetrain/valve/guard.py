"""Stability guard of the valve integrators: input checks and RK4 sub-step counts (physics §4).

Explicit RK4 is stable only while ``|h λ|`` stays inside its stability region for every
eigenvalue of the active linear system. Before a case is integrated, the largest eigenvalue
modulus over the four linear modes of [V2] (contact+seat, contact, seat, free) sets the
number of equal sub-steps that keeps ``|h λ| ≤ STEP_RATIO_TARGET`` (2.0, a margin under
``RK4_STABILITY_BOUND`` = 2.6); past ``max_substeps`` the case is not integrated and its
status is ``STATUS_SUBSTEP_LIMIT`` (with the needed count in ``O_SUBSTEPS``). The check of the
run itself, from the physics, is in :mod:`engine_kernels.valvetrain.valve.energy_balance`.
"""

from __future__ import annotations

import math

import numpy as np

from engine_kernels._jit import jit
from engine_kernels.valvetrain.rk4 import MAX_SUBSTEPS, stable_substeps
from engine_kernels.valvetrain.valve.layout import (
    O_STATUS,
    O_STEP_RATIO,
    O_SUBSTEPS,
    P_DRIVE_DAMPING,
    P_DRIVE_STIFFNESS,
    P_EXTERNAL_DAMPING,
    P_MASS,
    P_SEAT_DAMPING,
    P_SEAT_STIFFNESS,
    P_SPEED,
    P_SPRING_RATE,
    S_MAX_SUBSTEPS,
    S_STABILITY_GUARD,
    S_SUBSTEPS,
    STATUS_INVALID_INPUT,
    STATUS_SUBSTEP_LIMIT,
)
from engine_kernels.valvetrain.valve.model import valve_spectral_radius

# Sub-steps keep |h λ| at or below this, with a margin under RK4_STABILITY_BOUND: each linear
# mode is stable up to the bound, but the switching, clipped system still pumps energy at
# hard seat impacts when a mode sits right at it.
STEP_RATIO_TARGET = 2.0


@jit
def valid_valve_parameters(params, excitation):
    """True if the parameter row and excitation table can be integrated (physics §4 inputs).

    params     : 1-D array  Parameter row (``P_*``, SI units).
    excitation : 2-D array  Excitation table (3, n); at least one RK4 step (n ≥ 3).
    """
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
    radius = valve_spectral_radius(params)
    step = grid_step / params[P_SPEED]
    return stable_substeps(step, radius, STEP_RATIO_TARGET), step * radius


def stability_substeps_rows(rows, grid_steps):
    """:func:`stability_substeps` of every parameter row, in NumPy (the plan's check of a
    design: it runs before anything is compiled, on up to millions of rows at once).

    rows      : 2-D array  Parameter rows (``P_*``), one per case; masses > 0.
    grid_steps: 1-D array  Grid step Δθ of each case [rad].
    Returns the sub-steps per grid step (int64) and ``|h λ|_max`` of the full step per row.
    """
    mass = rows[:, P_MASS]
    k, b = rows[:, P_DRIVE_STIFFNESS], rows[:, P_DRIVE_DAMPING]
    ks, gamma = rows[:, P_SPRING_RATE], rows[:, P_EXTERNAL_DAMPING]
    kz, bz = rows[:, P_SEAT_STIFFNESS], rows[:, P_SEAT_DAMPING]
    radius = _oscillator_radii(mass, b + bz + gamma, k + kz + ks)
    for damping, stiffness in ((b + gamma, k + ks), (bz + gamma, kz + ks), (gamma, ks)):
        radius = np.maximum(radius, _oscillator_radii(mass, damping, stiffness))
    with np.errstate(all="ignore"):  # a speed of 1e-300 rad/s needs more than any count
        ratio = grid_steps / rows[:, P_SPEED] * radius
        scaled = ratio / STEP_RATIO_TARGET
        needed = np.where(scaled < MAX_SUBSTEPS, np.ceil(scaled), MAX_SUBSTEPS)
        needed = np.where(scaled <= 1.0, 1, needed).astype(np.int64)
    return needed, ratio


def _oscillator_radii(mass, damping, stiffness):
    """:func:`~engine_kernels.valvetrain.rk4.oscillator_spectral_radius` of arrays."""
    with np.errstate(all="ignore"):  # IEEE results, as compiled: a tiny mass gives inf
        discriminant = damping * damping - 4.0 * mass * stiffness
        under = np.sqrt(stiffness / mass)
        over = (damping + np.sqrt(discriminant)) / (2.0 * mass)
    return np.where(discriminant < 0.0, under, over)


@jit
def prepare_case(excitation, table_step, params, settings, out):
    """Validate one case and apply the stability guard before integrating it.

    Sets every output to NaN, then ``O_SUBSTEPS`` and ``O_STEP_RATIO`` (|h λ|_max per
    sub-step), and the status if the case cannot run. Returns the RK4 sub-steps per grid step
    (the stable count, or 1 without the guard, raised to ``S_SUBSTEPS`` if that is larger),
    or 0 when the case must not be integrated (``STATUS_INVALID_INPUT`` or
    ``STATUS_SUBSTEP_LIMIT``, the needed count left in ``O_SUBSTEPS``).

    excitation : 2-D array  Excitation table (3, n) at spacing ``table_step`` [m, m/rad, m/rad²].
    table_step : float      Table spacing [rad]; the RK4 grid step is twice it.
    params     : 1-D array  Parameter row (``P_*``).
    settings   : 1-D int64  ``S_*`` settings.
    out        : 1-D array  Output row (``O_*``).
    """
    out[:] = math.nan
    if not valid_valve_parameters(params, excitation):
        out[O_STATUS] = STATUS_INVALID_INPUT
        return 0
    needed, ratio = stability_substeps(params, 2.0 * table_step)
    guard = settings[S_STABILITY_GUARD] != 0
    substeps = max(needed if guard else 1, settings[S_SUBSTEPS])
    out[O_SUBSTEPS] = needed
    out[O_STEP_RATIO] = ratio / substeps
    if guard and needed > settings[S_MAX_SUBSTEPS]:
        out[O_STATUS] = STATUS_SUBSTEP_LIMIT
        return 0
    out[O_SUBSTEPS] = substeps
    return substeps
