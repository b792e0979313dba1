"""Data layout of the valve kernels: parameter, output, curve and settings rows (SPEC §4).

Parameters are rows indexed by the ``P_*`` constants (SI units, ``VALVE_PARAM_UNITS``),
outputs by the ``O_*`` constants, curves by the ``C_*`` constants, integer settings by the
``S_*`` constants (build them with :func:`valve_settings`), status codes ``STATUS_*``; the
running observations of a run are the ``ST_*`` rows of a flat array
(:mod:`engine_kernels.valvetrain.observations`), its seat phase one of the ``PHASE_*`` values.
The model itself is in :mod:`engine_kernels.valvetrain.model`.
"""

from __future__ import annotations

import numpy as np

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

STATUS_OK = 0
STATUS_SUBSTEP_LIMIT = 1
STATUS_UNSTABLE = 2
STATUS_NONFINITE = 3
STATUS_INVALID_INPUT = 4
VALVE_STATUS_NAMES = ("ok", "substep_limit", "unstable", "nonfinite", "invalid_input")


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


# Seat phase of a run: not yet lifted off the seat, open, closed again after opening, and off
# the seat again after that closure (bouncing).
PHASE_SEATED = np.float32(0.0)
PHASE_OPEN = np.float32(1.0)
PHASE_CLOSED = np.float32(2.0)
PHASE_BOUNCING = np.float32(3.0)

# Rows of the running observations of one case (engine_kernels.valvetrain.observations).
ST_MAX_LIFT = 0
ST_MAX_V = 1
ST_MIN_V = 2
ST_MAX_A = 3
ST_MIN_A = 4
ST_MAX_FORCE = 5
ST_JUMP_START = 6
ST_JUMP_STEPS = 7
ST_JUMP_GAP = 8
ST_PHASE = 9
ST_BOUNCE_HEIGHT = 10
ST_CONTACT = 11
ST_SEATED = 12
ST_TRANSITIONS = 13
ST_POWER_SUM = 14
ST_POWER_FIRST = 15
ST_SEAT_Y0 = 16
ST_SEAT_V0 = 17
ST_SEAT_A0 = 18
ST_CAPTURED = 19
ST_BOUNCES = 20
ST_ENERGY0 = 21
ST_EXCESS = 22
ST_WORK_MAX = 23
ST_REST_ENERGY = 24
ST_REST_RISE = 25
N_STATS = 26
