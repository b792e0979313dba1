"""Memory the cam scene needs at a study's settings: the kinematic, geometry and load stages
work on the cam-angle grid −180…180° at ``angle_step``."""

from __future__ import annotations

import math
from typing import Any

from studies.scenes.base import WorkEstimate

GRID_ARRAYS = 12  # lift and its derivatives, curvature, lubrication, film, force, stress
BYTES = 8.0


def work_estimate(
    settings: dict[str, Any], _responses: list[str], curves: list[str]
) -> WorkEstimate:
    """About ``GRID_ARRAYS`` float64 arrays over the angle grid per design point [bytes]."""
    angles = 2.0 * math.pi / settings["angle_step"] + 1.0  # angle_step [rad]
    return WorkEstimate(per_point=angles * BYTES * (GRID_ARRAYS + len(curves)))
