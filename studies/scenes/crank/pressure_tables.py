"""Measured cylinder-pressure tables for the ``crank`` scene: read a CSV, resample on the grid.

A table is rows of ``crank angle [deg], pressure [MPa]`` (a header line and ``#`` comments are
allowed) over one four-stroke cycle, with **firing TDC at 0°** as measured traces are usually
written (−360…360° or any other 720° window; angles are read modulo 720°). The scene's grid has
gas-exchange TDC at 0° and firing TDC at 360° (:mod:`engine_kernels.crank.kinematics`), so the table is
shifted by 360° and interpolated linearly and periodically onto it.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from studies.common.bounded_files import TABLE_FILE_BYTES, read_bounded_text
from studies.common.errors import StudyError

CYCLE_DEG = 720.0
FIRING_TDC_DEG = 360.0  # firing TDC on the scene's cycle grid
MIN_ROWS = 4
MPA = 1e6


def read_pressure_table(path: str | Path) -> tuple[np.ndarray, np.ndarray]:
    """Read a pressure table → (crank angle [deg] from firing TDC, pressure [MPa]).

    Raises ValueError with a sentence naming the file and what is wrong with it.
    """
    path = Path(path)
    name = f"pressure_table = {str(path)!r}"
    if not str(path) or not path.is_file():
        raise StudyError(f"{name}: no such file (a CSV of crank angle [deg], pressure [MPa])")
    rows = read_bounded_text(path, "pressure_table", TABLE_FILE_BYTES).splitlines()
    try:
        data = np.genfromtxt(rows, delimiter=",", comments="#", dtype=float)
    except ValueError as exc:
        raise StudyError(f"{name}: not a two-column numeric CSV ({exc})") from None
    data = np.atleast_2d(data)
    if data.size:
        data = data[~np.isnan(data).all(axis=1)]
    if data.ndim != 2 or data.shape[1] != 2 or not np.isfinite(data).all():
        raise StudyError(
            f"{name}: expected two numeric columns 'crank angle [deg], pressure [MPa]' on every row"
        )
    angle, pressure = data[:, 0], data[:, 1]
    if len(angle) < MIN_ROWS:
        raise StudyError(f"{name}: {len(angle)} rows, need at least {MIN_ROWS}")
    if np.any(np.diff(angle) <= 0):
        raise StudyError(f"{name}: crank angles must increase strictly")
    span = angle[-1] - angle[0]
    if span > CYCLE_DEG:
        raise StudyError(f"{name}: covers {span:g}° of crank angle, more than one cycle (720°)")
    gap = CYCLE_DEG - span
    if gap > np.diff(angle).max() * (1.0 + 1e-9):
        raise StudyError(
            f"{name}: covers only {span:g}° of crank angle; give the whole "
            "720° cycle (the gap between the last and first row is wider than "
            "the table's own spacing)"
        )
    if np.any(pressure < 0):
        raise StudyError(f"{name}: pressures must be ≥ 0 MPa (absolute pressure)")
    return angle, pressure


def resample_pressure(angle: np.ndarray, pressure: np.ndarray, n_angles: int) -> np.ndarray:
    """Pressure [Pa] on the scene's cycle grid α_j = 720°·j/m (firing TDC at 360°).

    angle   : table crank angles [deg] from firing TDC, increasing, spanning ≤ 720°.
    pressure: table pressures [MPa].
    n_angles: grid points m over the cycle.
    """
    if np.isclose(angle[-1] - angle[0], CYCLE_DEG):
        angle, pressure = angle[:-1], pressure[:-1]  # last row repeats the first
    grid = CYCLE_DEG * np.arange(n_angles) / n_angles
    table_angle = (angle + FIRING_TDC_DEG) % CYCLE_DEG
    return np.interp(grid, table_angle, pressure, period=CYCLE_DEG) * MPA
