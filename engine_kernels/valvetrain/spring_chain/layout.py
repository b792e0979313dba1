"""Data layout of the multi-mass valve-spring kernels [V4]: parameter, output and curve rows.

Parameters are rows indexed by the ``SC_*`` constants (SI units, ``CHAIN_PARAM_UNITS``),
outputs by the ``CO_*`` constants, curves by the ``CC_*`` constants. Settings and status codes
are the valve kernels' own (:func:`engine_kernels.valvetrain.valve.layout.valve_settings`,
``STATUS_*``), so both rungs of the model ladder are driven and read the same way.

Unlike the lumped row (``P_MASS`` = the [V1] equivalent mass with m_s/3 on the valve), the
chain row keeps the valve-side mass without any spring share (``SC_VALVE_MASS`` = valve group
+ I_rocker/l_v²) and the spring's own mass apart (``SC_SPRING_MASS``).
"""

from __future__ import annotations

from engine_kernels.valvetrain.valve.layout import (
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
    VALVE_PARAM_NAMES,
    VALVE_PARAM_UNITS,
)

# The lumped row's entries first, in its order (the mass without the spring's share) ...
SC_SPEED = P_SPEED
SC_VALVE_MASS = P_MASS
SC_DRIVE_STIFFNESS = P_DRIVE_STIFFNESS
SC_DRIVE_DAMPING = P_DRIVE_DAMPING
SC_SPRING_RATE = P_SPRING_RATE
SC_PRELOAD = P_PRELOAD
SC_SEAT_STIFFNESS = P_SEAT_STIFFNESS
SC_SEAT_DAMPING = P_SEAT_DAMPING
SC_EXTERNAL_DAMPING = P_EXTERNAL_DAMPING
SC_INITIAL_LIFT = P_INITIAL_LIFT
SC_INITIAL_VELOCITY = P_INITIAL_VELOCITY
# ... then the spring's own.
SC_SPRING_MASS = len(VALVE_PARAM_NAMES)
SC_SPRING_MASSES = SC_SPRING_MASS + 1
SC_SPRING_DAMPING_RATIO = SC_SPRING_MASS + 2
SC_CLASH_TRAVEL = SC_SPRING_MASS + 3
SC_CLASH_STIFFNESS = SC_SPRING_MASS + 4
SC_CLASH_DAMPING = SC_SPRING_MASS + 5
_SPRING = (
    ("spring_mass", "kg"),
    ("spring_masses", "1"),
    ("spring_damping_ratio", "1"),
    ("clash_travel", "m"),
    ("clash_stiffness", "N/m"),
    ("clash_damping", "N s/m"),
)
CHAIN_PARAM_NAMES = (
    *(("valve_mass" if k == P_MASS else n) for k, n in enumerate(VALVE_PARAM_NAMES)),
    *(n for n, _ in _SPRING),
)
CHAIN_PARAM_UNITS = (*VALVE_PARAM_UNITS, *(u for _, u in _SPRING))

# Valid numbers of coil masses ([V4], issue 12: 1–24).
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
