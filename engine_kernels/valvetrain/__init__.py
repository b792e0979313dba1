"""Valve-train kernels (physics §3, §4), one folder per model family:

* :mod:`~engine_kernels.valvetrain.rocker` — rocker kinematics [R1]–[R6], tappet law, and
  :mod:`~engine_kernels.valvetrain.rocker_batches` — its drivers for many chains at once;
* :mod:`~engine_kernels.valvetrain.rk4` — RK4 stability and Hermite interpolation, and
  :mod:`~engine_kernels.valvetrain.jump_search` — the jump-speed search, both shared by the
  two models;
* :mod:`~engine_kernels.valvetrain.valve` — the single-mass valve [V1], [V2]: rows and case
  record (``layout``), coefficients, forces and excitation (``model``), one RK4 step
  (``step``), input checks and stable sub-steps (``guard``), ``observations`` and the
  ``energy_balance``, switch-aware RK4 (``modes``, ``switching``, ``located``), one case at a
  time (``one_case``), SIMD lanes (``lanes``, ``lane_batch``) and the jump-speed search
  (``jump``);
* :mod:`~engine_kernels.valvetrain.spring_chain` — the multi-mass spring [V4]: ``model``,
  rows (``layout``), input checks, sub-steps and status (``guard``), one case at a time and
  the batch entry (``one_case``), SIMD lanes (``lanes``, ``lane_layout``,
  ``lane_observations``, ``lane_batch``) and its jump-speed search (``jump``);
* :mod:`~engine_kernels.valvetrain.dopri` — adaptive Dormand–Prince 5(4) with switches
  located on its dense output, one case at a time (``integrate``, ``step``, ``observe``;
  imported as its own package).

This package re-exports the public API of the one-case valve kernels and their data layout,
so ``from engine_kernels import valvetrain`` is the one import a caller of them needs.
"""

from __future__ import annotations

from engine_kernels.valvetrain.jump_search import (
    JUMP_AT_LOWER_BOUND,
    JUMP_FOUND,
    JUMP_NONE_IN_RANGE,
    JUMP_RUN_FAILED,
    JUMP_STATUS_NAMES,
)
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
    stability_substeps_rows,
    valid_valve_parameters,
)
from engine_kernels.valvetrain.valve.jump import jump_speed
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
    "stability_substeps_rows",
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
