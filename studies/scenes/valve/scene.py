"""Scene ``valve``: single-DOF valve-train dynamics driven through the rocker (physics §4).

The excitation is the theoretical valve lift Y(θ) of the ``rocker`` scene's linkage, so this
scene extends :class:`~studies.scenes.linkage.scene.LinkageScene` and adds two stages:

* ``dynamics`` — fixed-step RK4 of [V2] over the integration window (valve opening − 2° …
  closure + ``closing_window``, snapped outward to whole multiples of 2°), with the integrator
  of the settings: :func:`engine_kernels.valvetrain.valve.lane_batch.valve_response_lanes` (``lanes``, and
  ``lanes_f32`` on a float32 copy of the table), :func:`engine_kernels.valvetrain.valve_response_batch`
  (``rk4``, ``rk4_switch_aware``), or one :func:`engine_kernels.valvetrain.valve_response` call
  per point (double precision) when curves are stored;
* ``jump_speed`` — :func:`engine_kernels.valvetrain.jump_speed` per design point (scan over
  geometric speeds, then bisection), at ``angle_step``.

Kinematic responses run only ``tappet`` and ``rocker``. Points sharing the cam and rocker
parameters share one excitation table (cached per linkage and step): it is the table every
lane of a block reads. Jumps, bounces, an unstable run or an invalid linkage are results
(``follows_cam``, ``status``, ``run_ok``), never exceptions. How a tolerance picks the step is
described in :mod:`studies.scenes.valve.parameters`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

import numpy as np

from engine_kernels import valvetrain as valve
from engine_kernels.valvetrain import rocker
from studies.scenes.checks import on_distinct
from studies.scenes.linkage.parameters import RESPONSES as ROCKER_RESPONSES
from studies.scenes.linkage.scene import (
    CACHE_SIZE,
    GRID_UNIT_DEG,
    HALF_TURN_DEG,
    BoundedCache,
    LinkageScene,
    open_range,
    step_deg,
)
from studies.scenes.state import RunState
from studies.scenes.valve import spring, work
from studies.scenes.valve.batches import (
    N_CURVES,
    N_OUT,
    STABILITY_NAMES,
    dopri_jump_speeds,
    integrate,
    integrate_dopri,
    jump_setting_problems,
    kernel_settings,
    rk4_jump_speeds,
    stability_problems,
    valve_rows,
)
from studies.scenes.valve.error_bar import BAR_FACTOR, DERIVED_BARS, Ladder, tolerance_rungs
from studies.scenes.valve.excitation import unclipped_valve_lift
from studies.scenes.valve.output_columns import BAR_SCALE, CURVE_ROWS, MM, OUTPUT_COLUMNS
from studies.scenes.valve.parameters import (
    CURVES,
    DOPRI,
    INTEGRATORS,
    JUMP_NOT_RUN,
    PARAMETERS,
    RESPONSES,
    SETTINGS,
    STATUS_NOT_RUN,
    dopri_table_deg,
    dopri_tolerance,
)
from studies.scenes.valve.state import ValveState

if TYPE_CHECKING:
    import xarray as xr

    from studies.scenes.base import FigureBuilder, SceneBenchmark

RPM = 30.0 / math.pi
WINDOW_PROBE_DEG = 0.25
"""Grid on which the valve opening and closing angles that set the window are found."""
PRE_OPEN_DEG = 2.0
BUDGET_RESPONSES = frozenset(("integration_error", "excitation_error"))
BAR_RESPONSES = (
    frozenset(("error_estimate", "step_halving_difference", *DERIVED_BARS)) | BUDGET_RESPONSES
)
KINEMATIC_RESPONSES = frozenset(r.name for r in ROCKER_RESPONSES)


class ValveScene(LinkageScene[ValveState]):
    name = "valve"
    # The dynamics at fixed step (lanes at 0.5°, the default): `bench study` measured 2.8 µs a
    # design point on 2 cores (10⁷ points, b61dd3e), about 6 µs on one; 1e-5 s bounds both.
    seconds_per_point = 1e-5
    # Anything else, per design point [s]: the jump-speed search measured 0.29 ms on 2 cores
    # (2000 points of jump_speed_map's setup); dopri costs 9–62× the default per case and the
    # tolerance ladder 27–10 060× (issue #26's random sample); the multi-mass chain was not
    # measured at scale (1e-3, the conservative value this scene had for everything).
    SEARCH_OR_ADAPTIVE_SECONDS = 1e-3
    TOLERANCE_SECONDS = 1e-2
    work_estimate = staticmethod(work.work_estimate)  # type: ignore[assignment]
    description = "valve-train dynamics through the rocker: jump, bounce, seating, jump speed"
    parameters = PARAMETERS
    settings = SETTINGS
    responses = RESPONSES
    curves = CURVES
    stage_order: tuple[str, ...] = ("tappet", "rocker", "dynamics", "surge", "jump_speed")
    status_responses: tuple[str, ...] = ("chain_status", "status", "surge_status")
    state_type: type[RunState] = ValveState

    def point_seconds(self, settings: dict[str, Any], responses: list[str]) -> float:
        """:attr:`seconds_per_point` for the fixed-step dynamics; more for the jump-speed
        search, ``dopri``, the multi-mass chain or a tolerance (see the class constants)."""
        if self.name != ValveScene.name:  # the accuracy and spring-ladder scenes: their own
            return self.seconds_per_point
        if settings.get("tolerance"):
            return self.TOLERANCE_SECONDS
        known = [r for r in responses if self.response(r)]  # unknown ones are refused later
        plain = set(self.stages_to_run(settings, known, [])) <= {"tappet", "rocker", "dynamics"}
        if plain and settings.get("integrator", "lanes") != DOPRI:
            return self.seconds_per_point
        return self.SEARCH_OR_ADAPTIVE_SECONDS

    def stages_to_run(
        self, settings: dict[str, Any], responses: list[str], curves: list[str]
    ) -> list[str]:
        """Under ``spring_model = "multi_mass"`` the ``surge`` stage answers the dynamic
        responses too: it runs in place of ``dynamics``."""
        stages = self.stages_for(responses, curves)
        if spring.uses_chain(settings) and "dynamics" in stages:
            wanted = {*stages, "surge"} - {"dynamics"}
            stages = [s for s in self.stage_order if s in wanted]
        return stages

    # --- outputs beside the generic ones -----------------------------------------------------
    def figures(self) -> dict[str, FigureBuilder]:
        from studies.scenes.linkage.figures import valve_lift_figure  # noqa: PLC0415
        from studies.scenes.valve.figures.maps import jump_speed_map_figure  # noqa: PLC0415
        from studies.scenes.valve.figures.surge import surge_sweep_figure  # noqa: PLC0415

        return {
            "valve_lift": valve_lift_figure,
            "jump_speed_map": jump_speed_map_figure,
            "surge_sweep": surge_sweep_figure,
        }

    def benchmarks(self) -> dict[str, SceneBenchmark]:
        from studies.scenes.valve.bench.kernels import bench_valve  # noqa: PLC0415

        return {"valve": bench_valve}

    def summaries(self, ds: xr.Dataset) -> list[str]:
        from studies.scenes.linkage.summaries import linkage_status_summary  # noqa: PLC0415
        from studies.scenes.valve.summaries import dynamics_status_summary  # noqa: PLC0415

        return linkage_status_summary(ds) + dynamics_status_summary(ds)

    def __init__(self) -> None:
        super().__init__()
        self.window_cache = BoundedCache(CACHE_SIZE)

    # --- checks ---------------------------------------------------------------------------
    def check_points(self, points: Mapping[str, np.ndarray], settings: dict[str, Any]) -> list[str]:
        problems = super().check_points(points, settings) + jump_setting_problems(settings)
        problems += on_distinct(points, spring.MASS_NAMES, spring.spring_point_problems)

        def stability(values: dict[str, np.ndarray]) -> list[str]:
            steps = np.broadcast_to(settings["angle_step"], len(values["cam_speed"]))
            return stability_problems(values, settings, steps)

        return problems + on_distinct(points, STABILITY_NAMES, stability)

    def request_problems(
        self, settings: dict[str, Any], responses: list[str], curves: list[str]
    ) -> list[str]:
        return spring.request_problems(settings, responses, curves)

    # --- excitation -----------------------------------------------------------------------
    def window(self, state: ValveState, key: tuple) -> tuple[float, float]:
        """Integration window [deg]: opening − 2° … closure + closing window, on 2° marks."""
        closing_window = math.degrees(state.settings["closing_window"])
        spacing = step_deg(state.settings["tappet_step"])

        def make() -> tuple[float, float]:
            probe = self.linkage(state, key, (-HALF_TURN_DEG, WINDOW_PROBE_DEG, HALF_TURN_DEG))
            opening, closing = open_range(probe)
            if math.isnan(opening):
                return -HALF_TURN_DEG, HALF_TURN_DEG
            start = math.floor((opening - PRE_OPEN_DEG) / GRID_UNIT_DEG) * GRID_UNIT_DEG
            stop = math.ceil((closing + closing_window) / GRID_UNIT_DEG) * GRID_UNIT_DEG
            return max(start, -HALF_TURN_DEG), min(stop, HALF_TURN_DEG)

        return self.window_cache.get((key, spacing, closing_window), make)

    def excitation(
        self,
        state: ValveState,
        key: tuple,
        step: float,
        span: tuple[float, float] | None = None,
        unclipped: bool = False,
    ) -> tuple[np.ndarray, float, float]:
        """(Y, Y', Y'') table at half the RK4 ``step`` [deg] over the integration window (or
        over ``span`` = (start, stop) [deg]), its step [rad] and start [rad].

        The linkage's valve lift, clipped at zero where the lash is open: interpolated, its kink
        at lash take-up is smeared over a table interval, and fixed-step RK4 converges
        regularly as its table halves with its step (so its step-halving bar holds). With
        ``unclipped``, the lift before the take-up, which the kernels clip exactly at its zero
        (:mod:`studies.scenes.valve.excitation`): for ``dopri``, whose table does not follow
        its steps, and for the scipy reference.
        """
        start, stop = self.window(state, key) if span is None else span
        grid = (start, step / 2.0, stop)
        if unclipped:
            table = self.linkage_cache.get(
                ("unclipped", key, step_deg(state.settings["tappet_step"]), grid),
                lambda: unclipped_valve_lift(
                    self.rocker_walk(state, key, no_lash=True), self.tappet_table(state, key), grid
                ),
            )
        else:
            linkage = self.linkage(state, key, grid)
            table = np.ascontiguousarray(linkage.curves[: rocker.ROW_VALVE_ACCELERATION + 1])
        return table, math.radians(step / 2.0), math.radians(start)

    def linkage_valid(self, state: ValveState, key: tuple) -> bool:
        probe = self.linkage(state, key, (-HALF_TURN_DEG, WINDOW_PROBE_DEG, HALF_TURN_DEG))
        return probe.status == rocker.ROCKER_OK

    # --- stages ---------------------------------------------------------------------------
    def stage_dynamics(self, state: ValveState) -> None:
        """The lumped rung [V2] per linkage group (:meth:`run_group`); under
        ``spring_model = "multi_mass"`` the ``surge`` stage runs instead (:meth:`stages_to_run`)."""
        n = state.n
        state.out = np.full((n, N_OUT), np.nan)
        state.step_used = np.full(n, np.nan)
        want = any(c in CURVE_ROWS for c in state.curves)
        axis = self.curve_coordinate(state.settings)
        state.traces = np.full((n, N_CURVES, axis.size if want else 0), np.nan)
        names = ("error_estimate", "tolerance_met", *DERIVED_BARS, *BUDGET_RESPONSES)
        state.bars = {name: np.full(n, np.nan) for name in names}
        state.method = np.full(n, float(INTEGRATORS.index(state.settings["integrator"])))
        state.per_step = np.full(n, dopri_tolerance(state.settings["tolerance"]))
        for key, idx in state.groups.items():
            if not self.linkage_valid(state, key):
                state.out[idx, valve.O_STATUS] = STATUS_NOT_RUN
                continue
            self.run_group(state, key, idx, want)

    def run_group(self, state: ValveState, key: tuple, idx: np.ndarray, want: bool) -> None:
        """Integrate the points ``idx`` of one linkage; with error bars or a tolerance, down the
        halving ladder of :mod:`studies.scenes.valve.error_bar`.

        Under a tolerance the method is picked per point too
        (:func:`~studies.scenes.valve.error_bar.tolerance_rungs`).
        """
        settings = state.settings
        tolerance = settings["tolerance"]
        integrator = settings["integrator"]
        rows = valve_rows(state.points, idx)
        coarse = step_deg(settings["angle_step"])
        if tolerance <= 0.0 and not BAR_RESPONSES.intersection(state.responses):
            if integrator == DOPRI:
                out, trace = self.dopri_run(state, key, rows, coarse, want)
            else:
                flags = kernel_settings(settings, integrator, False)
                excitation = self.excitation(state, key, coarse)
                out, trace = integrate(excitation, rows, integrator, flags, want)
            state.out[idx] = out
            state.step_used[idx] = coarse
            if trace is not None:
                self.store_traces(state, key, idx, trace, coarse, 0)
            return
        rungs = tolerance_rungs(
            lambda step, unclipped: self.excitation(state, key, step, unclipped=unclipped),
            rows,
            lambda method: kernel_settings(settings, method, False),
            integrator,
            coarse,
            tolerance,
            not BUDGET_RESPONSES.isdisjoint(state.responses),
            not DERIVED_BARS.keys().isdisjoint(state.responses),
        )
        for pending, method, ladder in rungs:
            at = idx[pending]
            state.out[at] = ladder.out
            state.step_used[at] = coarse / 2.0**ladder.level
            state.method[at] = INTEGRATORS.index(method)
            state.per_step[at] = ladder.per_step
            state.bars["error_estimate"][at] = ladder.bar
            state.bars["tolerance_met"][at] = ladder.met
            for name, values in (ladder.derived | ladder.budget).items():
                state.bars[name][at] = values
            if want:
                self.ladder_curves(state, key, at, rows[pending], ladder, coarse, method)

    def ladder_curves(
        self,
        state: ValveState,
        key: tuple,
        idx: np.ndarray,
        rows: np.ndarray,
        ladder: Ladder,
        coarse: float,
        integrator: str,
    ) -> None:
        """Curves of each point at the level the ladder stopped at (its sub-step count)."""
        if integrator == DOPRI:
            trace = self.dopri_run(state, key, rows, coarse, True, ladder.per_step)[1]
            assert trace is not None
            self.store_traces(state, key, idx, trace, coarse, 0)
            return
        pairs = np.stack([ladder.level, ladder.substeps], axis=1)
        for level, count in np.unique(pairs, axis=0):
            members = np.flatnonzero((pairs == (level, count)).all(axis=1))
            step = coarse / 2.0**level
            flags = kernel_settings(state.settings, integrator, False, int(count))
            trace = integrate(
                self.excitation(state, key, step), rows[members], integrator, flags, True
            )[1]
            assert trace is not None
            self.store_traces(state, key, idx[members], trace, coarse, int(level))

    def dopri_run(
        self,
        state: ValveState,
        key: tuple,
        rows: np.ndarray,
        grid_deg: float,
        curves: bool,
        per_step: float | None = None,
    ) -> tuple[np.ndarray, np.ndarray | None]:
        """``dopri`` on its own excitation table (``dopri_table_deg``), reported on the
        grid every ``grid_deg`` [deg], at the per-step tolerance of the study's tolerance or
        ``per_step`` [m] (a tighter rung's, :attr:`Ladder.per_step`)."""
        tolerance = state.settings["tolerance"]
        excitation = self.excitation(state, key, 2.0 * dopri_table_deg(tolerance), unclipped=True)
        atol = dopri_tolerance(tolerance) if per_step is None else per_step
        return integrate_dopri(excitation, rows, grid_deg, atol, curves)

    def store_traces(
        self,
        state: ValveState,
        key: tuple,
        idx: np.ndarray,
        trace: np.ndarray,
        coarse: float,
        level: int,
    ) -> None:
        """Curves at step coarse/2^level into the study's curve axis (the coarse grid)."""
        first = round((self.window(state, key)[0] + HALF_TURN_DEG) / coarse)
        kept = trace[:, :, :: 2**level]
        state.traces[idx, :, first : first + kept.shape[2]] = kept

    def stage_surge(self, state: ValveState) -> None:
        """The multi-mass spring [V4] (:func:`studies.scenes.valve.spring.surge_stage`)."""
        spring.surge_stage(self, state)

    def spring_rows(self, state: ValveState, idx: np.ndarray) -> np.ndarray:
        masses = int(state.settings["spring_masses"])
        return spring.chain_rows(valve_rows(state.points, idx), state.points, idx, masses)

    def stage_jump_speed(self, state: ValveState) -> None:
        settings = state.settings
        state.jump = np.full((state.n, 2), np.nan)
        chained = spring.uses_chain(settings)
        for key, idx in state.groups.items():
            if not self.linkage_valid(state, key):
                state.jump[idx, 1] = JUMP_NOT_RUN
            elif settings["integrator"] == DOPRI and not chained:  # the search honours dopri
                table_deg = 2 * dopri_table_deg(settings["tolerance"])
                table = self.excitation(state, key, table_deg, unclipped=True)
                state.jump[idx] = dopri_jump_speeds(table, valve_rows(state.points, idx), settings)
            else:
                table = self.excitation(state, key, step_deg(settings["angle_step"]))
                rows = self.spring_rows(state, idx) if chained else valve_rows(state.points, idx)
                state.jump[idx] = rk4_jump_speeds(table, rows, settings, chained)

    # --- outputs --------------------------------------------------------------------------
    def scalar(self, state: ValveState, response: str) -> np.ndarray:
        if response in KINEMATIC_RESPONSES:
            return super().scalar(state, response)
        if response in ("jump_speed", "jump_speed_status"):
            jump = state.jump
            return jump[:, 0] * RPM if response == "jump_speed" else jump[:, 1]
        if response == "surge_frequency":
            return spring.surge_frequency(state.points, int(state.settings["spring_masses"]))
        if response in spring.SURGE_OUTPUT:
            column, scale = spring.SURGE_OUTPUT[response]
            return state.chain_out[:, column] * scale
        out = state.out
        if response in OUTPUT_COLUMNS:
            column, scale = OUTPUT_COLUMNS[response]
            return out[:, column] * scale
        status = out[:, valve.O_STATUS]
        if response == "run_ok":
            return (status == valve.STATUS_OK).astype(float)
        if response == "follows_cam":
            duration = out[:, valve.O_JUMP_DURATION]
            return np.where(np.isnan(duration), np.nan, (duration == 0.0).astype(float))
        if response == "angle_step_used":
            return state.step_used.copy()
        if response == "integrator_used":
            return state.method.copy()
        bars = state.bars
        if response == "step_halving_difference":
            return bars["error_estimate"] / BAR_FACTOR * MM
        if response == "error_estimate":
            return bars["error_estimate"] * MM
        if response in BAR_SCALE:
            return bars[response] * BAR_SCALE[response]
        if state.settings["tolerance"] > 0.0:
            return bars["tolerance_met"].copy()
        return np.ones(state.n)

    def curve_values(self, state: ValveState, name: str) -> np.ndarray:
        if name in spring.SURGE_CURVE_NAMES or (
            name in spring.CHAIN_CURVE_ROW and spring.uses_chain(state.settings)
        ):
            row, scale = spring.CHAIN_CURVE_ROW[name]
            return state.chain_traces[:, row, :] * scale
        if name not in CURVE_ROWS:
            return super().curve_values(state, name)
        row, scale = CURVE_ROWS[name]
        return state.traces[:, row, :] * scale
