"""The cam scene's benchmark: kinematics only against all three stages on the same design
points (what "model only what a scene requires" saves). Reached through
:meth:`studies.scenes.base.Scene.benchmarks`; the engine lends the planner and the evaluator."""

from __future__ import annotations

import json
from functools import partial
from typing import Any

import numpy as np

from studies.common.timing import best_time
from studies.scenes.base import BenchKit

CAM_STUDY = """
name = "bench_cam"
scene = "cam"
responses = {responses}
design = "full_factorial"
[settings]
angle_step = {step}
[factors.seg2_width]
levels = {widths}
[factors.seg2_amplitude]
levels = [10.0, 12.0, 14.0, 16.0]
"""


def bench_cam(kit: BenchKit, cases: int, step: float, repeat: int) -> dict[str, Any]:
    """Cam cases/s: kinematics only vs all three stages (what 'model only what is needed' saves)."""
    widths = np.linspace(6.0, 13.0, max(cases // 4, 1)).round(6).tolist()
    figures: dict[str, Any] = {}
    for label, responses in [
        ("kinematics_only", ["max_jerk"]),
        ("all_stages", ["max_jerk", "max_contact_stress"]),
    ]:
        plan = kit.plan(CAM_STUDY.format(responses=json.dumps(responses), step=step, widths=widths))
        everything = slice(0, plan.runs)
        seconds = best_time(partial(kit.evaluate, plan, everything), repeat)
        figures[label] = {
            "cases": plan.runs,
            "seconds": seconds,
            "cases_per_s": plan.runs / seconds,
        }
    figures["all_stages_over_kinematics_time"] = (
        figures["all_stages"]["seconds"] / figures["kinematics_only"]["seconds"]
    )
    return figures
