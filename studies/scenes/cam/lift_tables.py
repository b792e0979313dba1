"""Measured lift tables: read a CSV of (cam angle, lift), smooth with a spline, differentiate.

Raw measured tables are not smooth: differentiating them twice without smoothing gives huge
spurious accelerations (the motorcycle thesis saw ±11 600 m/s² from cusps). The smoothing
strength is therefore a study setting (``table_smoothing``: the RMS lift residual the spline
may leave) and its effect is measurable (see tests/studies/test_lift_tables.py).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from studies.common.bounded_files import TABLE_FILE_BYTES, read_bounded_text
from studies.common.errors import StudyError

SPLINE_DEGREE = 5  # quintic: lift, velocity, acceleration and jerk all come from the spline
MIN_POINTS = SPLINE_DEGREE + 2


def read_lift_table(path: str | Path) -> tuple[np.ndarray, np.ndarray]:
    """Read ``cam angle [deg], lift [mm]`` rows (header line optional) → (angle, lift).

    Angles must increase strictly, with the nose near 0 deg (the scene's convention).
    """
    path = Path(path)
    if not path.is_file():
        raise StudyError(f"lift_table = {str(path)!r}: no such file")
    rows = read_bounded_text(path, "lift_table", TABLE_FILE_BYTES).splitlines()
    try:
        data = np.genfromtxt(rows, delimiter=",", comments="#", dtype=float)
    except ValueError as exc:
        raise StudyError(f"lift_table {path}: not a two-column numeric CSV ({exc})") from None
    data = np.atleast_2d(data)
    if data.shape[0] > 0 and np.isnan(data[0]).all():
        data = data[1:]  # a header line
    if data.ndim != 2 or data.shape[1] != 2 or not np.isfinite(data).all():
        raise StudyError(
            f"lift_table {path}: expected two numeric columns "
            "'cam angle [deg], lift [mm]' on every row"
        )
    angle, lift = data[:, 0], data[:, 1]
    if len(angle) < MIN_POINTS:
        raise StudyError(f"lift_table {path}: {len(angle)} rows, need at least {MIN_POINTS}")
    if np.any(np.diff(angle) <= 0):
        raise StudyError(f"lift_table {path}: cam angles must increase strictly")
    return angle, lift


def table_kinematics(
    angle: np.ndarray, lift: np.ndarray, smoothing: float, theta: np.ndarray
) -> np.ndarray:
    """Lift and its derivatives on ``theta`` from a smoothing spline through a table.

    angle     : table cam angles [rad], increasing.
    lift      : table lifts [m].
    smoothing : RMS lift residual the spline may leave [m]; 0 interpolates every point.
    theta     : evaluation grid [rad]; outside the table the tappet is on the base circle.
    Returns curves[4, m]: h [m], h' [m/rad], h'' [m/rad²], h''' [m/rad³].
    """
    from scipy.interpolate import UnivariateSpline  # noqa: PLC0415  (slow import, rarely used)

    spline = UnivariateSpline(angle, lift, k=SPLINE_DEGREE, s=len(angle) * smoothing**2)
    inside = (theta >= angle[0]) & (theta <= angle[-1])
    curves = np.zeros((4, theta.size))
    for order in range(4):
        curves[order, inside] = spline(theta[inside], nu=order)
    return curves
