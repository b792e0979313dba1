"""The ``crank`` scene: slider-crank kinematics, forces and multi-cylinder torque (physics §5).

Stages (each one compiled batch driver; a study runs only those its responses and curves need):

* ``kinematics`` — :func:`engine_kernels.crank.kinematics.crank_kinematics_batch`: piston and rod motion
  and the error of the two-term approximation (always measured against the exact relations);
* ``pressure`` — cylinder pressure on the cycle grid: the single-zone Wiebe cycle
  (:func:`engine_kernels.crank.combustion.cycle_pressure_batch`) or a measured table
  (:mod:`studies.scenes.crank.pressure_tables`);
* ``forces`` — :func:`engine_kernels.crank.forces.crank_forces_batch`: gas, inertia, rod, side,
  tangential and radial forces and the torque of one cylinder;
* ``multicylinder`` — :func:`engine_kernels.crank.multicylinder.crank_multicylinder_batch`: summed
  torque of the layout, its harmonic orders and the free first- and second-order forces and
  (inline layouts) moments.

The kinematics model (``exact`` or two-term ``approximate``) is a study setting; it sets the
piston motion used for the inertia forces, the torque and the kinematic curves.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from engine_kernels.crank import combustion as cb
from engine_kernels.crank import forces as cf
from engine_kernels.crank import kinematics as ck
from engine_kernels.crank import multicylinder as cl
from studies.common.units import UNITS
from studies.scenes.base import Scene, SceneOutput
from studies.scenes.checks import PointProblems, on_distinct
from studies.scenes.crank import work
from studies.scenes.crank.checks import (
    CHECKED_NAMES,
    CYCLE_NAMES,
    LAYOUT_NAMES,
    cycle_problems,
    layout_problems,
)
from studies.scenes.crank.parameters import MAX_ORDER_HALVES, PARAMETERS, SETTINGS
from studies.scenes.crank.pressure_tables import read_pressure_table, resample_pressure
from studies.scenes.crank.responses import CRANK_ANGLE, CURVES, RESPONSES, order_name
from studies.scenes.state import RunState

if TYPE_CHECKING:
    from studies.scenes.base import FigureBuilder

CYCLE_DEG = 720.0
MODEL_CODES = {"exact": ck.MODEL_EXACT, "approximate": ck.MODEL_TWO_TERM}
HEAT_CODES = {"max_pressure": cb.HEAT_MODE_PEAK_PRESSURE, "cycle_heat": cb.HEAT_MODE_ENERGY}
FORCE_NAMES = {
    "mean_torque": "cylinder_mean_torque",
    "max_torque": "cylinder_max_torque",
    "min_torque": "cylinder_min_torque",
    "torque": "cylinder_torque",
}
CYCLE_ONLY = ("compression_pressure", "heat_released", "cycle_work", "imep")


def angle_count(angle_step: float) -> int:
    """Grid points over the 720° cycle for a step [rad] (the step must divide 720°)."""
    return round(ck.CYCLE_ANGLE / angle_step)


def crank_params(points: dict[str, np.ndarray], model: str) -> np.ndarray:
    """The kernel parameter matrix params[n, N_PARAMS] (SI) of these design points."""
    n = len(points["stroke"])
    params = np.empty((n, ck.N_PARAMS))
    params[:, ck.CRANK_RADIUS] = 0.5 * points["stroke"]
    params[:, ck.ROD_RATIO] = points["rod_ratio"]
    params[:, ck.ANGULAR_SPEED] = points["engine_speed"]
    params[:, ck.BORE] = points["bore"]
    params[:, ck.RECIPROCATING_MASS] = points["reciprocating_mass"]
    params[:, ck.ROTATING_MASS] = points["rotating_mass"]
    params[:, ck.CRANKCASE_PRESSURE] = points["crankcase_pressure"]
    params[:, ck.KINEMATICS_MODEL] = MODEL_CODES[model]
    params[:, ck.CYLINDERS] = points["cylinders"]
    return params


def cycle_params(points: dict[str, np.ndarray]) -> np.ndarray:
    """The single-zone cycle parameter matrix (SI) of these design points."""
    n = len(points["stroke"])
    params = np.empty((n, cb.N_PARAMS))
    params[:, cb.BORE] = points["bore"]
    params[:, cb.CRANK_RADIUS] = 0.5 * points["stroke"]
    params[:, cb.ROD_RATIO] = points["rod_ratio"]
    params[:, cb.COMPRESSION_RATIO] = points["compression_ratio"]
    params[:, cb.INTAKE_PRESSURE] = points["intake_pressure"]
    params[:, cb.EXHAUST_PRESSURE] = points["exhaust_pressure"]
    params[:, cb.POLYTROPIC_EXPONENT] = points["polytropic_exponent"]
    params[:, cb.COMBUSTION_START] = points["combustion_start"]
    params[:, cb.COMBUSTION_DURATION] = points["combustion_duration"]
    params[:, cb.WIEBE_EFFICIENCY] = points["wiebe_efficiency"]
    params[:, cb.WIEBE_FORM] = points["wiebe_form"]
    params[:, cb.HEAT_INPUT_MODE] = [HEAT_CODES[h] for h in points["heat_input"]]
    params[:, cb.HEAT_RELEASED] = points["cycle_heat"]
    params[:, cb.PEAK_PRESSURE_TARGET] = points["max_pressure"]
    return params


def layout_geometry(points: dict[str, np.ndarray]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Firing and cylinder-axis angles [rad] and axial positions [m] per design point, each
    (n, z_max). Positions are ``cylinder_positions`` where given; otherwise inline cylinder c
    sits at (c − 1)·cylinder_pitch, and a V layout (two banks, whose order along the shaft the
    firing order does not fix) gets NaN positions, so its moments are NaN."""
    z = points["cylinders"].astype(int)
    n, z_max = len(z), int(z.max())
    firing = np.zeros((n, z_max))
    axis = np.zeros((n, z_max))
    positions = np.full((n, z_max), np.nan)
    orders = points["firing_order"].astype(np.int64)
    for i in range(n):
        order = np.ascontiguousarray(orders[i])
        gamma = float(points["bank_angle"][i])
        kind = points["firing"][i]
        if kind == "given":
            firing[i, : z[i]] = points["firing_angles"][i, : z[i]]
        elif kind == "shared_crankpins":
            cl.v_crank_firing_angles(order, gamma, firing[i])
        else:
            cl.even_firing_angles(order, firing[i])
        if points["layout"][i] == "v":
            cl.v_axis_angles(order, gamma, axis[i])
        given = points["cylinder_positions"][i]
        if given.size:
            positions[i, : z[i]] = given[: z[i]]
        elif points["layout"][i] == "inline":
            positions[i] = np.arange(z_max) * points["cylinder_pitch"][i]
    return firing, axis, positions


def _empty_curves(n: int, count: int, store: bool, m: int) -> np.ndarray:
    return np.empty((n, count, m if store else 0))


@dataclass(slots=True)
class CrankState(RunState):
    """Run state of a ``crank`` chunk; each stage adds its named responses and curves (SI)."""

    params: np.ndarray = field(init=False)  # kernel parameters (n, ck.N_PARAMS), SI
    n_angles: int = field(init=False)  # grid points over the 720° cycle
    stored: frozenset[str] = field(init=False)  # stages that produce a requested curve
    pressure: np.ndarray = field(init=False)  # cylinder pressure (n, n_angles) [Pa]
    scalars: dict[str, np.ndarray] = field(init=False, default_factory=dict)  # per point, SI
    curves_si: dict[str, np.ndarray] = field(init=False, default_factory=dict)  # (n, n_angles)


class CrankScene(Scene[CrankState]):
    """Slider-crank and multi-cylinder engine (physics §5)."""

    name = "crank"
    seconds_per_point = 2e-3
    work_estimate = staticmethod(work.work_estimate)  # type: ignore[assignment]
    description = (
        "slider-crank kinematics (exact and two-term), gas and inertia forces, torque, "
        "multi-cylinder torque harmonics, free forces and moments (physics §5)"
    )
    parameters = PARAMETERS
    settings = SETTINGS
    responses = RESPONSES
    curves = CURVES
    curve_axis = CRANK_ANGLE
    stage_order = ("kinematics", "pressure", "forces", "multicylinder")
    state_type = CrankState

    # --- outputs beside the generic ones -----------------------------------------------------
    def figures(self) -> dict[str, FigureBuilder]:
        from studies.scenes.crank.figures import (  # noqa: PLC0415  (matplotlib on use)
            approximation_error_figure,
            torque_curve_figure,
            torque_harmonics_figure,
        )

        return {
            "torque_curve": torque_curve_figure,
            "torque_harmonics": torque_harmonics_figure,
            "approximation_error": approximation_error_figure,
        }

    def curve_coordinate(self, settings: dict[str, Any]) -> np.ndarray:
        m = angle_count(settings["angle_step"])
        return CYCLE_DEG * np.arange(m) / m

    # --- checks --------------------------------------------------------------------------
    def check_points(self, points: Mapping[str, np.ndarray], settings: dict[str, Any]) -> list[str]:
        problems: list[str] = []
        step_deg = math.degrees(settings["angle_step"])
        if not math.isclose(CYCLE_DEG / step_deg, round(CYCLE_DEG / step_deg), abs_tol=1e-9):
            problems.append(
                f"setting angle_step = {step_deg:g} deg must divide 720 deg (a "
                "whole number of grid points per cycle)"
            )
        return problems + on_distinct(points, CHECKED_NAMES, self._distinct_problems)

    def _distinct_problems(self, points: dict[str, np.ndarray]) -> list[str]:
        found = PointProblems()
        lam = np.asarray(points["rod_ratio"])
        found.add_grouped(
            np.flatnonzero(lam >= 1.0),
            [lam],
            lambda i: (
                f"rod_ratio λ = r/l = {lam[i]:g} must be < 1 (the connecting rod "
                "must be longer than the crank radius)"
            ),
        )
        columns = [points[name] for name in LAYOUT_NAMES]
        found.add_checked(np.arange(lam.size), columns, lambda i: layout_problems(points, i))
        self._check_pressure(points, found)
        return found.messages()

    def _check_pressure(self, points: Mapping[str, np.ndarray], found: PointProblems) -> None:
        table = np.flatnonzero(points["pressure_model"] == "table")
        if table.size:
            try:
                read_pressure_table(points["pressure_table"][table[0]])
            except ValueError as exc:
                found.add_all(table, str(exc))
        cycle = np.flatnonzero(points["pressure_model"] == "cycle")
        columns = [points[name] for name in CYCLE_NAMES]
        found.add_checked(cycle, columns, lambda i: cycle_problems(points, i))

    # --- stages --------------------------------------------------------------------------
    def prepare(self, state: CrankState) -> None:
        state.n_angles = angle_count(state.settings["angle_step"])
        state.params = crank_params(state.points, state.settings["model"])
        # a curve's last stage is the one that produces it
        state.stored = frozenset(self.curve(c).needs[-1] for c in state.curves)  # type: ignore[union-attr]

    def stage_kinematics(self, state: CrankState) -> None:
        params, n_angles = state.params, state.n_angles
        out = np.empty((state.n, ck.N_KINEMATICS_OUT))
        curves = _empty_curves(
            state.n, ck.N_KINEMATICS_CURVES, "kinematics" in state.stored, n_angles
        )
        ck.crank_kinematics_batch(params, n_angles, out, curves)
        scalars = dict(zip(ck.KINEMATICS_OUTPUTS, out.T, strict=True))
        r = params[:, ck.CRANK_RADIUS]
        omega = params[:, ck.ANGULAR_SPEED]
        scalars["approx_error_displacement_relative"] = scalars["approx_error_displacement"] / r
        scalars["approx_error_velocity_relative"] = scalars["approx_error_velocity"] / (r * omega)
        scalars["approx_error_acceleration_relative"] = scalars["approx_error_acceleration"] / (
            r * omega**2
        )
        state.scalars |= scalars
        state.curves_si |= dict(zip(ck.KINEMATICS_CURVES, curves.transpose(1, 0, 2), strict=True))

    def stage_pressure(self, state: CrankState) -> None:
        points, n, n_angles = state.points, state.n, state.n_angles
        pressure = np.empty((n, n_angles))
        values = np.full((n, cb.N_OUT), np.nan)
        cycle = points["pressure_model"] == "cycle"
        if cycle.any():
            out = np.empty((int(cycle.sum()), cb.N_OUT))
            part = np.empty((out.shape[0], n_angles))
            cb.cycle_pressure_batch(cycle_params(points)[cycle], out, part)
            pressure[cycle], values[cycle] = part, out
        if not cycle.all():
            angle, table = read_pressure_table(points["pressure_table"][~cycle][0])
            grid = resample_pressure(angle, table, n_angles)
            peak = int(np.argmax(grid))
            pressure[~cycle] = grid
            values[~cycle, cb.OUT_PEAK_PRESSURE] = grid[peak]
            values[~cycle, cb.OUT_PEAK_PRESSURE_ANGLE] = (
                ck.CYCLE_ANGLE * peak / n_angles - 2.0 * math.pi
            )
        scalars = dict(zip(cb.OUTPUTS, values.T, strict=True))
        for name in CYCLE_ONLY:
            scalars[name] = np.where(cycle, scalars[name], np.nan)
        state.scalars |= scalars
        state.pressure = state.curves_si["cylinder_pressure"] = pressure

    def stage_forces(self, state: CrankState) -> None:
        n, m = state.pressure.shape
        out = np.empty((n, cf.N_FORCE_OUT))
        curves = _empty_curves(n, cf.N_FORCE_CURVES, "forces" in state.stored, m)
        cf.crank_forces_batch(state.params, state.pressure, out, curves)
        state.scalars |= {
            FORCE_NAMES.get(k, k): v for k, v in zip(cf.FORCE_OUTPUTS, out.T, strict=True)
        }
        state.curves_si |= {
            FORCE_NAMES.get(k, k): v
            for k, v in zip(cf.FORCE_CURVES, curves.transpose(1, 0, 2), strict=True)
        }

    def stage_multicylinder(self, state: CrankState) -> None:
        n, m = state.pressure.shape
        firing, axis, positions = layout_geometry(state.points)
        out = np.empty((n, cl.N_MULTI_OUT))
        harmonics = np.empty((n, MAX_ORDER_HALVES))
        curves = _empty_curves(n, 1, "multicylinder" in state.stored, m)
        cl.crank_multicylinder_batch(
            state.params, state.pressure, firing, axis, positions, out, harmonics, curves
        )
        scalars = dict(zip(cl.MULTI_OUTPUTS, out.T, strict=True))
        for q in range(MAX_ORDER_HALVES):
            scalars[order_name(q + 1)] = harmonics[:, q]
        scalars["dominant_torque_order"] = (np.argmax(harmonics, axis=1) + 1) / 2.0
        scalars["dominant_torque_amplitude"] = harmonics.max(axis=1)
        state.scalars |= scalars
        state.curves_si["engine_torque"] = curves[:, 0]

    # --- outputs -------------------------------------------------------------------------
    def finish(self, state: CrankState) -> SceneOutput:
        return SceneOutput(
            scalars={r: state.scalars[r] / self._scale(r) for r in state.responses},
            curves={c: state.curves_si[c] / self._scale(c) for c in state.curves},
        )

    def _scale(self, name: str) -> float:
        """SI value of one unit of the response or curve ``name``."""
        declared = self.response(name) or self.curve(name)
        assert declared is not None
        return UNITS[declared.units].to_si
