"""The valve scene's benchmarks: the lane kernel (double and single precision) against one
case per prange iteration and against the C reference of the lane kernel on identical inputs,
the multi-mass spring kernel [V4] against the lumped lanes (:mod:`.multi_mass`), the scene end to
end through the study engine for each integrator, and scipy's event-restarted DOP853 (the
accuracy reference). Reached through :meth:`studies.scenes.base.Scene.benchmarks`; the engine
lends the planner and the evaluator (the scene layer cannot import them)."""

from __future__ import annotations

import ctypes
import time
from collections.abc import Callable
from functools import partial
from typing import Any

import numpy as np

from engine_kernels import valvetrain as valve
from engine_kernels.valvetrain.valve import lane_batch as valve_lanes
from studies.common.simd import host_lanes
from studies.common.timing import best_time, best_times
from studies.scenes.base import BenchKit
from studies.scenes.linkage.scene import HALF_TURN_DEG, grid_deg
from studies.scenes.valve.batches import kernel_settings, valve_rows
from studies.scenes.valve.bench.multi_mass import chain_figures
from studies.scenes.valve.reference import c_valve
from studies.scenes.valve.reference.accuracy import reference_lift
from studies.scenes.valve.state import ValveState

VALVE_STUDY = """
name = "bench_valve"
scene = "valve"
responses = ["max_lift", "follows_cam", "bounce_count", "seating_velocity"]
design = "full_factorial"
[settings]
integrator = "{integrator}"
angle_step = {step}
tolerance = {tolerance}
[factors.cam_speed]
levels = {speeds}
[factors.spring_preload]
levels = {preloads}
"""
VALVE_PRELOADS = 20
SWITCH_AWARE_CASES = 1000
ACCURATE = {
    "dopri": ("dopri", 0.0),
    "tolerance_1e-3": ("lanes", 1e-3),
    "tolerance_1e-4": ("lanes", 1e-4),
}
"""The accurate settings timed end to end beside the default: label → (integrator, tolerance
[mm]); as many cases as the switch-aware RK4."""
SCIPY_SPEEDS = (3000.0, 4500.0, 6000.0)
SCIPY_RTOLS = (1e-10, 1e-6)


def _valve_plan(
    kit: BenchKit, integrator: str, cases: int, step: float, tolerance: float = 0.0
) -> Any:
    """The default valve train at camshaft speeds 3000–6000 rpm × spring preloads."""
    preloads = min(VALVE_PRELOADS, cases)
    speeds = np.linspace(3000.0, 6000.0, max(cases // preloads, 1)).round(6).tolist()
    levels = np.linspace(180.0, 240.0, preloads).round(6).tolist()
    text = VALVE_STUDY.format(
        integrator=integrator, step=step, speeds=speeds, preloads=levels, tolerance=tolerance
    )
    return kit.plan(text)


def bench_valve(kit: BenchKit, cases: int, step: float, repeat: int) -> dict[str, Any]:
    """Valve cases/s: the lane kernel (double and single precision) vs one case per prange
    iteration and vs the C reference of the lane kernel on identical inputs (kernels alone,
    over the scene's window and over a whole revolution, and end to end through the study
    engine), the multi-mass spring kernel [V4] for N = 1 … 24 against the lumped lanes on the
    same rows (:mod:`.multi_mass`), the switch-aware RK4, the accurate settings (``ACCURATE``:
    ``dopri`` and the tolerance mode, each with its cost per case over the default's,
    ``scene_<label>_cost_over_lanes``), and scipy's event-restarted DOP853 (the accuracy
    reference)."""
    figures: dict[str, Any] = {
        "lanes_per_vector_float64": host_lanes(np.float64),
        "lanes_per_vector_float32": host_lanes(np.float32),
        "kernel": _valve_kernels(kit, cases, step, repeat),
        "multi_mass": _multi_mass(kit, cases, step, repeat),
    }
    fewer = min(cases, SWITCH_AWARE_CASES)
    for label, integrator, n, tolerance in [
        ("lanes", "lanes", cases, 0.0),
        ("lanes_f32", "lanes_f32", cases, 0.0),
        ("rk4", "rk4", cases, 0.0),
        ("rk4_switch_aware", "rk4_switch_aware", fewer, 0.0),
        *((label, method, fewer, tolerance) for label, (method, tolerance) in ACCURATE.items()),
    ]:
        plan = _valve_plan(kit, integrator, n, step, tolerance)
        seconds = best_time(partial(kit.evaluate, plan, slice(0, plan.runs)), repeat)
        figures[f"scene_{label}"] = {
            "cases": plan.runs,
            "seconds": seconds,
            "cases_per_s": plan.runs / seconds,
        }
    for name in ("lanes", "lanes_f32"):
        figures[f"scene_{name}_over_one_case"] = (
            figures[f"scene_{name}"]["cases_per_s"] / figures["scene_rk4"]["cases_per_s"]
        )
    for label in ACCURATE:
        figures[f"scene_{label}_cost_over_lanes"] = (
            figures["scene_lanes"]["cases_per_s"] / figures[f"scene_{label}"]["cases_per_s"]
        )
    scene, state, key, idx = _valve_case(
        kit,
        VALVE_STUDY.format(
            integrator="rk4",
            step=step,
            speeds=list(SCIPY_SPEEDS),
            preloads=[205.8],
            tolerance=0.0,
        ),
    )
    excitation = scene.excitation(state, key, step)
    start, stop = scene.window(state, key)
    theta = np.radians(grid_deg(start, step, stop))
    rows = valve_rows(state.points, idx)
    for rtol in SCIPY_RTOLS:
        t0 = time.perf_counter()
        for row in rows:
            reference_lift(excitation, row, theta, "DOP853", rtol)
        seconds = time.perf_counter() - t0
        figures[f"scipy_dop853_rtol_{rtol:g}"] = {
            "cases": len(rows),
            "seconds": seconds,
            "cases_per_s": len(rows) / seconds,
        }
    return figures


def _valve_case(kit: BenchKit, text: str) -> tuple[Any, ValveState, tuple, np.ndarray]:
    """Scene (the valve scene of the plan), run state, linkage key and points of a valve
    study with one cam–rocker linkage."""
    plan = kit.plan(text)
    scene = plan.scene
    state = scene.start(plan.points, plan.settings, [], [])
    ((key, idx),) = state.groups.items()
    return scene, state, key, idx


def _valve_kernels(kit: BenchKit, cases: int, step: float, repeat: int) -> dict[str, Any]:
    """The compiled kernels alone on the same parameter rows: over the scene's integration
    window, and over a whole cam revolution (the equal-work figure for a 360° comparison).

    Beside the Numba kernels, the C reference of the lane kernel (``studies/scenes/valve/reference/
    valve_lanes.c``, lanes and one case at a time, both precisions) built with this machine's
    compiler: the issue's "C -O3 kernel of this form", measured here rather than quoted.
    """
    scene, state, key, idx = _valve_case(
        kit, _valve_plan(kit, "lanes", cases, step).definition.text
    )
    first, last = scene.window(state, key)
    tables = {
        "window": scene.excitation(state, key, step),
        "revolution": scene.excitation(state, key, step, (-HALF_TURN_DEG, HALF_TURN_DEG)),
    }
    rows = valve_rows(state.points, idx)
    flags = kernel_settings(state.settings, "lanes", estimate=False)
    out = np.empty((rows.shape[0], len(valve.VALVE_OUTPUT_NAMES)))
    figures: dict[str, Any] = {"window_span_deg": last - first, "step_deg": step}
    libraries, skipped = _c_reference(tables["revolution"], rows, flags, out)
    if skipped:
        figures["c_reference"] = f"skipped: {skipped}"
    for span, (table, table_step, start) in tables.items():
        runs: dict[str, Callable[[], None]] = {}
        for suffix, dtype in PRECISIONS.items():
            typed: np.ndarray = table.astype(dtype)
            numba_args = (typed, table_step, start, rows, flags, out)
            runs[f"lanes{suffix}"] = partial(valve_lanes.valve_response_lanes, *numba_args)
            if dtype == np.float64:
                runs["one_case"] = partial(valve.valve_response_batch, *numba_args)
            if dtype in libraries:
                for name in ("lanes", "one_case"):
                    runs[f"c_{name}{suffix}"] = partial(
                        c_valve.valve_response_c,
                        libraries[dtype],
                        f"valve_{name}",
                        typed,
                        table_step,
                        start,
                        rows,
                        out,
                    )
        for name, seconds in zip(runs, best_times(list(runs.values()), repeat), strict=True):
            figures[f"{span}_{name}"] = {
                "cases": len(rows),
                "seconds": seconds,
                "cases_per_s": len(rows) / seconds,
            }
        for numerator, denominator in RATIOS:
            if f"{span}_{denominator}" in figures:
                figures[f"{span}_{numerator}_over_{denominator}"] = (
                    figures[f"{span}_{numerator}"]["cases_per_s"]
                    / figures[f"{span}_{denominator}"]["cases_per_s"]
                )
    return figures


def _multi_mass(kit: BenchKit, cases: int, step: float, repeat: int) -> dict[str, Any]:
    """The multi-mass spring kernel on the rows and window table of :func:`_valve_kernels`."""
    scene, state, key, idx = _valve_case(
        kit, _valve_plan(kit, "lanes", cases, step).definition.text
    )
    rows = valve_rows(state.points, idx)
    flags = kernel_settings(state.settings, "lanes", estimate=False)
    return chain_figures(scene.excitation(state, key, step), rows, flags, repeat)


def _c_reference(
    revolution: tuple[np.ndarray, float, float],
    rows: np.ndarray,
    flags: np.ndarray,
    out: np.ndarray,
) -> tuple[dict[type, ctypes.CDLL], str]:
    """The C reference built for each precision, or why the comparison is skipped.

    The C kernel has no stability guard: it does the same work only where the guard gives
    every case one RK4 sub-step, which is checked here.
    """
    table, table_step, start = revolution
    valve_lanes.valve_response_lanes(table, table_step, start, rows, flags, out)
    if np.any(out[:, valve.O_SUBSTEPS] != 1):
        return {}, "some cases need RK4 sub-steps, which the C reference does not take"
    try:
        return {dtype: c_valve.build(np.dtype(dtype)) for dtype in PRECISIONS.values()}, ""
    except (c_valve.CompilerMissing, c_valve.CompileFailed) as error:
        return {}, str(error)


PRECISIONS: dict[str, type] = {"": np.float64, "_f32": np.float32}
RATIOS = (
    ("lanes", "one_case"),
    ("lanes_f32", "one_case"),
    ("lanes", "c_lanes"),
    ("lanes_f32", "c_lanes_f32"),
    ("c_lanes", "c_one_case"),
    ("c_lanes_f32", "c_one_case_f32"),
)
