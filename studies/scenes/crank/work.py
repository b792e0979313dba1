"""Memory the crank scene needs at a study's settings: every stage works on the crank-angle
grid of the 720° cycle, ``720°/angle_step`` values per design point."""

from __future__ import annotations

import math
from typing import Any

from studies.scenes.base import WorkEstimate

GRID_ARRAYS = 24  # kinematic curves, pressure, forces, torques and harmonics per point
BYTES = 8.0


def work_estimate(
    settings: dict[str, Any], _responses: list[str], curves: list[str]
) -> WorkEstimate:
    """About ``GRID_ARRAYS`` float64 arrays over the cycle grid per design point [bytes]."""
    angles = 4.0 * math.pi / settings["angle_step"]  # angle_step [rad]; no rounding: may be huge
    return WorkEstimate(per_point=angles * BYTES * (GRID_ARRAYS + len(curves)))
