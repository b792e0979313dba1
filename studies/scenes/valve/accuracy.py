"""Scene ``valve_accuracy``: the ``valve`` scene with its integrator and step as factors.

In the ``valve`` scene the integrator and the RK4 step are accuracy settings, fixed for a
study. To measure the speed–accuracy trade (physics §4) they must vary between design points, so
this scene declares them as parameters (``integrator``, ``angle_step``) and adds two stages:

* ``reference`` — the error of each run against scipy's event-restarted reference
  (:mod:`studies.scenes.valve.reference.accuracy`), computed once per distinct set of the other parameters
  (e.g. once per camshaft speed × seat stiffness pair) and reused by every integrator and step;
* ``cost`` — measured seconds per case of the integrator's batch kernel (a timing: the median
  of repeats, with their interquartile range stored beside it whenever it runs).

Every ``valve`` response is available; the design points of one (integrator, step) pair are
evaluated together by the ``valve`` machinery with those settings.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from functools import partial
from typing import TYPE_CHECKING, Any

import numpy as np

from engine_kernels import valvetrain as valve
from studies.scenes.base import Parameter, Response, SceneOutput
from studies.scenes.checks import PointProblems, on_distinct
from studies.scenes.linkage.scene import (
    CACHE_SIZE,
    LINKAGE_NAMES,
    BoundedCache,
    angle_step_problem,
    grid_deg,
    step_deg,
)
from studies.scenes.valve.batches import STABILITY_NAMES
from studies.scenes.valve.error_bar import tolerance_rungs
from studies.scenes.valve.parameters import (
    ANGLE_STEP,
    DOPRI,
    DYNAMIC_RESPONSES,
    INTEGRATOR,
    INTEGRATORS,
    PARAMETERS,
    TOLERANCE,
    WINDOW_SETTINGS,
)
from studies.scenes.valve.parameters import SETTINGS as VALVE_SETTINGS
from studies.scenes.valve.reference import accuracy as acc
from studies.scenes.valve.scene import (
    MM,
    WINDOW_PROBE_DEG,
    ValveScene,
    integrate,
    jump_setting_problems,
    kernel_settings,
    stability_problems,
    valve_rows,
)
from studies.scenes.valve.state import CostState, ValveState

if TYPE_CHECKING:
    from studies.scenes.base import FigureBuilder

REFERENCE_METHODS = ("DOP853", "Radau")
REF = ("tappet", "rocker", "dynamics", "reference")  # the error of the reported run
COST = ("tappet", "rocker", "cost")
MS = 1e3

SETTINGS: tuple[Parameter, ...] = (
    *(s for s in VALVE_SETTINGS if s.name == "tappet_step"),
    *WINDOW_SETTINGS,
    Parameter(
        "reference_method",
        "1",
        "DOP853",
        "scipy solve_ivp method of the reference (event restarts at every mode switch)",
        choices=REFERENCE_METHODS,
    ),
    Parameter(
        "reference_rtol", "1", 1e-10, "relative tolerance of the reference solver", 1e-13, 1e-4
    ),
)

RESPONSES: tuple[Response, ...] = (
    *DYNAMIC_RESPONSES,
    Response(
        "reference_error",
        "mm",
        "max |y − y_ref| over the grid against the scipy reference (lanes: the same RK4 scheme "
        "as rk4)",
        REF,
    ),
    Response(
        "cost_per_case",
        "ms",
        "measured time per case of the batch kernel: median of repeated timings (wall clock: "
        "varies from run to run and machine to machine; spread in cost_per_case_iqr)",
        COST,
    ),
    Response(
        "cost_per_case_iqr",
        "ms",
        "interquartile range of the repeated timings behind cost_per_case (costs closer than "
        "their spreads are not different)",
        COST,
    ),
)


class ValveAccuracyScene(ValveScene):
    name = "valve_accuracy"
    seconds_per_point = 0.2
    description = "valve dynamics vs integrator and step: error against scipy, cost per case"
    parameters = (*PARAMETERS, INTEGRATOR, ANGLE_STEP, TOLERANCE)
    settings = SETTINGS
    responses = RESPONSES
    curves = ()
    curve_axis = None
    state_type = CostState
    stage_order = ("tappet", "rocker", "dynamics", "jump_speed", "reference", "cost")
    status_responses = (*ValveScene.status_responses, "cost_per_case_iqr")  # beside every cost

    # --- outputs beside the generic ones -----------------------------------------------------
    def figures(self) -> dict[str, FigureBuilder]:
        from studies.scenes.valve.figures.maps import error_vs_cost_figure  # noqa: PLC0415

        return {"error_vs_cost": error_vs_cost_figure}

    def __init__(self) -> None:
        super().__init__()
        self.reference_cache = BoundedCache(CACHE_SIZE)

    def kinematic_grid(self, settings: dict[str, Any]) -> tuple[float, float, float]:
        return -180.0, WINDOW_PROBE_DEG, 180.0

    def check_points(self, points: Mapping[str, np.ndarray], settings: dict[str, Any]) -> list[str]:
        def step_problems(values: dict[str, np.ndarray]) -> list[str]:
            found = PointProblems()
            for i, step in enumerate(values["angle_step"]):
                problem = angle_step_problem(step, "angle_step")
                if problem:
                    found.add(i, problem)
            return found.messages()

        def stability(values: dict[str, np.ndarray]) -> list[str]:
            return stability_problems(values, settings, values["angle_step"])

        problems = on_distinct(points, ("angle_step",), step_problems)
        problems += on_distinct(points, LINKAGE_NAMES, self.linkage_point_problems)
        problems += jump_setting_problems(settings)
        return problems + on_distinct(points, (*STABILITY_NAMES, "angle_step"), stability)

    def evaluate(
        self,
        points: dict[str, np.ndarray],
        settings: dict[str, Any],
        responses: list[str],
        curves: list[str],
    ) -> SceneOutput:
        scalars = {r: np.full(len(points["angle_step"]), np.nan) for r in responses}
        steps = [step_deg(s) for s in points["angle_step"]]
        spacing = acc.common_spacing({*steps, acc.REFERENCE_TABLE_DEG})
        groups: dict[tuple[str, float, float], list[int]] = {}
        for i, group in enumerate(
            zip(points["integrator"], steps, points["tolerance"], strict=True)
        ):
            groups.setdefault(group, []).append(i)
        for (integrator, step, tolerance), members in groups.items():
            idx = np.array(members)
            local = dict(settings, integrator=integrator, angle_step=math.radians(step))
            local |= {"tolerance": tolerance, "reference_spacing": spacing}
            out = super().evaluate({k: v[idx] for k, v in points.items()}, local, responses, [])
            for r in responses:
                scalars[r][idx] = out.scalars[r]
        return SceneOutput(scalars)

    def stage_reference(self, state: CostState) -> None:
        settings = state.settings
        step = step_deg(settings["angle_step"])
        spacing = settings["reference_spacing"]
        state.reference_error = np.full(state.n, np.nan)
        for key, idx in state.groups.items():
            if not self.linkage_valid(state, key):
                continue
            fine = self.excitation(state, key, 2.0 * acc.REFERENCE_TABLE_DEG, unclipped=True)
            window = self.window(state, key)
            theta = np.radians(grid_deg(window[0], spacing, window[1]))
            solver = (settings["reference_method"], settings["reference_rtol"])
            for i, row in zip(idx, valve_rows(state.points, idx), strict=True):
                reference = self.reference_cache.get(
                    (key, window, spacing, tuple(row), solver),
                    partial(acc.reference_lift, fine, row, theta, *solver),
                )
                lift = self.reported_lift(state, key, i, row)
                state.reference_error[i] = acc.max_error(lift, reference, round(step / spacing))

    def reported_lift(self, state: ValveState, key: tuple, i: int, row: np.ndarray) -> np.ndarray:
        """Lift [m] of point i on the study's grid, integrated as it was reported: at its
        step, method and sub-step count (they differ from the settings under a tolerance)."""
        settings = state.settings
        used = float(state.step_used[i])
        method = INTEGRATORS[int(state.method[i])]
        if method == DOPRI:
            grid = step_deg(settings["angle_step"])
            per_step = float(state.per_step[i])
            trace = self.dopri_run(state, key, row[None, :], grid, True, per_step)[1]
            assert trace is not None
            return trace[0, valve.C_LIFT]
        substeps = state.out[i, valve.O_SUBSTEPS]
        forced = int(substeps) if np.isfinite(substeps) else 0
        flags = kernel_settings(settings, method, False, forced)
        lift = acc.trajectory_lift(self.excitation(state, key, used), row, flags, method)
        return lift[:: round(step_deg(settings["angle_step"]) / used)]

    def stage_cost(self, state: CostState) -> None:
        """Seconds per case of what produced the results: the integrator's batch kernel at
        the study's step, or under a tolerance the whole ladder (runs, companions, rungs)."""
        settings = state.settings
        integrator = settings["integrator"]
        step = step_deg(settings["angle_step"])
        state.cost = np.full(state.n, np.nan)
        state.cost_iqr = np.full(state.n, np.nan)
        for key, idx in state.groups.items():
            if not self.linkage_valid(state, key):
                continue
            if settings["tolerance"] > 0.0:
                run = partial(self.ladder_run, state, key)
            elif integrator == DOPRI:
                run = partial(self.dopri_cost_run, state, key, step)
            else:
                flags = kernel_settings(settings, integrator, False)
                run = partial(_run_kernel, self.excitation(state, key, step), integrator, flags)
            for i, row in zip(idx, valve_rows(state.points, idx), strict=True):
                state.cost[i], state.cost_iqr[i] = acc.timing_per_case(run, row)

    def dopri_cost_run(
        self, state: ValveState, key: tuple, step: float, rows: np.ndarray
    ) -> object:
        """``dopri`` on ``rows`` as the dynamics stage runs it (for its timing)."""
        return self.dopri_run(state, key, rows, step, False)

    def ladder_run(self, state: ValveState, key: tuple, rows: np.ndarray) -> object:
        """The tolerance ladder of the dynamics stage on ``rows`` (for its timing)."""
        settings = state.settings
        return tolerance_rungs(
            lambda step, unclipped: self.excitation(state, key, step, unclipped=unclipped),
            rows,
            lambda method: kernel_settings(settings, method, False),
            settings["integrator"],
            step_deg(settings["angle_step"]),
            settings["tolerance"],
            False,
            False,
        )

    def scalar(self, state: ValveState, response: str) -> np.ndarray:
        if not isinstance(state, CostState):
            return super().scalar(state, response)
        if response == "reference_error":
            return state.reference_error * MM
        if response == "cost_per_case":
            return state.cost * MS
        if response == "cost_per_case_iqr":
            return state.cost_iqr * MS
        return super().scalar(state, response)


def _run_kernel(
    excitation: tuple[np.ndarray, float, float],
    integrator: str,
    flags: np.ndarray,
    rows: np.ndarray,
) -> object:
    return integrate(excitation, rows, integrator, flags, False)
