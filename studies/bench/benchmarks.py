"""Benchmarks: throughput figures printed and written as JSON under ``outputs/bench/``.

Timing claims live here, never in test assertions. Alternatives are measured in the same run
and reported as ratios, because the machines are shared and absolute figures are noisy.
Each benchmark warms up (compiles) first and reports the best of ``repeat`` timed runs.

The engine's own benchmark is ``study`` (:mod:`studies.bench.study`); each scene brings its
own through :meth:`studies.scenes.base.Scene.benchmarks` (``cam``, ``valve``), lent the
engine's planner and evaluator as a :class:`~studies.scenes.base.BenchKit`.
"""

from __future__ import annotations

import json
from collections.abc import Callable
from functools import partial
from pathlib import Path
from typing import Any

from studies.bench.plots import save_bench_figure
from studies.bench.study import bench_noise_study, bench_study
from studies.common.errors import StudyError
from studies.define.plan import plan_text
from studies.run import provenance
from studies.run.runner import evaluate_chunk
from studies.scenes import SCENES, BenchKit
from studies.tracking import records

Benchmark = Callable[[int, float, int], dict[str, Any]]
KIT = BenchKit(plan=plan_text, evaluate=evaluate_chunk)


def benchmarks() -> dict[str, Benchmark]:
    """Every benchmark by name: the engine's ``study`` and ``noise_study``, and each scene's
    own."""
    found: dict[str, Benchmark] = {"study": bench_study, "noise_study": bench_noise_study}
    for scene in SCENES.values():
        for name, bench in scene().benchmarks().items():
            found[name] = partial(bench, KIT)  # the engine's kit lent to the scene's benchmark
    return found


def summarize(figures: dict[str, Any], indent: str = "  ") -> list[str]:
    """Readable lines of a benchmark's figures: cases/s per timing, × per ratio, groups
    indented (the JSON file keeps every number)."""
    lines = []
    for key, value in figures.items():
        if isinstance(value, dict) and "cases_per_s" in value:
            lines.append(f"{indent}{key:<42} {value['cases_per_s']:>13,.1f} cases/s")
        elif isinstance(value, dict):
            lines += [f"{indent}{key}:", *summarize(value, indent + "  ")]
        elif isinstance(value, float) and "_over_" in key:
            lines.append(f"{indent}{key:<42} {value:>13.2f} ×")
        else:
            lines.append(f"{indent}{key:<42} {value!s:>13}")
    return lines


def run_benchmark(name: str, cases: int, step: float, repeat: int, outputs: Path) -> Path:
    """Run one benchmark; write its figures as JSON and a bar chart of the timings (PNG,
    same name); return the JSON path."""
    known = benchmarks()
    if name not in known:
        raise StudyError(f"unknown benchmark {name!r}; known: {', '.join(known)}, all")
    figures = known[name](cases, step, repeat)
    commit, dirty = provenance.git_state()
    record = {
        "benchmark": name,
        "cases": cases,
        "step_deg": step,
        "repeat": repeat,
        "created": records.now(),
        "git_commit": commit,
        "git_dirty": dirty,
        "versions": provenance.versions(),
        "host": provenance.host(),
        "figures": figures,
    }
    folder = outputs / "bench"
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / f"{name}-{records.new_run_id(name)}.json"
    path.write_text(json.dumps(record, indent=2) + "\n", encoding="utf-8")
    title = f"benchmark {name}: {cases} cases, step {step:g} deg, commit {commit[:10]}"
    save_bench_figure(title, figures, path.with_suffix(".png"))
    return path
