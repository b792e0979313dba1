"""Benchmark of a whole study, end to end: the command line in its own process, timed by the
wall clock, with its peak resident memory (``peak_rss_mb``: the run's process;
``peak_pss_all_mb``: with its figure workers, :mod:`studies.bench.tree_memory`), beside the
compute time the run records.

The study is the 125 cc OHC valve train of ``ohc125_dynamics`` over a full factorial of camshaft
speed × spring preload × spring rate × drive stiffness with that study's nine responses:
10⁶ points as 40 × 25 × 25 × 40 levels, 10⁷ as 100 × 40 × 50 × 50, other sizes as four
factors of about equal level counts. What the kernels cost is ``compute`` (``run.json``
``run_s``); everything else — imports, planning, writing results.nc, the analysis, the figures —
is the rest of ``end_to_end``.

``noise_study`` is the same valve study with a tolerance (noise) sample crossed with fewer
design points, about as many computed cases: its cost per case beside ``study``'s is the cost of
a noise case beside a design point's.
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

from studies.bench.tree_memory import TreePeak
from studies.common.errors import StudyError
from studies.define.definition import find_study

PHASES = ("results_s", "analysis_s", "figures_s", "report_s")  # after the chunks (run.json)
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


def study_text(points: int, counts: tuple[int, ...] = ()) -> str:
    """``ohc125_dynamics`` with its four factors at ``counts`` (default ``level_counts(points)``)
    levels each."""
    text = find_study("ohc125_dynamics").read_text(encoding="utf-8")
    text = text[: text.index("[factors.")].replace(
        'name = "ohc125_dynamics"', 'name = "bench_study"'
    )
    for (name, (low, high, units)), n in zip(
        RANGES.items(), counts or level_counts(points), strict=True
    ):
        levels = np.linspace(low, high, n).round(6).tolist()
        text += f'\n[factors.{name}]\nlevels = {levels}\nunits = "{units}"\n'
    return text


NOISE_CASES = 1024
"""Noise cases per design point of ``noise_study`` (a scrambled Sobol' sample, 2¹⁰)."""
NOISE = {  # noise factor: relative half width of its uniform tolerance [%]
    "spring_rate": 5.0,
    "spring_preload": 8.0,
    "drive_stiffness": 10.0,
    "equivalent_mass": 3.0,
}


def noise_design(points: int) -> tuple[int, ...]:
    """Level counts of the noise study's design: camshaft speeds × 4 × 4 × 4, with NOISE_CASES
    noise cases each at least ``points`` cases (10⁶: 16 × 4 × 4 × 4 × 1024 = 1 048 576)."""
    return (max(1, math.ceil(points / (NOISE_CASES * 64))), 4, 4, 4)


def noise_study_text(points: int) -> str:
    """:func:`study_text` at ``points`` / NOISE_CASES design points crossed with a Sobol' sample
    of NOISE_CASES tolerance cases over the spring, drive and mass (:data:`NOISE`): about
    ``points`` computed cases. The lash is left out on purpose: it fixes the linkage, so a
    noise over it makes one cam–rocker table per case (about 10 ms each)."""
    text = study_text(0, noise_design(points)).replace("bench_study", "bench_noise_study")
    text += f'\n[noise]\ntype = "sobol"\nsamples = {NOISE_CASES}\nseed = 1\n'
    for name, half_width in NOISE.items():
        text += f'\n[noise.{name}]\ndistribution = "uniform"\nhalf_width = {half_width}\n'
        text += "relative = true\n"
    return text


def run_command(args: list[str]) -> tuple[float, float, float | None]:
    """Run a command; its wall time [s], its peak resident memory [MB] (from wait4) and the
    peak of its process tree's summed PSS [MB] (with the figure workers; None off Linux)."""
    t0 = time.perf_counter()
    process = subprocess.Popen(args, stdout=subprocess.DEVNULL)
    tree = TreePeak(process.pid)
    _, status, usage = os.wait4(process.pid, 0)
    wall = time.perf_counter() - t0
    tree_peak = tree.stop()
    process.returncode = os.waitstatus_to_exitcode(status)  # reaped here, not by Popen
    if process.returncode != 0:  # the run said why on stderr, above
        msg = f"the benchmark's run stopped with exit code {process.returncode}: {' '.join(args)}"
        raise StudyError(msg)
    return wall, usage.ru_maxrss / 1024.0, tree_peak  # ru_maxrss: kB on Linux


def bench_study(points: int, step: float, repeat: int) -> dict[str, Any]:  # noqa: ARG001
    """Run the valve study of about ``points`` design points once through the command line
    (``repeat`` is not used: one run of a large study is the measurement)."""
    figures = _run_study("bench_study", study_text(points), step)
    runs = int(math.prod(level_counts(points)))
    return {"points": runs, "levels": "x".join(str(n) for n in level_counts(points)), **figures}


def bench_noise_study(points: int, step: float, repeat: int) -> dict[str, Any]:  # noqa: ARG001
    """Like :func:`bench_study` for :func:`noise_study_text`: about ``points`` cases, of which
    NOISE_CASES per design point are noise cases."""
    figures = _run_study("bench_noise_study", noise_study_text(points), step)
    designs = "x".join(str(n) for n in noise_design(points))
    return {"design_levels": designs, "noise_cases": NOISE_CASES, **figures}


def _run_study(name: str, text: str, step: float) -> dict[str, Any]:
    """Run the study ``text`` (called ``name``) once through the command line; its compute
    and end-to-end throughput over the computed cases, peak memory and results file."""
    with tempfile.TemporaryDirectory(prefix=f"{name}_") as tmp:
        folder = Path(tmp)
        study = folder / f"{name}.toml"
        study.write_text(text.replace("angle_step = 0.5", f"angle_step = {step}"))
        outputs = folder / "outputs"
        command = [sys.executable, "-m", "studies", "run", str(study), "--no-progress"]
        wall, peak, tree_peak = run_command([*command, "--outputs", str(outputs)])
        (record,) = outputs.glob(f"{name}/*/run.json")
        timings = json.loads(record.read_text(encoding="utf-8"))["timings"]
        (results,) = outputs.glob(f"{name}/*/results.nc")
        size = results.stat().st_size
        with netCDF4.Dataset(results) as stored:
            cases = len(stored.dimensions["run"])
            if "noise" in stored.dimensions:
                cases *= len(stored.dimensions["noise"])
        shutil.rmtree(outputs, ignore_errors=True)
    return {
        "compute": {
            "cases": cases,
            "seconds": timings["run_s"],
            "cases_per_s": cases / timings["run_s"],
        },
        "end_to_end": {"cases": cases, "seconds": wall, "cases_per_s": cases / wall},
        "compile_s": round(timings["compile_s"], 3),
        **{k: round(timings[k], 2) for k in PHASES if k in timings},
        "wall_over_compute": wall / timings["run_s"],
        "peak_rss_mb": round(peak, 1),
        "peak_pss_all_mb": None if tree_peak is None else round(tree_peak, 1),
        "results_nc_mb": round(size / 1e6, 1),
        "results_nc_cases": cases,
    }
