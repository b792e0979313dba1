"""Which kernel output answers each response and curve of the valve scene, and the factor
from SI to the unit the scene declares for it (physics §4)."""

from __future__ import annotations

import math

from engine_kernels import valvetrain as valve

MM, DEG = 1e3, math.degrees(1.0)  # m -> mm, rad -> degree

# error bar response -> factor from SI to the response's units
BAR_SCALE = {
    "jump_start_error": DEG,
    "seating_velocity_error": 1.0,
    "bounce_height_error": MM,
    "max_lift_error": MM,
    "integration_error": MM,
    "excitation_error": MM,
}

# response -> (output column, factor from SI to the response's units)
OUTPUT_COLUMNS: dict[str, tuple[int, float]] = {
    "max_lift": (valve.O_MAX_LIFT, MM),
    "max_opening_velocity": (valve.O_MAX_VELOCITY, 1.0),
    "max_closing_velocity": (valve.O_MIN_VELOCITY, 1.0),
    "max_acceleration": (valve.O_MAX_ACCELERATION, 1.0),
    "min_acceleration": (valve.O_MIN_ACCELERATION, 1.0),
    "jump_start": (valve.O_JUMP_START, DEG),
    "jump_duration": (valve.O_JUMP_DURATION, DEG),
    "jump_max_gap": (valve.O_JUMP_GAP, MM),
    "bounce_count": (valve.O_BOUNCE_COUNT, 1.0),
    "bounce_height": (valve.O_BOUNCE_HEIGHT, MM),
    "seating_velocity": (valve.O_SEATING_VELOCITY, 1.0),
    "max_contact_force": (valve.O_MAX_CONTACT_FORCE, 1.0),
    "substeps": (valve.O_SUBSTEPS, 1.0),
    "step_ratio": (valve.O_STEP_RATIO, 1.0),
    "mode_transitions": (valve.O_TRANSITIONS, 1.0),
    "status": (valve.O_STATUS, 1.0),
}
CURVE_ROWS = {
    "actual_lift": (valve.C_LIFT, MM),
    "actual_velocity": (valve.C_VELOCITY, 1.0),
    "actual_acceleration": (valve.C_ACCELERATION, 1.0),
    "drive_force": (valve.C_DRIVE_FORCE, 1.0),
    "seat_force": (valve.C_SEAT_FORCE, 1.0),
}
