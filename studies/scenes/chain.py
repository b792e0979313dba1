"""Scene ``rocker``: OHC cam with a variable-ratio rocker, valve kinematics (physics §3).

Two stages, each a compiled kernel:

* ``tappet`` — :func:`engine_kernels.cam.kinematics.cam_kinematics_batch`: the flat-tappet lift law
  h, h', h'' on a tappet-angle grid (a standard rise law, a polydyne, or the six-segment
  profile), scaled so that the chain gives the target valve lift at the nose
  (:func:`engine_kernels.valvetrain.rocker.tappet_lift_for_valve_lift`);
* ``rocker`` — :func:`engine_kernels.valvetrain.rocker.rocker_valve_lift`: the chain [R1]–[R6], valve
  lift Y and its derivatives, force ratio and rocker angle on a cam-angle grid.

Design points that share the cam and rocker parameters share one chain: both stages work per
distinct parameter set and keep their tables in a bounded cache on the scene, so a study that
varies only speeds or springs computes the kinematics once. A cam that is not convex, or a
chain that does not close, is a per-point result (``chain_status``, ``cam_convex``), never an
exception; impossible geometry is refused by :meth:`ChainScene.check_points` before anything
runs.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Hashable
from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd

from engine_kernels.cam import multi_segment
from engine_kernels.valvetrain import rocker
from studies.scenes.base import CurveAxis, Scene, SceneOutput
from studies.scenes.cam_laws import SHAPE_CODES, polydyne_problems
from studies.scenes.chain_parameters import (
    CAM_ANGLE,
    CURVES,
    PARAMETERS,
    RESPONSES,
    SETTINGS,
)
from studies.scenes.chain_tappet import (
    HALF_TURN_DEG,
    TappetTable,
    concave_chains,
    geometry_row,
    grid_deg,
    nose_tappet_lift,
    step_deg,
    tappet_table,
)
from studies.scenes.checks import PointProblems

MM = 1e3
GRID_UNIT_DEG = 2.0
"""Every angle step must divide this, so grids of different steps share their nodes."""
MAX_EVENT_HALF_DEG = 150.0
"""Largest event half-width (rise + ramp) that leaves room for the closing window."""
CACHE_SIZE = 64
SIDES = {"ahead": rocker.PAD_AHEAD, "behind": rocker.PAD_BEHIND}
KEY_NAMES = tuple(p.name for p in PARAMETERS if p.kind != "vector")
"""Parameters that fix the chain (with the polydyne coefficients): the cache key."""

# response -> (row of the chain curves, reduction, factor to the response's units)
_CURVE_ROWS: dict[str, tuple[int, float]] = {
    "valve_lift": (rocker.ROW_VALVE_LIFT, MM),
    "valve_velocity": (rocker.ROW_VALVE_VELOCITY, MM),
    "valve_acceleration": (rocker.ROW_VALVE_ACCELERATION, MM),
    "force_ratio": (rocker.ROW_FORCE_RATIO, 1.0),
    "rocker_angle": (rocker.ROW_ROCKER_ANGLE, math.degrees(1.0)),
    "tappet_angle": (rocker.ROW_TAPPET_ANGLE, math.degrees(1.0)),
}


class BoundedCache:
    """A dict that forgets its oldest entries beyond ``size`` (tables shared across chunks)."""

    def __init__(self, size: int) -> None:
        self.size = size
        self.entries: dict[Hashable, Any] = {}

    def get(self, key: Hashable, make: Callable[[], Any]) -> Any:
        if key not in self.entries:
            if len(self.entries) >= self.size:
                self.entries.pop(next(iter(self.entries)))
            self.entries[key] = make()
        return self.entries[key]


@dataclass(frozen=True)
class ChainCurves:
    """The chain [R1]–[R6] of one parameter set on a cam-angle grid (``ROW_*`` rows, SI)."""

    theta_deg: np.ndarray
    curves: np.ndarray
    status: int


def chain_keys(points: dict[str, np.ndarray]) -> dict[tuple, np.ndarray]:
    """The design points of each distinct chain, keyed by the tuple of its chain parameters.

    Vectorised (hash factorisation, column by column, skipping the columns that hold one
    value): a 100 000-point study has few chains, and a Python loop over its points would cost
    more than integrating them.
    """
    coefficients = np.asarray(points["polydyne_coefficients"], dtype=float)
    columns = [*coefficients.T, *(np.asarray(points[name]) for name in KEY_NAMES)]
    group: np.ndarray | None = None
    for column in columns:
        if len(column) and bool((column == column[0]).all()):
            continue
        codes, uniques = pd.factorize(column)
        group = codes if group is None else pd.factorize(group * len(uniques) + codes)[0]
    if group is None:  # one chain for every point
        members = [np.arange(len(coefficients))]
    else:
        order = np.argsort(group, kind="stable")
        members = np.split(order, np.cumsum(np.bincount(group))[:-1])
    return {
        (*(points[name][idx[0]] for name in KEY_NAMES), tuple(coefficients[idx[0]].tolist())): idx
        for idx in members
    }


class ChainScene(Scene):
    name = "rocker"
    seconds_per_point = 2e-2
    description = "OHC cam with variable-ratio rocker: valve lift, force ratio (kinematics)"
    parameters = PARAMETERS
    settings = SETTINGS
    responses = RESPONSES
    curves = CURVES
    curve_axis: CurveAxis | None = CAM_ANGLE
    stage_order: tuple[str, ...] = ("tappet", "rocker")
    status_responses: tuple[str, ...] = ("chain_status",)

    def __init__(self) -> None:
        super().__init__()
        self.tappet_cache = BoundedCache(CACHE_SIZE)
        self.chain_cache = BoundedCache(CACHE_SIZE)

    def curve_coordinate(self, settings: dict[str, Any]) -> np.ndarray:
        step = step_deg(settings["angle_step"])
        return grid_deg(-HALF_TURN_DEG, step, HALF_TURN_DEG)

    # --- checks ---------------------------------------------------------------------------
    def check_points(self, points: dict[str, np.ndarray], settings: dict[str, Any]) -> list[str]:
        problem = angle_step_problem(settings["angle_step"], "setting angle_step")
        return ([problem] if problem else []) + self.chain_point_problems(points)

    def point_warnings(self, points: dict[str, np.ndarray], settings: dict[str, Any]) -> list[str]:
        """The chains whose cam is concave: their points will not run (a result, not an error)."""
        return concave_chains(points, chain_keys(points))

    def chain_point_problems(self, points: dict[str, np.ndarray]) -> list[str]:
        """Input errors of the cam laws and rocker geometries, grouped by design points."""
        found = PointProblems()
        groups = chain_keys(points)
        for idx in groups.values():
            for problem in chain_problems(points, int(idx[0])):
                found.add_all(idx.tolist(), problem)
        return found.messages()

    # --- evaluation -----------------------------------------------------------------------
    def context(
        self,
        points: dict[str, np.ndarray],
        settings: dict[str, Any],
        responses: list[str],
        curves: list[str],
    ) -> dict[str, Any]:
        """What the stages share: the points, their chain keys and groups, the requests."""
        groups = chain_keys(points)
        return {
            "points": points,
            "settings": settings,
            "groups": groups,
            "responses": set(responses),
            "curves": set(curves),
            "n": len(points["polydyne_coefficients"]),
        }

    def evaluate(
        self,
        points: dict[str, np.ndarray],
        settings: dict[str, Any],
        responses: list[str],
        curves: list[str],
    ) -> SceneOutput:
        ctx = self.context(points, settings, responses, curves)
        self.run_stages(ctx, responses, curves)
        return SceneOutput(
            {r: self.scalar(ctx, r) for r in responses},
            {c: self.curve_values(ctx, c) for c in curves},
        )

    def kinematic_grid(self, settings: dict[str, Any]) -> tuple[float, float, float]:
        """(start, spacing, stop) [deg] of the grid of kinematic responses and curves."""
        return -HALF_TURN_DEG, step_deg(settings["angle_step"]), HALF_TURN_DEG

    def tappet_table(self, ctx: dict[str, Any], key: tuple) -> TappetTable:
        """The flat-tappet law of the chain ``key`` (cached per key and tappet step)."""
        spacing = step_deg(ctx["settings"]["tappet_step"])
        i = int(ctx["groups"][key][0])
        return self.tappet_cache.get(
            (key, spacing), lambda: tappet_table(ctx["points"], i, spacing)
        )

    def chain(
        self, ctx: dict[str, Any], key: tuple, grid: tuple[float, float, float]
    ) -> ChainCurves:
        """The chain [R1]–[R6] of ``key`` on the cam-angle grid (start, spacing, stop) [deg]."""
        table = self.tappet_table(ctx, key)
        i = int(ctx["groups"][key][0])
        spacing = step_deg(ctx["settings"]["tappet_step"])
        return self.chain_cache.get(
            (key, spacing, grid), lambda: _chain_curves(ctx["points"], i, table, grid)
        )

    def stage_tappet(self, ctx: dict[str, Any]) -> None:
        ctx["tappet"] = {key: self.tappet_table(ctx, key) for key in ctx["groups"]}

    def stage_rocker(self, ctx: dict[str, Any]) -> None:
        grid = self.kinematic_grid(ctx["settings"])
        ctx["chain"] = {key: self.chain(ctx, key, grid) for key in ctx["groups"]}

    # --- outputs --------------------------------------------------------------------------
    def scalar(self, ctx: dict[str, Any], response: str) -> np.ndarray:
        """Values of a kinematic response per design point (response units)."""
        out = np.empty(ctx["n"])
        for key, idx in ctx["groups"].items():
            out[idx] = _kinematic_value(response, ctx, key)
        return out

    def curve_values(self, ctx: dict[str, Any], name: str) -> np.ndarray:
        """A kinematic curve per design point on the curve axis (curve units)."""
        axis = self.curve_coordinate(ctx["settings"])
        out = np.empty((ctx["n"], axis.size))
        for key, idx in ctx["groups"].items():
            if name == "tappet_lift":
                table = ctx["tappet"][key]
                values = np.interp(np.radians(axis), table.phi, table.curves[0]) * MM
            else:
                row, scale = _CURVE_ROWS[name]
                values = ctx["chain"][key].curves[row] * scale
            out[idx] = values
        return out


def _chain_curves(
    points: dict[str, np.ndarray], i: int, table: TappetTable, grid: tuple[float, float, float]
) -> ChainCurves:
    theta_deg = grid_deg(*grid)
    out = np.empty((len(rocker.ROCKER_CURVE_NAMES), theta_deg.size))
    status = rocker.rocker_valve_lift(
        table.phi,
        table.curves[0],
        table.curves[1],
        table.curves[2],
        geometry_row(points, i),
        SIDES[str(points["pad_side"][i])],
        np.radians(theta_deg),
        out,
    )
    return ChainCurves(theta_deg, out, int(status))


def open_range(chain: ChainCurves) -> tuple[float, float]:
    """Cam angles [deg] of the first and last grid points with the valve open (NaN if none)."""
    open_idx = np.flatnonzero(chain.curves[rocker.ROW_VALVE_LIFT] > 0.0)
    if open_idx.size == 0:
        return math.nan, math.nan
    return float(chain.theta_deg[open_idx[0]]), float(chain.theta_deg[open_idx[-1]])


def _kinematic_value(response: str, ctx: dict[str, Any], key: tuple) -> float:
    if response in ("max_tappet_lift", "min_radius_of_curvature", "cam_convex"):
        table = ctx["tappet"][key]
        if response == "cam_convex":
            return float(table.min_radius > 0.0)
        return (table.nose_lift if response == "max_tappet_lift" else table.min_radius) * MM
    chain = ctx["chain"][key]
    c = chain.curves
    lift = c[rocker.ROW_VALVE_LIFT]
    is_open = lift > 0.0
    opening, closing = open_range(chain)
    values: dict[str, Callable[[], float]] = {
        "max_valve_lift": lambda: lift.max() * MM,
        "max_valve_velocity": lambda: c[rocker.ROW_VALVE_VELOCITY].max() * MM,
        "min_valve_velocity": lambda: c[rocker.ROW_VALVE_VELOCITY].min() * MM,
        "max_valve_acceleration": lambda: c[rocker.ROW_VALVE_ACCELERATION].max() * MM,
        "min_valve_acceleration": lambda: c[rocker.ROW_VALVE_ACCELERATION].min() * MM,
        "valve_opening_angle": lambda: opening,
        "valve_closing_angle": lambda: closing,
        "valve_open_duration": lambda: closing - opening,
        "lift_ratio": lambda: lift.max() / ctx["tappet"][key].nose_lift,
        "force_ratio_nose": lambda: float(
            np.interp(0.0, chain.theta_deg, c[rocker.ROW_FORCE_RATIO])
        ),
        "max_force_ratio": lambda: _masked(c[rocker.ROW_FORCE_RATIO], is_open, np.max),
        "min_force_ratio": lambda: _masked(c[rocker.ROW_FORCE_RATIO], is_open, np.min),
        "rocker_swing": lambda: math.degrees(np.ptp(c[rocker.ROW_ROCKER_ANGLE])),
        "chain_status": lambda: float(chain.status),
        "chain_ok": lambda: float(chain.status == rocker.ROCKER_OK),
    }
    return float(values[response]())


def _masked(values: np.ndarray, mask: np.ndarray, reduce: Callable[[np.ndarray], Any]) -> float:
    return float(reduce(values[mask])) if mask.any() else math.nan


# --- checks ---------------------------------------------------------------------------------
def angle_step_problem(step_rad: float, what: str) -> str | None:
    """Why an angle step [rad] cannot be used (it must divide GRID_UNIT_DEG), or None."""
    step = step_deg(step_rad)
    ratio = GRID_UNIT_DEG / step
    if abs(ratio - round(ratio)) <= 1e-6:
        return None
    return (
        f"{what} = {step:g} deg is not allowed: it must divide {GRID_UNIT_DEG:g} deg (e.g. 1, "
        "0.5, 0.25, 0.2, 0.125, 0.1) so that grids of different steps share their nodes"
    )


def chain_problems(points: dict[str, np.ndarray], i: int) -> list[str]:
    """Input errors of one design point's cam law and rocker geometry (mm and deg shown)."""
    p = {name: points[name][i] for name in KEY_NAMES}
    out = _geometry_problems(p)
    if not out:
        nose = nose_tappet_lift(points, i)
        out += _nose_problems(p, nose)
    law = str(p["law"])
    half = p["rise_angle"]
    if law == "six_segment":
        out += _six_segment_problems(points, i)
        if p["ramp_height"] > 0.0:
            half += p["ramp_width"]
    if law == "polydyne":
        out += polydyne_problems(np.asarray(points["polydyne_coefficients"][i], dtype=float))
    if math.degrees(half) > MAX_EVENT_HALF_DEG:
        out.append(
            f"the event half-width rise_angle + ramp_width = {math.degrees(half):g} deg exceeds "
            f"{MAX_EVENT_HALF_DEG:g} deg: the valve event and its closing window must fit in one "
            "camshaft turn"
        )
    return out


def _geometry_problems(p: dict[str, Any]) -> list[str]:
    out = []
    arm = p["lash"] + p["ball_radius"] + p["stem_height"]
    if not abs(arm) < p["valve_arm"]:
        out.append(
            f"lash + ball_radius + stem_height = {arm * MM:g} mm must be smaller in size than "
            f"valve_arm = {p['valve_arm'] * MM:g} mm: β0 = asin((Δ + ρb + z)/lb) [R6]"
        )
    reach = p["base_radius"] + p["pad_radius"]
    low, high = abs(p["pad_arm"] - p["centre_distance"]), p["pad_arm"] + p["centre_distance"]
    if not low < reach < high:
        out.append(
            f"base_radius + pad_radius = {reach * MM:g} mm must lie between |pad_arm − "
            f"centre_distance| = {low * MM:g} mm and pad_arm + centre_distance = {high * MM:g} mm "
            "for the rocker triangle O–Oc–A to close on the base circle [R3], [R5]"
        )
    return out


def _nose_problems(p: dict[str, Any], nose: float) -> list[str]:
    reach = p["base_radius"] + p["pad_radius"] + nose
    high = p["pad_arm"] + p["centre_distance"]
    if not (math.isfinite(nose) and nose > 0.0 and reach < high):
        return [
            (
                f"valve_lift = {p['valve_lift'] * MM:g} mm is out of reach of this rocker: the "
                "valve arm or the triangle O–Oc–A at the nose cannot close [R3], [R6] (use a "
                "smaller valve_lift or a longer valve_arm)"
            )
        ]
    if str(p["law"]) == "six_segment" and p["ramp_height"] >= nose:
        return [
            (
                f"ramp_height = {p['ramp_height'] * MM:g} mm must be below the tappet nose lift "
                f"{nose * MM:.4g} mm that valve_lift = {p['valve_lift'] * MM:g} mm needs"
            )
        ]
    return []


def _six_segment_problems(points: dict[str, np.ndarray], i: int) -> list[str]:
    out = []
    widths = np.array([points[f"seg{k}_width"][i] for k in range(1, 7)], dtype=float)
    shapes = np.array([SHAPE_CODES[points[f"seg{k}_shape"][i]] for k in range(1, 7)])
    half = float(points["rise_angle"][i])
    adjusted = np.empty(6)
    if not multi_segment.segment_widths(widths, shapes, half, adjusted):
        out.append(
            f"segment widths {np.round(np.degrees(widths), 3).tolist()} deg cannot be fitted to "
            f"the rise_angle = {math.degrees(half):g} deg half-event: the fillet and segment 6 "
            f"would need widths {np.round(np.degrees(adjusted), 3).tolist()} deg (must be ≥ 0)"
        )
    height, width = float(points["ramp_height"][i]), float(points["ramp_width"][i])
    velocity = float(points["ramp_velocity"][i])
    if height > 0.0:
        if velocity <= 0.0 or width <= 0.0:
            out.append(
                f"ramp_height = {height * MM:g} mm needs ramp_width > 0 and ramp_velocity > 0"
            )
        elif not height / velocity <= width <= 2.0 * height / velocity:
            out.append(
                f"ramp_width = {math.degrees(width):g} deg cannot carry a {height * MM:g} mm ramp "
                f"ending at {velocity * MM:g} mm/rad: constant acceleration then constant "
                f"velocity needs {math.degrees(height / velocity):.4g} ≤ ramp_width ≤ "
                f"{math.degrees(2.0 * height / velocity):.4g} deg"
            )
    return out
