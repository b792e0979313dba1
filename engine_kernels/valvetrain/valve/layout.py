"""Data layout of the valve kernels: parameter, output, curve and settings rows (physics §4).

Parameters are rows indexed by the ``P_*`` constants (SI units, ``VALVE_PARAM_UNITS``),
outputs by the ``O_*`` constants, curves by the ``C_*`` constants, integer settings by the
``S_*`` constants (build them with :func:`valve_settings`), status codes ``STATUS_*``. What
the kernels carry for a case (coefficients ``K_*``, time steps, running observations ``ST_*``)
is one record of ``N_RECORD`` rows of a flat array; a run's seat phase is one of the
``PHASE_*`` values.
The model itself is in :mod:`engine_kernels.valvetrain.valve.model`.
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
O_ERROR_ESTIMATE = 16  # max |y(n sub-steps) − y(2n)| over the grid [m] (S_ESTIMATE_ERROR)
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
S_SUBSTEPS = 4
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
    substeps=0,
):
    """Integer settings array for the valve kernels (plain Python, builds the ``S_*`` row).

    max_substeps    : int   Hard cap on RK4 sub-steps per grid step (stability guard).
    switch_aware    : bool  Locate contact and seat switches inside steps (one-case kernel).
    estimate_error  : bool  Step-halving difference in ``O_ERROR_ESTIMATE``: the largest lift
                            difference over the grid from a second run with twice the
                            sub-steps (never a longer step, so never past the RK4 bound).
    stability_guard : bool  False integrates with one sub-step whatever the bound says: only
                            to demonstrate the physics-based instability detection.
    substeps        : int   Sub-steps per grid step to use when more than the guard needs
                            (0: the guard's count). Halving the angle step at a fixed count
                            halves every sub-step, also where a stiff seat forces them (the
                            guard alone would halve their number instead, and the error of a
                            seat contact would not converge).
    """
    return np.array(
        [max_substeps, int(switch_aware), int(estimate_error), int(stability_guard), substeps],
        dtype=np.int64,
    )


# Seat phase of a run: not yet lifted off the seat, open, closed again after opening, and off
# the seat again after that closure (bouncing).
PHASE_SEATED = np.float32(0.0)
PHASE_OPEN = np.float32(1.0)
PHASE_CLOSED = np.float32(2.0)
PHASE_BOUNCING = np.float32(3.0)

# The record of a case: its coefficients of [V2] per unit mass (``K_*``, built from a ``P_*``
# row by engine_kernels.valvetrain.valve.model.valve_coefficients), its time steps (``K_TAU`` ...,
# engine_kernels.valvetrain.valve.step.valve_time_steps) and its running observations (``ST_*``,
# engine_kernels.valvetrain.valve.observations). Row r of the case sits at ``at + r*w`` of a flat
# array: the one-case kernel has w = 1, the lane kernel w = LANES and ``at`` the lane, so both
# read every coefficient through this one layout. The arithmetic of a case reads its K_* rows
# once, as the tuple of engine_kernels.valvetrain.valve.model.case_coefficients (element r = row r,
# so c[K_X] is row K_X): the K_* rows stay first and contiguous, up to K_TIME_STEP.
K_STIFFNESS = 0  # k' = k/M [1/s²]
K_DAMPING = 1  # b' = b/M [1/s]
K_SPRING_RATE = 2  # ks' = ks/M [1/s²]
K_PRELOAD = 3  # Ps0' = Ps0/M [m/s²]
K_SEAT_STIFFNESS = 4  # kz' = kz/M [1/s²]
K_SEAT_DAMPING = 5  # bz' = bz/M [1/s]
K_EXTERNAL_DAMPING = 6  # γ' = γ/M [1/s]
K_SEAT_DEPTH = 7  # δ0 = Ps0/kz [m]
K_SPEED = 8  # ω [rad/s]
K_DAMPING_SPEED = 9  # b'ω [1/(s rad)]
K_BAND = 10  # dead band of the mode changes per unit mass [N/kg]
K_MASS = 11  # M [kg]
K_TAU = 12  # RK4 (sub-)step h [s]
K_HALF_TAU = 13  # h/2 [s]
K_SIXTH_TAU = 14  # h/6 [s]
K_TIME_STEP = 15  # grid time step Δθ/ω [s]
ST_MAX_LIFT = 16
ST_MAX_V = 17
ST_MIN_V = 18
ST_MAX_A = 19
ST_MIN_A = 20
ST_MAX_FORCE = 21
ST_JUMP_START = 22
ST_JUMP_STEPS = 23
ST_JUMP_GAP = 24
ST_PHASE = 25
ST_BOUNCE_HEIGHT = 26
ST_CONTACT = 27
ST_SEATED = 28
ST_TRANSITIONS = 29
ST_POWER_SUM = 30
ST_POWER_FIRST = 31
ST_SEAT_Y0 = 32
ST_SEAT_V0 = 33
ST_SEAT_A0 = 34
ST_CAPTURED = 35
ST_BOUNCES = 36
ST_ENERGY0 = 37
ST_EXCESS = 38
ST_WORK_MAX = 39
ST_REST_ENERGY = 40
ST_REST_RISE = 41
ST_PREV_ANGLE = 42  # the previous observed point (grid point, or a located switch of dopri)
ST_PREV_LIFT = 43
ST_PREV_VELOCITY = 44
ST_PREV_DRIVE = 45
ST_INVERSE_SPEED = 46  # 1/ω [s/rad]
ST_SEAT_J0 = 47  # jerk at the point before the first closure [m/s³]
N_RECORD = 48
