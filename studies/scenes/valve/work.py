"""Memory the valve scene needs at a study's settings: the excitation table of the chain
(every half ``angle_step``, or under a ``tolerance`` the ``dopri`` table, whose spacing shrinks
with the square root of the tolerance: :func:`~studies.scenes.valve.parameters.dopri_table_deg`)
and the per-point grids and curves at ``angle_step``."""

from __future__ import annotations

import math
from typing import Any

from studies.scenes.base import WorkEstimate
from studies.scenes.valve.parameters import dopri_table_deg

TURN_DEG = 360.0
TABLE_ARRAYS = 8  # tables of the run, its companion and the ladder (1e-12 mm: > 22 GB, killed)
GRID_ARRAYS = 8  # per point on the angle_step grid: lift, velocity, force, error bars
BYTES = 8.0


def work_estimate(
    settings: dict[str, Any], _responses: list[str], curves: list[str]
) -> WorkEstimate:
    """The excitation tables once per chunk, the angle grid per design point [bytes]
    (nothing known for the scenes built on this one that have no ``angle_step``)."""
    if "angle_step" not in settings:
        return WorkEstimate()
    step = math.degrees(settings["angle_step"])
    table = step / 2.0
    if settings.get("tolerance", 0.0) > 0.0:
        table = min(table, dopri_table_deg(settings["tolerance"]))
    revolutions = max(1.0, float(settings.get("revolutions", 1)))
    fixed = revolutions * TURN_DEG / table * BYTES * TABLE_ARRAYS
    per_point = revolutions * TURN_DEG / step * BYTES * (GRID_ARRAYS + len(curves))
    return WorkEstimate(fixed=fixed, per_point=per_point)
