"""Scene ``valve_spring_ladder``: the ``valve`` scene with the spring model as a factor [V4].

In the ``valve`` scene the spring model is a setting, fixed for a study. To measure what each
rung of the model ladder changes and costs, this scene declares the rung as a parameter:
``spring_masses`` = 0 is the lumped model (m_s/3 on the valve), N = 1 … 24 the chain of N coil
masses. Design points of one rung are evaluated together by the ``valve`` machinery with that
rung's settings, and a ``cost`` stage measures the seconds per case of the rung's batch kernel
(``lanes`` for the lumped rung, the chain batch for N ≥ 1) on enough copies of a point that
fixed overhead stays small (:func:`studies.scenes.valve.reference.accuracy.seconds_per_case`).

The lumped rung answers the spring responses from its own assumptions: the spring force at the
retainer is the static ``Ps0 + ks·y`` (ratio 1, deviation 0, no surge), the run status is the
dynamics' status, and coils clash only if the lift reaches the travel to solid length.
"""

from __future__ import annotations

from functools import partial
from typing import TYPE_CHECKING, Any

import numpy as np

from studies.scenes.base import Parameter, Response, SceneOutput
from studies.scenes.linkage.scene import step_deg
from studies.scenes.valve import spring
from studies.scenes.valve.parameters import PARAMETERS, RESPONSES, SETTINGS
from studies.scenes.valve.reference import accuracy as acc
from studies.scenes.valve.scene import MM, ValveScene, integrate, kernel_settings, valve_rows
from studies.scenes.valve.spring_parameters import SPRING_MASSES, SPRING_MODEL, SURGE_RESPONSES
from studies.scenes.valve.state import CostState, ValveState

if TYPE_CHECKING:
    from studies.scenes.base import FigureBuilder

MS = 1e3
COST = ("tappet", "rocker", "cost")
SURGE_NAMES = frozenset(r.name for r in SURGE_RESPONSES)

RUNG = Parameter(
    "spring_masses",
    "1",
    0.0,
    "rung of the spring-model ladder: 0 = lumped (m_s/3 on the valve), N = 1 … 24 coil masses",
    0.0,
    24.0,
    integer=True,
)


class ValveSpringLadderScene(ValveScene):
    name = "valve_spring_ladder"
    seconds_per_point = 0.05
    description = "valve dynamics vs spring model: lumped and N-mass chains, change and cost"
    parameters = (*PARAMETERS, RUNG)
    settings = tuple(s for s in SETTINGS if s not in (SPRING_MODEL, SPRING_MASSES))
    responses = (
        *RESPONSES,
        Response(
            "cost_per_case",
            "ms",
            "measured time per case of the rung's batch kernel: median of repeated timings "
            "(wall clock: varies from run to run and machine to machine; spread in "
            "cost_per_case_iqr)",
            COST,
        ),
        Response(
            "cost_per_case_iqr",
            "ms",
            "interquartile range of the repeated timings behind cost_per_case (costs closer "
            "than their spreads are not different)",
            COST,
        ),
    )
    status_responses = (*ValveScene.status_responses, "cost_per_case_iqr")  # beside every cost
    curves = ()
    curve_axis = None
    state_type = CostState
    stage_order = ("tappet", "rocker", "dynamics", "surge", "jump_speed", "cost")

    def figures(self) -> dict[str, FigureBuilder]:
        from studies.scenes.valve.figures.ladder import ladder_figure  # noqa: PLC0415
        from studies.scenes.valve.figures.surge import surge_sweep_figure  # noqa: PLC0415

        return {"spring_model_ladder": ladder_figure, "surge_sweep": surge_sweep_figure}

    def request_problems(
        self, settings: dict[str, Any], responses: list[str], curves: list[str]
    ) -> list[str]:
        return spring.request_problems(dict(settings, spring_model="multi_mass"), responses, [])

    def evaluate(
        self,
        points: dict[str, np.ndarray],
        settings: dict[str, Any],
        responses: list[str],
        curves: list[str],
    ) -> SceneOutput:
        rungs = points["spring_masses"]
        scalars = {r: np.full(len(rungs), np.nan) for r in responses}
        for rung in np.unique(rungs):
            idx = np.flatnonzero(rungs == rung)
            model = "lumped" if rung == 0 else "multi_mass"
            local = dict(settings, spring_model=model, spring_masses=max(int(rung), 1))
            asked = [r for r in responses if rung > 0 or r not in SURGE_NAMES]
            if rung == 0 and len(asked) < len(responses):
                asked = list(dict.fromkeys([*asked, "status", "max_lift"]))
            out = super().evaluate({k: v[idx] for k, v in points.items()}, local, asked, [])
            for r in asked:
                if r in scalars:
                    scalars[r][idx] = out.scalars[r]
            if rung == 0:
                _lumped_spring_answers(scalars, idx, points, out.scalars)
        return SceneOutput(scalars)

    def stage_cost(self, state: CostState) -> None:
        settings = state.settings
        chained = spring.uses_chain(settings)
        flags = kernel_settings(settings, "lanes", False)
        state.cost = np.full(state.n, np.nan)
        state.cost_iqr = np.full(state.n, np.nan)
        step = step_deg(settings["angle_step"])
        for key, idx in state.groups.items():
            if not self.linkage_valid(state, key):
                continue
            excitation = self.excitation(state, key, step)
            rows = self.spring_rows(state, idx) if chained else valve_rows(state.points, idx)
            run = partial(_run_rung, excitation, flags, chained)
            for i, row in zip(idx, rows, strict=True):
                state.cost[i], state.cost_iqr[i] = acc.timing_per_case(run, row)

    def scalar(self, state: ValveState, response: str) -> np.ndarray:
        if not isinstance(state, CostState):
            return super().scalar(state, response)
        if response == "cost_per_case":
            return state.cost * MS
        if response == "cost_per_case_iqr":
            return state.cost_iqr * MS
        return super().scalar(state, response)


def _run_rung(
    excitation: tuple[np.ndarray, float, float], flags: np.ndarray, chained: bool, rows: np.ndarray
) -> object:
    if chained:
        return spring.run_chain(excitation, rows, flags, False)
    return integrate(excitation, rows, "lanes", flags, False)


def _lumped_spring_answers(
    scalars: dict[str, np.ndarray],
    idx: np.ndarray,
    points: dict[str, np.ndarray],
    lumped: dict[str, np.ndarray],
) -> None:
    """The spring responses of the lumped rung, from its assumptions (module docstring)."""
    by_definition = {
        "surge_amplitude": 0.0,
        "min_retainer_force_ratio": 1.0,
        "max_retainer_force_deviation": 0.0,
    }
    if "surge_frequency" in scalars:
        rate, mass = points["spring_rate"][idx], points["spring_mass"][idx]
        scalars["surge_frequency"][idx] = 0.5 * np.sqrt(rate / mass)
    for name, value in by_definition.items():
        if name in scalars:
            scalars[name][idx] = value
    if "surge_status" in scalars:
        scalars["surge_status"][idx] = lumped["status"]
    if "coil_clash_count" in scalars:
        travel = points["clash_travel"][idx] * MM
        scalars["coil_clash_count"][idx] = (lumped["max_lift"] >= travel).astype(float)
