"""Valve-train kernels: rocker, valve model [V1], [V2], RK4 integrators, lanes (physics §3, §4).

One physical concept per module:

* :mod:`~engine_kernels.valvetrain.rocker` — rocker kinematics [R1]–[R6], tappet law;
* :mod:`~engine_kernels.valvetrain.valve.layout` — parameter, output, curve and settings rows of
  the valve kernels, and the case record (coefficients, time steps, observations) they share;
* :mod:`~engine_kernels.valvetrain.valve.model` — coefficients, forces, energy and stiffest mode of
  [V2], the excitation table;
* :mod:`~engine_kernels.valvetrain.rk4` — RK4 stability and Hermite interpolation;
  :mod:`~engine_kernels.valvetrain.valve.step` — one RK4 step of [V2];
* :mod:`~engine_kernels.valvetrain.valve.guard` — input checks and stable sub-step counts;
* :mod:`~engine_kernels.valvetrain.valve.observations` and
  :mod:`~engine_kernels.valvetrain.valve.energy_balance` — running observations, outputs and the
  physics check of a run;
* :mod:`~engine_kernels.valvetrain.valve.modes` and :mod:`~engine_kernels.valvetrain.valve.switching` —
  switch-aware RK4 with located contact and seat switches;
* :mod:`~engine_kernels.valvetrain.dopri.integrate` with :mod:`~engine_kernels.valvetrain.dopri.step`
  and :mod:`~engine_kernels.valvetrain.dopri.observe` — adaptive Dormand–Prince 5(4) with
  switches located on its dense output, one case at a time (imported as its own module);
* :mod:`~engine_kernels.valvetrain.valve.one_case` — one case at a time;
  :mod:`~engine_kernels.valvetrain.valve.jump` — jump-speed search;
* :mod:`~engine_kernels.valvetrain.valve.lanes` and :mod:`~engine_kernels.valvetrain.valve.lane_batch` —
  blocks of cases in SIMD lanes;
* the multi-mass spring [V4]: :mod:`~engine_kernels.valvetrain.spring_chain.model` (model),
  ``spring_chain_layout`` (rows), ``spring_chain_guard`` (input checks, sub-steps, status),
  ``spring_chain_response`` (one case at a time, and the batch entry
  ``spring_chain_response_batch``), ``spring_chain_lanes`` with ``spring_chain_lane_layout``,
  ``spring_chain_lane_observations`` and ``spring_chain_lane_batch`` (SIMD lanes).

This package re-exports the public API of the one-case valve kernels and their data layout,
so ``from engine_kernels import valvetrain`` is the one import a caller of them needs.
"""

from __future__ import annotations

from engine_kernels.valvetrain.valve.energy_balance import (
    ENERGY_FLOOR_FRACTION,
    ENERGY_INTERVAL,
    ENERGY_REST_RISE,
    ENERGY_SLACK,
)
from engine_kernels.valvetrain.valve.guard import (
    STEP_RATIO_TARGET,
    prepare_case,
    stability_substeps,
    stability_substeps_batch,
    valid_valve_parameters,
)
from engine_kernels.valvetrain.valve.jump import (
    JUMP_AT_LOWER_BOUND,
    JUMP_FOUND,
    JUMP_NONE_IN_RANGE,
    JUMP_RUN_FAILED,
    JUMP_STATUS_NAMES,
    jump_speed,
)
from engine_kernels.valvetrain.valve.layout import (
    C_ACCELERATION,
    C_DRIVE_FORCE,
    C_LIFT,
    C_SEAT_FORCE,
    C_VELOCITY,
    DEFAULT_MAX_SUBSTEPS,
    N_RECORD,
    O_BOUNCE_COUNT,
    O_BOUNCE_HEIGHT,
    O_ERROR_ESTIMATE,
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
    O_STEP_RATIO,
    O_SUBSTEPS,
    O_TRANSITIONS,
    P_DRIVE_DAMPING,
    P_DRIVE_STIFFNESS,
    P_EXTERNAL_DAMPING,
    P_INITIAL_LIFT,
    P_INITIAL_VELOCITY,
    P_MASS,
    P_PRELOAD,
    P_SEAT_DAMPING,
    P_SEAT_STIFFNESS,
    P_SPEED,
    P_SPRING_RATE,
    S_ESTIMATE_ERROR,
    S_MAX_SUBSTEPS,
    S_STABILITY_GUARD,
    S_SUBSTEPS,
    S_SWITCH_AWARE,
    STATUS_INVALID_INPUT,
    STATUS_NONFINITE,
    STATUS_OK,
    STATUS_SUBSTEP_LIMIT,
    STATUS_UNSTABLE,
    VALVE_CURVE_NAMES,
    VALVE_CURVE_UNITS,
    VALVE_OUTPUT_NAMES,
    VALVE_OUTPUT_UNITS,
    VALVE_PARAM_NAMES,
    VALVE_PARAM_UNITS,
    VALVE_STATUS_NAMES,
    valve_settings,
)
from engine_kernels.valvetrain.valve.model import (
    TRANSITION_BAND,
    equivalent_mass,
    excitation_at,
    valve_acceleration,
    valve_coefficients,
    valve_energy,
    valve_spectral_radius,
)
from engine_kernels.valvetrain.valve.one_case import (
    valve_lift_batch,
    valve_response,
    valve_response_batch,
)
from engine_kernels.valvetrain.valve.step import (
    rk4_valve_step,
)
from engine_kernels.valvetrain.valve.switching import (
    SWITCH_OVERSHOOT,
    SWITCHES_PER_STEP,
)

__all__ = [
    "C_ACCELERATION",
    "C_DRIVE_FORCE",
    "C_LIFT",
    "C_SEAT_FORCE",
    "C_VELOCITY",
    "DEFAULT_MAX_SUBSTEPS",
    "ENERGY_FLOOR_FRACTION",
    "ENERGY_INTERVAL",
    "ENERGY_REST_RISE",
    "ENERGY_SLACK",
    "JUMP_AT_LOWER_BOUND",
    "JUMP_FOUND",
    "JUMP_NONE_IN_RANGE",
    "JUMP_RUN_FAILED",
    "JUMP_STATUS_NAMES",
    "N_RECORD",
    "O_BOUNCE_COUNT",
    "O_BOUNCE_HEIGHT",
    "O_ERROR_ESTIMATE",
    "O_JUMP_DURATION",
    "O_JUMP_GAP",
    "O_JUMP_START",
    "O_MAX_ACCELERATION",
    "O_MAX_CONTACT_FORCE",
    "O_MAX_LIFT",
    "O_MAX_VELOCITY",
    "O_MIN_ACCELERATION",
    "O_MIN_VELOCITY",
    "O_SEATING_VELOCITY",
    "O_STATUS",
    "O_STEP_RATIO",
    "O_SUBSTEPS",
    "O_TRANSITIONS",
    "P_DRIVE_DAMPING",
    "P_DRIVE_STIFFNESS",
    "P_EXTERNAL_DAMPING",
    "P_INITIAL_LIFT",
    "P_INITIAL_VELOCITY",
    "P_MASS",
    "P_PRELOAD",
    "P_SEAT_DAMPING",
    "P_SEAT_STIFFNESS",
    "P_SPEED",
    "P_SPRING_RATE",
    "STATUS_INVALID_INPUT",
    "STATUS_NONFINITE",
    "STATUS_OK",
    "STATUS_SUBSTEP_LIMIT",
    "STATUS_UNSTABLE",
    "STEP_RATIO_TARGET",
    "SWITCHES_PER_STEP",
    "SWITCH_OVERSHOOT",
    "S_ESTIMATE_ERROR",
    "S_MAX_SUBSTEPS",
    "S_STABILITY_GUARD",
    "S_SUBSTEPS",
    "S_SWITCH_AWARE",
    "TRANSITION_BAND",
    "VALVE_CURVE_NAMES",
    "VALVE_CURVE_UNITS",
    "VALVE_OUTPUT_NAMES",
    "VALVE_OUTPUT_UNITS",
    "VALVE_PARAM_NAMES",
    "VALVE_PARAM_UNITS",
    "VALVE_STATUS_NAMES",
    "equivalent_mass",
    "excitation_at",
    "jump_speed",
    "prepare_case",
    "rk4_valve_step",
    "stability_substeps",
    "stability_substeps_batch",
    "valid_valve_parameters",
    "valve_acceleration",
    "valve_coefficients",
    "valve_energy",
    "valve_lift_batch",
    "valve_response",
    "valve_response_batch",
    "valve_settings",
    "valve_spectral_radius",
]
