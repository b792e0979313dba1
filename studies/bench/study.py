"""Benchmark of a whole study, end to end: the command line in its own process, timed by the
wall clock, with its peak resident memory, beside the compute time the run records.

The study is the 125 cc OHC valve train of ``ohc125_dynamics`` over a full factorial of camshaft
speed × spring preload × spring rate × drive stiffness with that study's nine responses:
10⁶ points as 40 × 25 × 25 × 40 levels, 10⁷ as 100 × 40 × 50 × 50, other sizes as four
factors of about equal level counts. What the kernels cost is ``compute`` (``run.json``
``run_s``); everything else — imports, planning, writing results.nc, the analysis, the figures —
is the rest of ``end_to_end``.
"""

from __future__ import annotations

import json
import math
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import netCDF4
import numpy as np

from studies.define.definition import find_study

SHAPES = {10**6: (40, 25, 25, 40), 10**7: (100, 40, 50, 50)}
RANGES = {  # factor: (low, high, units), the ranges of ohc125_dynamics
    "cam_speed": (3000.0, 6000.0, "rpm"),
    "spring_preload": (170.0, 240.0, "N"),
    "spring_rate": (20.0, 40.0, "N/mm"),
    "drive_stiffness": (8000.0, 15000.0, "N/mm"),
}


def level_counts(points: int) -> tuple[int, ...]:
    """Level counts of the four factors for about ``points`` design points."""
    if points in SHAPES:
        return SHAPES[points]
    side = max(2, round(points**0.25))
    return (side,) * 4


def study_text(points: int) -> str:
    """``ohc125_dynamics`` with its four factors at ``level_counts(points)`` levels each."""
    text = find_study("ohc125_dynamics").read_text(encoding="utf-8")
    text = text[: text.index("[factors.")].replace(
        'name = "ohc125_dynamics"', 'name = "bench_study"'
    )
    for (name, (low, high, units)), n in zip(RANGES.items(), level_counts(points), strict=True):
        levels = np.linspace(low, high, n).round(6).tolist()
        text += f'\n[factors.{name}]\nlevels = {levels}\nunits = "{units}"\n'
    return text


def run_command(args: list[str]) -> tuple[float, float]:
    """Run a command; its wall time [s] and peak resident memory [MB] (from wait4)."""
    t0 = time.perf_counter()
    process = subprocess.Popen(args, stdout=subprocess.DEVNULL)
    _, status, usage = os.wait4(process.pid, 0)
    wall = time.perf_counter() - t0
    process.returncode = os.waitstatus_to_exitcode(status)  # reaped here, not by Popen
    if process.returncode != 0:
        msg = f"{' '.join(args)} failed with exit code {process.returncode}"
        raise RuntimeError(msg)
    return wall, usage.ru_maxrss / 1024.0  # kB on Linux


def bench_study(points: int, step: float, repeat: int) -> dict[str, Any]:  # noqa: ARG001
    """Run the valve study of about ``points`` design points once through the command line
    (``repeat`` is not used: one run of a large study is the measurement)."""
    with tempfile.TemporaryDirectory(prefix="bench_study_") as tmp:
        folder = Path(tmp)
        study = folder / "bench_study.toml"
        study.write_text(study_text(points).replace("angle_step = 0.5", f"angle_step = {step}"))
        outputs = folder / "outputs"
        command = [sys.executable, "-m", "studies", "run", str(study), "--no-progress"]
        wall, peak = run_command([*command, "--outputs", str(outputs)])
        (record,) = outputs.glob("bench_study/*/run.json")
        timings = json.loads(record.read_text(encoding="utf-8"))["timings"]
        (results,) = outputs.glob("bench_study/*/results.nc")
        size = results.stat().st_size
        with netCDF4.Dataset(results) as stored:
            stored_runs = len(stored.dimensions["run"])
        shutil.rmtree(outputs, ignore_errors=True)
    runs = int(math.prod(level_counts(points)))
    return {
        "points": runs,
        "levels": "x".join(str(n) for n in level_counts(points)),
        "compute": {
            "cases": runs,
            "seconds": timings["run_s"],
            "cases_per_s": runs / timings["run_s"],
        },
        "end_to_end": {"cases": runs, "seconds": wall, "cases_per_s": runs / wall},
        "compile_s": round(timings["compile_s"], 3),
        "wall_over_compute": wall / timings["run_s"],
        "peak_rss_mb": round(peak, 1),
        "results_nc_mb": round(size / 1e6, 1),
        "results_nc_runs": stored_runs,
    }
