"""How the ``valve`` scene calls the valve kernels: parameter and settings rows, one batch
integration on one excitation table, and the checks of a design before it runs (physics §4)."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from engine_kernels import valvetrain as valve
from engine_kernels.valvetrain.dopri import integrate as valve_dopri
from engine_kernels.valvetrain.dopri.jump import dopri_jump_speed
from engine_kernels.valvetrain.spring_chain.jump import chain_jump_speed
from engine_kernels.valvetrain.valve import lane_batch as valve_lanes
from studies.scenes.checks import PointProblems
from studies.scenes.linkage.scene import step_deg
from studies.scenes.valve.parameters import LANE_PRECISION, dopri_tolerance

RPM = 30.0 / math.pi  # rpm per rad/s
N_OUT = len(valve.VALVE_OUTPUT_NAMES)
N_CURVES = len(valve.VALVE_CURVE_NAMES)
DOPRI_MAX_STEPS = valve_dopri.DEFAULT_MAX_STEPS

# parameter name -> column of the valve kernels' parameter rows
_PARAM_COLUMN = {
    "cam_speed": valve.P_SPEED,
    "equivalent_mass": valve.P_MASS,
    "drive_stiffness": valve.P_DRIVE_STIFFNESS,
    "drive_damping": valve.P_DRIVE_DAMPING,
    "spring_rate": valve.P_SPRING_RATE,
    "spring_preload": valve.P_PRELOAD,
    "seat_stiffness": valve.P_SEAT_STIFFNESS,
    "seat_damping": valve.P_SEAT_DAMPING,
    "external_damping": valve.P_EXTERNAL_DAMPING,
}


STABILITY_NAMES = tuple(name for name in _PARAM_COLUMN if name != "spring_preload")
"""The parameters the RK4 stability bound reads (valve_spectral_radius and the speed)."""
CHECK_BLOCK = 1 << 18  # design points per block of the stability check


def valve_rows(points: dict[str, np.ndarray], idx: np.ndarray | slice) -> np.ndarray:
    """Kernel parameter rows (``engine_kernels.valvetrain.P_*``, SI) of the design points idx
    (indices or a slice)."""
    first = points["cam_speed"][idx]
    rows = np.zeros((len(first), len(valve.VALVE_PARAM_NAMES)))
    for name, column in _PARAM_COLUMN.items():
        rows[:, column] = points[name][idx]
    return rows


def kernel_settings(
    settings: dict[str, Any], integrator: str, estimate: bool, substeps: int = 0
) -> np.ndarray:
    """The ``S_*`` integer settings row for an integrator name (``estimate``: the kernels'
    sub-step halving difference; ``substeps``: forced sub-steps per grid step, 0 = the
    guard's)."""
    return valve.valve_settings(
        max_substeps=int(settings["max_substeps"]),
        switch_aware=integrator == "rk4_switch_aware",
        estimate_error=estimate,
        substeps=substeps,
    )


def integrate(
    excitation: tuple[np.ndarray, float, float],
    rows: np.ndarray,
    integrator: str,
    flags: np.ndarray,
    curves: bool,
) -> tuple[np.ndarray, np.ndarray | None]:
    """Run one integrator over the rows on one excitation; outputs (n, O_*) and curves.

    Curves come from the one-case kernel in double precision (the lane kernels keep none);
    the outputs are still the integrator's own, so storing curves never changes them (for
    ``lanes_f32`` they stay single precision, for ``lanes`` the lane kernel's round-off).
    """
    table, table_step, start = excitation
    out = np.empty((rows.shape[0], N_OUT))
    trace = None
    if curves:
        trace = np.empty((rows.shape[0], N_CURVES, (table.shape[1] - 1) // 2 + 1))
        for j in range(rows.shape[0]):
            valve.valve_response(table, table_step, start, rows[j], flags, out[j], trace[j])
    if integrator in LANE_PRECISION:
        lanes = table.astype(LANE_PRECISION[integrator], copy=False)
        valve_lanes.valve_response_lanes(lanes, table_step, start, rows, flags, out)
    elif trace is None:
        valve.valve_response_batch(table, table_step, start, rows, flags, out)
    return out, trace


def integrate_dopri(
    excitation: tuple[np.ndarray, float, float],
    rows: np.ndarray,
    grid_deg: float,
    tolerance: float,
    curves: bool,
) -> tuple[np.ndarray, np.ndarray | None]:
    """Run ``dopri`` over the rows: outputs (n, O_*) and, with ``curves``, the curves
    (n, C_*, grid points) on the grid every ``grid_deg`` [deg] from the table's start.

    excitation : (table, spacing [rad], start [rad]) at any spacing (the steps are adaptive).
    tolerance  : lift tolerance per step [m].
    """
    table, table_step, start = excitation
    grid = math.radians(grid_deg)
    out = np.empty((rows.shape[0], N_OUT))
    if curves:
        trace = np.empty(
            (rows.shape[0], N_CURVES, valve_dopri.grid_points(table, table_step, grid))
        )
        for j in range(rows.shape[0]):
            valve_dopri.dopri_response(
                table,
                table_step,
                start,
                grid,
                rows[j],
                tolerance,
                0.0,
                DOPRI_MAX_STEPS,
                out[j],
                trace[j],
            )
        return out, trace
    none = np.empty((rows.shape[0], 0))
    valve_dopri.dopri_batch(
        table, table_step, start, grid, rows, tolerance, 0.0, DOPRI_MAX_STEPS, out, none
    )
    return out, None


def dopri_lifts(
    excitation: tuple[np.ndarray, float, float],
    rows: np.ndarray,
    grid_deg: float,
    tolerance: float,
    max_step_deg: float,
) -> tuple[np.ndarray, np.ndarray]:
    """``dopri`` outputs (n, O_*) and lift [m] at every grid point (see :func:`integrate_dopri`),
    its steps at most ``max_step_deg`` [deg] of cam (0: no limit)."""
    table, table_step, start = excitation
    grid = math.radians(grid_deg)
    out = np.empty((rows.shape[0], N_OUT))
    lifts = np.empty((rows.shape[0], valve_dopri.grid_points(table, table_step, grid)))
    longest = math.radians(max_step_deg)
    valve_dopri.dopri_batch(
        table, table_step, start, grid, rows, tolerance, longest, DOPRI_MAX_STEPS, out, lifts
    )
    return out, lifts


JUMP_SCAN_POINTS = 16
"""Speeds the jump-speed search scans before it bisects (:mod:`engine_kernels.valvetrain.jump_search`)."""


def dopri_jump_speeds(
    excitation: tuple[np.ndarray, float, float], rows: np.ndarray, settings: dict[str, Any]
) -> np.ndarray:
    """(jump speed [rad/s], ``JUMP_*`` code) of every row, each speed of the search one
    ``dopri`` run (see :func:`integrate_dopri`) at the study's tolerance on its angle grid."""
    table, table_step, start = excitation
    found = np.empty((rows.shape[0], 2))
    for j, row in enumerate(rows):
        found[j] = dopri_jump_speed(
            table,
            table_step,
            start,
            math.radians(step_deg(settings["angle_step"])),
            row,
            dopri_tolerance(settings["tolerance"]),
            settings["jump_speed_low"],
            settings["jump_speed_high"],
            JUMP_SCAN_POINTS,
            settings["jump_speed_tolerance"],
        )
    return found


def rk4_jump_speeds(
    excitation: tuple[np.ndarray, float, float],
    rows: np.ndarray,
    settings: dict[str, Any],
    chained: bool,
) -> np.ndarray:
    """(jump speed [rad/s], ``JUMP_*`` code) of every row (``chained``: multi-mass spring
    rows [V4], else single-mass rows [V2]), each speed of the search one RK4 run."""
    search = chain_jump_speed if chained else valve.jump_speed
    flags = kernel_settings(settings, settings["integrator"], False)
    found = np.empty((rows.shape[0], 2))
    for j, row in enumerate(rows):
        found[j] = search(
            *excitation,
            row,
            flags,
            settings["jump_speed_low"],
            settings["jump_speed_high"],
            JUMP_SCAN_POINTS,
            settings["jump_speed_tolerance"],
        )
    return found


def jump_setting_problems(settings: dict[str, Any]) -> list[str]:
    if settings["jump_speed_low"] < settings["jump_speed_high"]:
        return []
    return [
        (
            "settings jump_speed_low and jump_speed_high: the low end of the jump speed search "
            f"({settings['jump_speed_low'] * RPM:g} rpm) must be below the high end "
            f"({settings['jump_speed_high'] * RPM:g} rpm)"
        )
    ]


def stability_problems(
    points: dict[str, np.ndarray], settings: dict[str, Any], steps: np.ndarray
) -> list[str]:
    """Points whose RK4 step [rad] (one per point) needs more sub-steps than
    ``max_substeps`` (physics §4); checked in NumPy over blocks of points, so the
    parameter rows of a 10⁷-point design never sit in memory at once."""
    found = PointProblems()
    limit = int(settings["max_substeps"])
    runs = len(points["cam_speed"])
    for start in range(0, runs, CHECK_BLOCK):
        part = slice(start, min(start + CHECK_BLOCK, runs))
        rows = valve_rows(points, part)
        block_steps = np.ascontiguousarray(steps[part], dtype=float)
        needed, ratio = valve.stability_substeps_rows(rows, block_steps)
        for i in np.flatnonzero(needed > limit):
            row, step = rows[i], block_steps[i]
            found.add(
                start + int(i),
                f"angle_step = {step_deg(step):g} deg at cam_speed = "
                f"{row[valve.P_SPEED] * RPM:g} rpm with seat_stiffness = "
                f"{row[valve.P_SEAT_STIFFNESS] / 1e3:g} N/mm gives |h λ| = {ratio[i]:.3g}: "
                f"{needed[i]} RK4 sub-steps per step would be needed to keep |h λ| ≤ "
                f"{valve.STEP_RATIO_TARGET:g}, more than max_substeps = {limit} (use a smaller "
                "angle_step or a larger max_substeps)",
            )
    return found.messages()
