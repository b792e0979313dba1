"""Benchmarks: throughput figures printed and written as JSON under ``outputs/bench/``.

Timing claims live here, never in test assertions. Alternatives are measured in the same run
and reported as ratios, because the machines are shared and absolute figures are noisy.
Each benchmark warms up (compiles) first and reports the best of ``repeat`` timed runs.
"""

from __future__ import annotations

import json
import time
from collections.abc import Callable
from functools import partial
from pathlib import Path
from typing import Any

import numpy as np

from studies import provenance, tracking
from studies.plan import plan_text
from studies.runner import evaluate_chunk

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


def best_time(fn: Callable[[], object], repeat: int) -> float:
    fn()
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times)


def bench_cam(cases: int, step: float, repeat: int) -> dict[str, Any]:
    """Cam cases/s: kinematics only vs all three stages (what 'model only what is needed' saves)."""
    widths = np.linspace(6.0, 13.0, max(cases // 4, 1)).round(6).tolist()
    figures: dict[str, Any] = {}
    for label, responses in [
        ("kinematics_only", ["max_jerk"]),
        ("all_stages", ["max_jerk", "max_contact_stress"]),
    ]:
        plan = plan_text(
            CAM_STUDY.format(responses=json.dumps(responses), step=step, widths=widths)
        )
        everything = slice(0, plan.runs)
        seconds = best_time(partial(evaluate_chunk, plan, everything), repeat)
        figures[label] = {
            "cases": plan.runs,
            "seconds": seconds,
            "cases_per_s": plan.runs / seconds,
        }
    figures["all_stages_over_kinematics_time"] = (
        figures["all_stages"]["seconds"] / figures["kinematics_only"]["seconds"]
    )
    return figures


BENCHMARKS: dict[str, Callable[[int, float, int], dict[str, Any]]] = {"cam": bench_cam}


def run_benchmark(name: str, cases: int, step: float, repeat: int, outputs: Path) -> Path:
    """Run one benchmark, print its figures, write them as JSON; return the JSON path."""
    if name not in BENCHMARKS:
        raise KeyError(f"unknown benchmark {name!r}; known: {', '.join(BENCHMARKS)}, all")
    figures = BENCHMARKS[name](cases, step, repeat)
    commit, dirty = provenance.git_state()
    record = {
        "benchmark": name,
        "cases": cases,
        "step_deg": step,
        "repeat": repeat,
        "created": tracking.now(),
        "git_commit": commit,
        "git_dirty": dirty,
        "versions": provenance.versions(),
        "host": provenance.host(),
        "figures": figures,
    }
    folder = outputs / "bench"
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / f"{name}-{tracking.new_run_id(name)}.json"
    path.write_text(json.dumps(record, indent=2) + "\n", encoding="utf-8")
    return path
