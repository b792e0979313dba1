"""A full factorial's report says a better value may lie beyond the grid only in the factors
whose edge level changes the best value, not in those the response does not depend on."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from studies.define.plan import plan_text
from studies.pipeline import run_plan
from study_text import scene_study

CAM = scene_study(
    "cam",
    parameters='law = "harmonic"',
    responses='["min_radius_of_curvature"]',
    factors=(
        "[factors.cam_speed]\nlevels = [2216.0, 2381.0]\n"
        "[factors.base_radius]\nlevels = [14.03, 28.53]"
    ),
)


def test_the_edge_note_leaves_out_a_factor_the_best_value_does_not_change_with(
    tmp_path: Path,
) -> None:
    """Before, the note named every factor whose optimum level is first or last: cam_speed too
    (the audit's cam_ff486 named six factors, three of which the radius does not depend on)."""
    result = run_plan(plan_text(CAM), tmp_path, progress=False)
    ds = result.dataset
    y = ds["min_radius_of_curvature"].values
    radius = ds["base_radius"].values
    # The premise, from the runs: the radius does not change with cam speed, it does with the
    # base radius, and every level is an edge of a two-level grid.
    for r in np.unique(radius):
        assert np.unique(y[radius == r]).size == 1
    assert np.unique(y).size == 2
    text = (result.folder / "report.md").read_text(encoding="utf-8")
    (note,) = [line for line in text.splitlines() if "edge of the grid in" in line]
    assert "base_radius" in note
    assert "cam_speed" not in note
