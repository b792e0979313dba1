"""The ``luffing`` scene: trolley-drive sizing checks of the tower-crane test rig (physics §7).

One stage, ``sizing`` (:func:`engine_kernels.luffing.sizing.luffing_batch`): the chain resistance →
work power → motor power → next rated motor → belt, pulley, shaft load → coupling torque, key,
bearing life, and the guide-tube deflection and slope. Every check is reported as value, limit
and pass flag; ``all_checks_ok`` and ``checks_passed`` sum them up.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from engine_kernels.luffing import drive
from engine_kernels.luffing import sizing as lf
from studies.common.units import UNITS
from studies.scenes.base import Scene, SceneOutput
from studies.scenes.checks import LoopOrder, groups_of, on_distinct
from studies.scenes.luffing.parameters import CHECKS, KERNEL_NAMES, NEEDS, PARAMETERS, RESPONSES
from studies.scenes.state import RunState

if TYPE_CHECKING:
    import xarray as xr

    from studies.scenes.base import FigureBuilder

BEARING_CODES = {"ball": drive.BALL_BEARING, "roller": drive.ROLLER_BEARING}
COLUMNS = {name: getattr(lf, name.upper()) for name in lf.PARAM_NAMES}
"""Kernel column of each parameter (the scene's parameter names are the kernel's)."""


def luffing_params(points: dict[str, np.ndarray]) -> np.ndarray:
    """The kernel parameter matrix params[n, N_PARAMS] (SI) of these design points."""
    n = len(points["trolley_mass"])
    params = np.empty((n, lf.N_PARAMS))
    for name, column in COLUMNS.items():
        if name == "bearing_type":
            params[:, column] = [BEARING_CODES[b] for b in points[name]]
        else:
            params[:, column] = points[name]
    return params


CHECKED = ("tube_outer_diameter", "tube_inner_diameter", "motor_ratings")
"""The parameters ``check_points`` reads."""


@dataclass(slots=True)
class LuffingState(RunState):
    """Run state of a ``luffing`` chunk."""

    out: np.ndarray = field(init=False)  # luffing_batch outputs (n, lf.N_OUT), SI, lf.OUTPUTS


class LuffingScene(Scene[LuffingState]):
    """Tower-crane test-rig trolley drive (physics §7)."""

    name = "luffing"
    seconds_per_point = 3e-4
    description = (
        "tower-crane test-rig trolley drive: motor, belt, coupling, key, bearing and "
        "guide-tube checks as value, limit and pass (physics §7)"
    )
    parameters = PARAMETERS
    responses = RESPONSES
    stage_order = NEEDS
    state_type = LuffingState

    # --- outputs beside the generic ones -----------------------------------------------------
    def figures(self) -> dict[str, FigureBuilder]:
        from studies.scenes.luffing.figures import motor_power_figure, pass_fail_map_figure  # noqa: PLC0415  (matplotlib on use)

        return {"pass_fail_map": pass_fail_map_figure, "motor_power": motor_power_figure}

    def summaries(self, ds: xr.Dataset) -> list[str]:
        from studies.scenes.luffing.summaries import luffing_summary  # noqa: PLC0415  (xarray on use)

        return luffing_summary(ds)

    def check_points(self, points: Mapping[str, np.ndarray], settings: dict[str, Any]) -> list[str]:
        return on_distinct(points, CHECKED, self._distinct_problems)

    def _distinct_problems(self, points: dict[str, np.ndarray]) -> list[str]:
        found = LoopOrder()
        mm = UNITS["mm"].to_si
        outer = np.asarray(points["tube_outer_diameter"])
        inner = np.asarray(points["tube_inner_diameter"])
        found.add(
            0,
            inner >= outer,
            [inner, outer],
            lambda i: (
                f"tube_inner_diameter = {inner[i] / mm:g} mm must be smaller than "
                f"tube_outer_diameter = {outer[i] / mm:g} mm"
            ),
        )
        ratings = np.asarray(points["motor_ratings"])
        bad = np.zeros(len(ratings), dtype=bool)
        for i, members in groups_of(np.arange(len(ratings)), [ratings]):
            row = ratings[i]
            bad[members] = bool(np.any(row <= 0) or np.any(np.diff(row) <= 0))
        found.add(
            1,
            bad,
            [ratings],
            lambda i: (
                f"motor_ratings = [{', '.join(f'{r:g}' for r in ratings[i])}] W must be "
                "positive and strictly ascending"
            ),
        )
        return found.messages()

    def stage_sizing(self, state: LuffingState) -> None:
        """Every check of every design point (:func:`engine_kernels.luffing.sizing.luffing_batch`)."""
        ratings = np.ascontiguousarray(
            state.points["motor_ratings"][0]
        )  # a vector: same in every run
        state.out = np.empty((state.n, lf.N_OUT))
        lf.luffing_batch(luffing_params(state.points), ratings, state.out)

    def finish(self, state: LuffingState) -> SceneOutput:
        si = dict(zip(KERNEL_NAMES, state.out.T, strict=True))
        si["selected_motor"] = si["selected_motor"] + 1.0
        flags = np.stack([si[f"{c}_ok"] for c in CHECKS])
        si["checks_passed"] = (flags == 1.0).sum(axis=0).astype(float)
        # a failed check fails the design; else one not evaluated leaves it unknown
        unknown = np.where(np.isnan(flags).any(axis=0), np.nan, 1.0)
        si["all_checks_ok"] = np.where((flags == 0.0).any(axis=0), 0.0, unknown)
        return SceneOutput(
            scalars={
                r: si[r] / UNITS[self.response(r).units].to_si  # type: ignore[union-attr]
                for r in state.responses
            },
        )
