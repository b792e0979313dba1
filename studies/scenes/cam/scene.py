"""Scene ``cam``: flat-faced tappet cam kinematics and contact criteria (physics §2).

Three stages, each one compiled batch driver of :mod:`engine_kernels.cam.kinematics` and :mod:`engine_kernels.cam.loads`:

* ``kinematics`` — lift h and h', h'', h''' on the cam-angle grid (six-segment profile, a
  standard rise law, or a smoothed measured table) and the kinematic responses;
* ``geometry``   — radius of curvature, lubrication coefficient, entrainment, film ratio;
* ``loads``      — contact force, Hertz stress, spring margin, EHL film thickness.

A response runs only the stages it needs (``Response.needs``).
"""

from __future__ import annotations

from collections import defaultdict
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from engine_kernels.cam import kinematics as cb
from engine_kernels.cam import lift_laws, multi_segment
from engine_kernels.cam import loads as cam_loads
from studies.scenes.base import Scene, SceneOutput
from studies.scenes.cam import work
from studies.scenes.cam.lift_tables import read_lift_table, table_kinematics
from studies.scenes.cam.parameters import (
    CAM_ANGLE,
    CURVES,
    PARAMETERS,
    RESPONSES,
    SETTINGS,
)
from studies.scenes.cam_laws import (
    LAW_CODES,
    SHAPE_CODES,
    codes,
    drop_empty_ramps,
    fitted_widths,
    polydyne_problems,
)
from studies.scenes.cam_radius import HALF_TURN_DEG, turn_deg
from studies.scenes.checks import checked_groups, on_distinct, point_list
from studies.scenes.state import RunState

if TYPE_CHECKING:
    from studies.scenes.base import FigureBuilder, SceneBenchmark


# parameter name -> kernel column (all other kernel columns are named alike)
_COLUMN = {
    "law": cb.P_LAW,
    "cam_speed": cb.P_CAM_SPEED,
    "base_radius": cb.P_BASE_RADIUS,
    "lift": cb.P_LIFT,
    "rise_angle": cb.P_RISE_ANGLE,
    "ramp_height": cb.P_RAMP_HEIGHT,
    "ramp_width": cb.P_RAMP_WIDTH,
    "ramp_velocity": cb.P_RAMP_VELOCITY,
    "cam_width": cb.P_CAM_WIDTH,
    "cam_modulus": cb.P_E1,
    "cam_poisson": cb.P_NU1,
    "tappet_modulus": cb.P_E2,
    "tappet_poisson": cb.P_NU2,
    "spring_preload": cb.P_SPRING_PRELOAD,
    "spring_rate": cb.P_SPRING_RATE,
    "equivalent_mass": cb.P_EQUIVALENT_MASS,
    "oil_viscosity": cb.P_VISCOSITY,
    "pressure_viscosity": cb.P_PRESSURE_VISCOSITY,
    "nose_window": cb.P_NOSE_WINDOW,
    "min_radius_limit": cb.P_MIN_RADIUS_LIMIT,
    "stress_limit": cb.P_STRESS_LIMIT,
    "spring_margin_limit": cb.P_SPRING_MARGIN_LIMIT,
    **{f"seg{k + 1}_width": cb.P_SEG_WIDTH0 + k for k in range(6)},
    **{f"seg{k + 1}_accel": cb.P_SEG_ACCEL0 + k for k in range(6)},
    **{f"seg{k + 1}_amplitude": cb.P_SEG_AMP0 + k for k in range(6)},
}

MM, UM, MPA = 1e3, 1e6, 1e-6
# response -> (CamState field, column, factor from SI to the response's units)
_SCALAR_SOURCE: dict[str, tuple[str, int, float]] = {
    "max_lift": ("kin", cb.K_MAX_LIFT, MM),
    "face_half_width": ("kin", cb.K_MAX_VELOCITY, MM),
    "max_acceleration": ("kin", cb.K_MAX_ACCELERATION, MM),
    "min_acceleration": ("kin", cb.K_MIN_ACCELERATION, MM),
    "max_acceleration_time": ("kin", cb.K_MAX_ACCELERATION_TIME, 1.0),
    "max_jerk": ("kin", cb.K_MAX_JERK, MM),
    "fullness": ("kin", cb.K_WORKING_FULLNESS, 1.0),
    "event_fullness": ("kin", cb.K_FULLNESS, 1.0),
    "working_lift_unscaled": ("diag", multi_segment.D_UNSCALED_WORKING_LIFT, MM),
    "fillet_monotone": ("diag", multi_segment.D_FILLET_MONOTONE, 1.0),
    "ramp_feasible": ("diag", multi_segment.D_RAMP_FEASIBLE, 1.0),
    "min_radius_of_curvature": ("geo", cam_loads.G_MIN_RADIUS, MM),
    "radius_margin": ("geo", cam_loads.G_RADIUS_MARGIN, MM),
    "radius_ok": ("geo", cam_loads.G_RADIUS_OK, 1.0),
    "max_lubrication_coefficient_nose": ("geo", cam_loads.G_MAX_LUBRICATION, 1.0),
    "min_lubrication_coefficient_nose": ("geo", cam_loads.G_MIN_LUBRICATION, 1.0),
    "min_relative_film_thickness_nose": ("geo", cam_loads.G_MIN_FILM_RATIO, 1.0),
    "max_entrainment_velocity": ("geo", cam_loads.G_MAX_ENTRAINMENT, 1.0),
    "max_contact_force": ("load", cam_loads.L_MAX_FORCE, 1.0),
    "min_contact_force": ("load", cam_loads.L_MIN_FORCE, 1.0),
    "max_contact_stress": ("load", cam_loads.L_MAX_STRESS, MPA),
    "stress_margin": ("load", cam_loads.L_STRESS_MARGIN, MPA),
    "stress_ok": ("load", cam_loads.L_STRESS_OK, 1.0),
    "spring_margin": ("load", cam_loads.L_SPRING_MARGIN, 1.0),
    "spring_margin_ok": ("load", cam_loads.L_SPRING_OK, 1.0),
    "min_film_thickness_nose": ("load", cam_loads.L_MIN_FILM, UM),
}
_CURVE_SOURCE: dict[str, tuple[str, int, float]] = {
    "lift": ("kin_curves", 0, MM),
    "velocity": ("kin_curves", 1, MM),
    "acceleration": ("kin_curves", 2, MM),
    "jerk": ("kin_curves", 3, MM),
    "radius_of_curvature": ("geo_curves", cam_loads.GC_RADIUS, MM),
    "lubrication_coefficient": ("geo_curves", cam_loads.GC_LUBRICATION, 1.0),
    "entrainment_velocity": ("geo_curves", cam_loads.GC_ENTRAINMENT, 1.0),
    "relative_film_thickness": ("geo_curves", cam_loads.GC_FILM_RATIO, 1.0),
    "contact_force": ("load_curves", cam_loads.LC_FORCE, 1.0),
    "contact_stress": ("load_curves", cam_loads.LC_STRESS, MPA),
    "film_thickness": ("load_curves", cam_loads.LC_FILM, UM),
}


CHECKED = (
    "law",
    "rise_angle",
    "lift",
    "ramp_height",
    "ramp_width",
    "ramp_velocity",
    *(f"seg{k}_{part}" for k in range(1, 7) for part in ("width", "shape")),
    "polydyne_coefficients",
    "lift_table",
)
"""The parameters the per-point input checks read (each distinct set is checked once)."""


@dataclass(slots=True)
class CamState(RunState):
    """Run state of a ``cam`` chunk: the kernels' inputs and outputs (SI, kernel columns)."""

    params: np.ndarray = field(init=False)  # kernel parameters (n, cb.N_PARAMS)
    shapes: np.ndarray = field(init=False)  # segment shape codes (n, 6)
    coeffs: np.ndarray = field(init=False)  # polydyne coefficients (n, lift_laws.NCOEF)
    theta: np.ndarray = field(init=False)  # cam angles of the grid [rad]
    kin_curves: np.ndarray = field(init=False)  # lift [m] and 3 derivatives [m/rad^k] (n, 4, grid)
    diag: np.ndarray = field(init=False)  # six-segment diagnostics (n, multi_segment.N_DIAG)
    kin: np.ndarray = field(init=False)  # kinematic responses (n, cb.N_KIN)
    geo: np.ndarray = field(init=False)  # geometry responses (n, cam_loads.N_GEO)
    geo_curves: np.ndarray = field(init=False)  # (n, cam_loads.N_GEO_CURVES, grid or 0)
    load: np.ndarray = field(init=False)  # load responses (n, cam_loads.N_LOAD)
    load_curves: np.ndarray = field(init=False)  # (n, cam_loads.N_LOAD_CURVES, grid or 0)


class CamScene(Scene[CamState]):
    name = "cam"
    seconds_per_point = 1e-3
    work_estimate = staticmethod(work.work_estimate)  # type: ignore[assignment]
    description = "flat-faced tappet cam: lift law, curvature, lubrication, contact stress"
    parameters = PARAMETERS
    settings = SETTINGS
    responses = RESPONSES
    curves = CURVES
    curve_axis = CAM_ANGLE
    stage_order = ("kinematics", "geometry", "loads")
    state_type = CamState

    # --- outputs beside the generic ones -----------------------------------------------------
    def figures(self) -> dict[str, FigureBuilder]:
        from studies.scenes.cam.figures import cam_curves_figure  # noqa: PLC0415  (matplotlib on use)

        return {"cam_curves": cam_curves_figure}

    def benchmarks(self) -> dict[str, SceneBenchmark]:
        from studies.scenes.cam.bench import bench_cam  # noqa: PLC0415

        return {"cam": bench_cam}

    def curve_coordinate(self, settings: dict[str, Any]) -> np.ndarray:
        return turn_deg(np.rad2deg(settings["angle_step"]))

    # --- checks ---------------------------------------------------------------------------
    def point_warnings(
        self, points: Mapping[str, np.ndarray], settings: dict[str, Any]
    ) -> list[str]:
        """The concave cams: their contact responses are inf or 0 (a result, warned)."""
        from studies.scenes.cam.convexity import SHAPE, concave_cams  # noqa: PLC0415

        return on_distinct(points, SHAPE, lambda shapes: concave_cams(self, shapes, settings))

    def check_points(self, points: Mapping[str, np.ndarray], settings: dict[str, Any]) -> list[str]:
        return on_distinct(points, CHECKED, self._distinct_problems)

    def _distinct_problems(self, points: dict[str, np.ndarray]) -> list[str]:
        found: dict[str, list[np.ndarray]] = defaultdict(list)
        tables: dict[str, str | None] = {}
        fitted = fitted_widths(points, np.flatnonzero(points["law"] == "six_segment"))
        for problem, members in checked_groups(
            np.arange(len(points["law"])),
            [points[name] for name in CHECKED if name in points],
            lambda i: self._point_problems(points, i, tables, fitted),
        ):
            found[problem].append(members)
        return [f"{point_list(np.concatenate(idx))}: {msg}" for msg, idx in found.items()]

    def _point_problems(
        self,
        p: dict[str, np.ndarray],
        i: int,
        tables: dict[str, str | None],
        fitted: tuple[np.ndarray, np.ndarray, np.ndarray],
    ) -> list[str]:
        law = p["law"][i]
        deg = np.rad2deg
        out = []
        if law == "six_segment":
            widths, adjusted, fits = (values[i] for values in fitted)
            if not fits:
                out.append(
                    f"segment widths {np.round(deg(widths), 3).tolist()} deg cannot be fitted to "
                    f"the rise_angle = {deg(p['rise_angle'][i]):g} deg half-event: the fillet and segment 6 "
                    f"would need widths {np.round(deg(adjusted), 3).tolist()} deg (must be ≥ 0)"
                )
            out += _ramp_problems(p["ramp_height"][i], p["ramp_width"][i], p["ramp_velocity"][i])
            half = p["rise_angle"][i] + (p["ramp_width"][i] if p["ramp_height"][i] > 0 else 0.0)
        else:
            half = p["rise_angle"][i]
            if law != "table" and p["lift"][i] <= 0.0:
                out.append(f"lift = 0 mm: law {law!r} needs a rise H > 0")
        if deg(half) > HALF_TURN_DEG:
            out.append(f"the event half-width {deg(half):g} deg (rise + ramp) exceeds 180 deg")
        if law == "polydyne":
            out += polydyne_problems(p["polydyne_coefficients"][i])
        if law == "table":
            path = str(p["lift_table"][i])
            if path not in tables:
                try:
                    read_lift_table(path)
                    tables[path] = None
                except ValueError as exc:
                    tables[path] = str(exc)
            if tables[path]:
                out.append(str(tables[path]))
        return out

    # --- evaluation -----------------------------------------------------------------------
    def prepare(self, state: CamState) -> None:
        state.params, state.shapes, state.coeffs = kernel_inputs(state.points)
        state.theta = np.deg2rad(self.curve_coordinate(state.settings))

    def finish(self, state: CamState) -> SceneOutput:
        scalars = {}
        for r in state.responses:
            if r in ("jerk_margin", "jerk_ok", "fullness_ok"):
                scalars[r] = _criterion(r, state)
                continue
            source, col, scale = _SCALAR_SOURCE[r]
            scalars[r] = getattr(state, source)[:, col] * scale
        out_curves = {}
        for c in state.curves:
            source, idx, scale = _CURVE_SOURCE[c]
            out_curves[c] = getattr(state, source)[:, idx, :] * scale
        return SceneOutput(scalars, out_curves)

    def stage_kinematics(self, state: CamState) -> None:
        params, theta, points = state.params, state.theta, state.points
        n, m = params.shape[0], theta.size
        curves = np.empty((n, 4, m))
        diag = np.empty((n, multi_segment.N_DIAG))
        cb.cam_kinematics_batch(params, state.shapes, state.coeffs, theta, curves, diag)
        table_rows = np.flatnonzero(points["law"] == "table")
        for i in table_rows:
            angle, lift = read_lift_table(points["lift_table"][i])
            smoothing = state.settings["table_smoothing"]
            curves[i] = table_kinematics(np.deg2rad(angle), lift * 1e-3, smoothing, theta)
            diag[i] = 1.0
            diag[i, multi_segment.D_UNSCALED_WORKING_LIFT] = lift.max() * 1e-3
        kin = np.empty((n, cb.N_KIN))
        cb.cam_kinematic_responses_batch(params, theta, curves, kin)
        state.kin_curves, state.diag, state.kin = curves, diag, kin

    def stage_geometry(self, state: CamState) -> None:
        params, theta = state.params, state.theta
        want = any(_CURVE_SOURCE[c][0] == "geo_curves" for c in state.curves)
        state.geo = np.empty((params.shape[0], cam_loads.N_GEO))
        state.geo_curves = np.empty(
            (params.shape[0], cam_loads.N_GEO_CURVES, theta.size if want else 0)
        )
        cam_loads.cam_geometry_batch(params, theta, state.kin_curves, state.geo, state.geo_curves)

    def stage_loads(self, state: CamState) -> None:
        params, theta = state.params, state.theta
        want = any(_CURVE_SOURCE[c][0] == "load_curves" for c in state.curves)
        state.load = np.empty((params.shape[0], cam_loads.N_LOAD))
        state.load_curves = np.empty(
            (params.shape[0], cam_loads.N_LOAD_CURVES, theta.size if want else 0)
        )
        cam_loads.cam_loads_batch(params, theta, state.kin_curves, state.load, state.load_curves)


def kernel_inputs(points: dict[str, np.ndarray]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``cam_kinematics_batch`` inputs of the design points: parameters (SI), six-segment shape
    codes and polydyne coefficients, one row per point."""
    shapes = np.stack([codes(points[f"seg{k}_shape"], SHAPE_CODES) for k in range(1, 7)], axis=1)
    return _pack(points), shapes, _coefficients(points["polydyne_coefficients"])


def _pack(points: dict[str, np.ndarray]) -> np.ndarray:
    n = len(points["law"])
    params = np.zeros((n, cb.N_PARAMS))
    for name, col in _COLUMN.items():
        params[:, col] = codes(points["law"], LAW_CODES) if name == "law" else points[name]
    table = points["law"] == "table"
    params[table, cb.P_LIFT] = 0.0
    drop_empty_ramps(params)
    return params


def _coefficients(vectors: np.ndarray) -> np.ndarray:
    coeffs = np.zeros((vectors.shape[0], lift_laws.NCOEF))
    k = min(vectors.shape[1], lift_laws.NCOEF)
    coeffs[:, :k] = vectors[:, :k]
    return coeffs


def _criterion(name: str, state: CamState) -> np.ndarray:
    kin, points = state.kin, state.points
    if name == "fullness_ok":
        return (kin[:, cb.K_WORKING_FULLNESS] >= points["fullness_limit"]).astype(float)
    margin = (points["jerk_limit"] - kin[:, cb.K_MAX_JERK]) * MM
    return margin if name == "jerk_margin" else (margin > 0).astype(float)


def _ramp_problems(height: float, width: float, velocity: float) -> list[str]:
    if height <= 0.0:
        return []
    deg = np.rad2deg
    if velocity <= 0.0 or width <= 0.0:
        return [f"a ramp of height {height * MM:g} mm needs ramp_width > 0 and ramp_velocity > 0"]
    with np.errstate(over="ignore"):  # a tiny ramp_velocity: the bounds are inf, still refused
        lo, hi = height / velocity, 2.0 * height / velocity
        lo_deg, hi_deg = deg(lo), deg(hi)
    if not lo <= width <= hi:
        return [
            (
                f"ramp_width = {deg(width):g} deg cannot carry a {height * MM:g} mm ramp ending at "
                f"{velocity * MM:g} mm/rad: constant acceleration then constant velocity needs "
                f"{lo_deg:.3g} ≤ ramp_width ≤ {hi_deg:.3g} deg"
            )
        ]
    return []
