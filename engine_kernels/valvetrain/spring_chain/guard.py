"""Input checks, stability guard and run status of the multi-mass spring kernels [V4].

Shared by the one-case kernel (:mod:`engine_kernels.valvetrain.spring_chain.one_case`) and
the lane kernel (:mod:`engine_kernels.valvetrain.spring_chain.lanes`), so a case is refused,
sub-stepped and judged the same way by both.

Stability guard: the bound of :func:`~engine_kernels.valvetrain.spring_chain.model.chain_spectral_radius`
(every contact active, coil clash included) sets equal sub-steps keeping ``|h λ| ≤ 2`` (the
lumped kernel's ``STEP_RATIO_TARGET``, under RK4's 2.6); past ``max_substeps`` the case is
refused with ``STATUS_SUBSTEP_LIMIT``. Reference: physics §4 [V2], [V4].
"""

from __future__ import annotations

import math

from engine_kernels._jit import jit
from engine_kernels.valvetrain.rk4 import stable_substeps
from engine_kernels.valvetrain.spring_chain.layout import (
    CO_STATUS,
    CO_STEP_RATIO,
    CO_SUBSTEPS,
    MAX_SPRING_MASSES,
    MIN_SPRING_MASSES,
    SC_CLASH_DAMPING,
    SC_CLASH_STIFFNESS,
    SC_CLASH_TRAVEL,
    SC_DRIVE_DAMPING,
    SC_DRIVE_STIFFNESS,
    SC_EXTERNAL_DAMPING,
    SC_SEAT_DAMPING,
    SC_SEAT_STIFFNESS,
    SC_SPEED,
    SC_SPRING_DAMPING_RATIO,
    SC_SPRING_MASS,
    SC_SPRING_MASSES,
    SC_SPRING_RATE,
    SC_VALVE_MASS,
)
from engine_kernels.valvetrain.spring_chain.model import chain_spectral_radius
from engine_kernels.valvetrain.valve.guard import STEP_RATIO_TARGET
from engine_kernels.valvetrain.valve.layout import (
    S_MAX_SUBSTEPS,
    S_STABILITY_GUARD,
    STATUS_INVALID_INPUT,
    STATUS_NONFINITE,
    STATUS_OK,
    STATUS_SUBSTEP_LIMIT,
    STATUS_UNSTABLE,
)

# Energy gained beyond the cam's work, as a fraction of the run's energy scale, above which a
# run is reported unstable: RK4 and the trapezoidal work integral stay far below it.
ENERGY_SLACK = 0.05


@jit
def valid_chain_parameters(params, excitation):
    """True if an ``SC_*`` row and the excitation table can be integrated.

    params : 1-D array  ``SC_*`` row (SI units);  excitation : 2-D array (3, n), n ≥ 3.
    """
    for c in range(params.shape[0]):
        if not math.isfinite(params[c]):
            return False
    masses = params[SC_SPRING_MASSES]
    if masses != math.floor(masses) or not MIN_SPRING_MASSES <= masses <= MAX_SPRING_MASSES:
        return False
    for c in (SC_SPEED, SC_VALVE_MASS, SC_SPRING_MASS, SC_SPRING_RATE):
        if params[c] <= 0.0:
            return False
    for c in (
        SC_DRIVE_STIFFNESS,
        SC_DRIVE_DAMPING,
        SC_SEAT_STIFFNESS,
        SC_SEAT_DAMPING,
        SC_EXTERNAL_DAMPING,
        SC_SPRING_DAMPING_RATIO,
        SC_CLASH_TRAVEL,
        SC_CLASH_STIFFNESS,
        SC_CLASH_DAMPING,
    ):
        if params[c] < 0.0:
            return False
    return excitation.shape[1] >= 3


@jit
def chain_stability_substeps(params, grid_step):
    """Sub-steps per grid step keeping ``|h λ| ≤ STEP_RATIO_TARGET``, and ``|h λ|_max``.

    params : 1-D array  ``SC_*`` row;  grid_step : float  Δθ [rad] (time step Δθ/ω).
    """
    radius = chain_spectral_radius(params)
    step = grid_step / params[SC_SPEED]
    return stable_substeps(step, radius, STEP_RATIO_TARGET), step * radius


@jit
def prepare_chain_case(excitation, table_step, params, settings, out):
    """Validate one case and apply the stability guard before integrating it.

    Sets every output to NaN, then ``CO_SUBSTEPS`` (the needed count) and ``CO_STEP_RATIO``
    (|h λ|_max per sub-step), and the status if the case cannot run. Returns the RK4 sub-steps
    per grid step, or 0 when the case must not be integrated (``STATUS_INVALID_INPUT`` or
    ``STATUS_SUBSTEP_LIMIT``). Arguments as in :func:`spring_chain_response`.
    """
    out[:] = math.nan
    if not valid_chain_parameters(params, excitation):
        out[CO_STATUS] = STATUS_INVALID_INPUT
        return 0
    needed, ratio = chain_stability_substeps(params, 2.0 * table_step)
    guard = settings[S_STABILITY_GUARD] != 0
    substeps = needed if guard else 1
    out[CO_SUBSTEPS] = needed
    out[CO_STEP_RATIO] = ratio / substeps
    if guard and needed > settings[S_MAX_SUBSTEPS]:
        out[CO_STATUS] = STATUS_SUBSTEP_LIMIT
        return 0
    return substeps


@jit
def chain_status(finite, energy_excess):
    """Status of an integrated run: ``STATUS_NONFINITE`` if the end state is not finite,
    ``STATUS_UNSTABLE`` if the energy excess (fraction of the run's scale) passes
    ``ENERGY_SLACK``, else ``STATUS_OK``."""
    if not finite:
        return STATUS_NONFINITE
    if energy_excess > ENERGY_SLACK:
        return STATUS_UNSTABLE
    return STATUS_OK
