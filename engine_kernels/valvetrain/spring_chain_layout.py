"""Data layout of the multi-mass valve-spring kernels [V4]: parameter, output and curve rows.

Parameters are rows indexed by the ``SC_*`` constants (SI units, ``CHAIN_PARAM_UNITS``),
outputs by the ``CO_*`` constants, curves by the ``CC_*`` constants. Settings and status codes
are the valve kernels' own (:func:`engine_kernels.valvetrain.layout.valve_settings`,
``STATUS_*``), so both rungs of the model ladder are driven and read the same way.

Unlike the lumped row (``P_MASS`` = the [V1] equivalent mass with m_s/3 on the valve), the
chain row keeps the valve-side mass without any spring share (``SC_VALVE_MASS`` = valve group
+ I_rocker/l_v²) and the spring's own mass apart (``SC_SPRING_MASS``).
"""

from __future__ import annotations

SC_SPEED = 0
SC_VALVE_MASS = 1
SC_DRIVE_STIFFNESS = 2
SC_DRIVE_DAMPING = 3
SC_SPRING_RATE = 4
SC_PRELOAD = 5
SC_SEAT_STIFFNESS = 6
SC_SEAT_DAMPING = 7
SC_EXTERNAL_DAMPING = 8
SC_INITIAL_LIFT = 9
SC_INITIAL_VELOCITY = 10
SC_SPRING_MASS = 11
SC_SPRING_MASSES = 12
SC_SPRING_DAMPING_RATIO = 13
SC_CLASH_TRAVEL = 14
SC_CLASH_STIFFNESS = 15
SC_CLASH_DAMPING = 16
CHAIN_PARAM_NAMES = (
    "camshaft_speed",
    "valve_mass",
    "drive_stiffness",
    "drive_damping",
    "spring_rate",
    "spring_preload",
    "seat_stiffness",
    "seat_damping",
    "external_damping",
    "initial_lift",
    "initial_velocity",
    "spring_mass",
    "spring_masses",
    "spring_damping_ratio",
    "clash_travel",
    "clash_stiffness",
    "clash_damping",
)
CHAIN_PARAM_UNITS = (
    "rad/s",
    "kg",
    "N/m",
    "N s/m",
    "N/m",
    "N",
    "N/m",
    "N s/m",
    "N s/m",
    "m",
    "m/s",
    "kg",
    "1",
    "1",
    "m",
    "N/m",
    "N s/m",
)

# Valid numbers of coil masses (SPEC [V4], issue 12: 1–24).
MIN_SPRING_MASSES = 1
MAX_SPRING_MASSES = 24

CO_MAX_LIFT = 0
CO_MAX_VELOCITY = 1
CO_MIN_VELOCITY = 2
CO_JUMP_START = 3
CO_JUMP_DURATION = 4
CO_JUMP_GAP = 5
CO_BOUNCE_COUNT = 6
CO_BOUNCE_HEIGHT = 7
CO_SEATING_VELOCITY = 8
CO_MAX_CONTACT_FORCE = 9
CO_MIN_FORCE_MARGIN = 10
CO_MIN_RETAINER_RATIO = 11
CO_MAX_RETAINER_DEVIATION = 12
CO_SURGE_AMPLITUDE = 13
CO_CLASH_COUNT = 14
CO_ENERGY_EXCESS = 15
CO_SUBSTEPS = 16
CO_STEP_RATIO = 17
CO_STATUS = 18
CHAIN_OUTPUT_NAMES = (
    "max_lift",
    "max_opening_velocity",
    "max_closing_velocity",
    "jump_start",
    "jump_duration",
    "jump_max_gap",
    "bounce_count",
    "bounce_height",
    "seating_velocity",
    "max_contact_force",
    "min_force_margin",
    "min_retainer_force_ratio",
    "max_retainer_force_deviation",
    "surge_amplitude",
    "coil_clash_count",
    "energy_excess",
    "substeps",
    "step_ratio",
    "status",
)
CHAIN_OUTPUT_UNITS = (
    "m",
    "m/s",
    "m/s",
    "rad",
    "rad",
    "m",
    "1",
    "m",
    "m/s",
    "N",
    "N",
    "1",
    "N",
    "m",
    "1",
    "1",
    "1",
    "1",
    "1",
)

CC_LIFT = 0
CC_VELOCITY = 1
CC_DRIVE_FORCE = 2
CC_RETAINER_FORCE = 3
CC_SURGE = 4
CC_ENERGY = 5
CHAIN_CURVE_NAMES = (
    "lift",
    "velocity",
    "drive_force",
    "retainer_force",
    "surge",
    "energy",
)
CHAIN_CURVE_UNITS = ("m", "m/s", "N", "N", "m", "J")
