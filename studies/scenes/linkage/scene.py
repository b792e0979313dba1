"""Scene ``rocker``: OHC cam with a variable-ratio rocker, valve kinematics (physics §3).

Two stages, each a compiled kernel:

* ``tappet`` — :func:`engine_kernels.cam.kinematics.cam_kinematics_batch`: the flat-tappet lift law
  h, h', h'' on a tappet-angle grid (a standard rise law, a polydyne, or the six-segment
  profile), scaled so that the linkage gives the target valve lift at the nose
  (:func:`engine_kernels.valvetrain.rocker.tappet_lift_for_valve_lift`);
* ``rocker`` — :func:`engine_kernels.valvetrain.rocker.rocker_valve_lift`: the linkage [R1]–[R6], valve
  lift Y and its derivatives, force ratio and rocker angle on a cam-angle grid.

Design points that share the cam and rocker parameters share one linkage: both stages work per
distinct parameter set and keep their tables in a bounded cache on the scene, so a study that
varies only speeds or springs computes the kinematics once. A cam that is not convex, or a
linkage that does not close, is a per-point result (``chain_status``, ``cam_convex``), never an
exception; impossible geometry is refused by :meth:`LinkageScene.check_points` before anything
runs.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Hashable, Mapping
from dataclasses import dataclass, field
from typing import Any, TypeVar

import numpy as np

from engine_kernels.valvetrain import rocker
from studies.scenes.base import CurveAxis, Scene, SceneOutput
from studies.scenes.checks import distinct, on_distinct
from studies.scenes.linkage.checks import linkage_point_problems
from studies.scenes.linkage.parameters import (
    CAM_ANGLE,
    CURVES,
    PARAMETERS,
    RESPONSES,
    SETTINGS,
)
from studies.scenes.linkage.tappet import (
    HALF_TURN_DEG,
    TappetTable,
    concave_linkages,
    geometry_row,
    grid_deg,
    step_deg,
    tappet_table,
)
from studies.scenes.state import RunState

MM = 1e3
GRID_UNIT_DEG = 2.0
"""Every angle step must divide this, so grids of different steps share their nodes."""
CACHE_SIZE = 64
SIDES = {"ahead": rocker.PAD_AHEAD, "behind": rocker.PAD_BEHIND}
KEY_NAMES = tuple(p.name for p in PARAMETERS if p.kind != "vector")
"""Parameters that fix the linkage (with the polydyne coefficients): the cache key."""
LINKAGE_NAMES = tuple(p.name for p in PARAMETERS)
"""The parameters of the cam law and the rocker: all that the linkage checks read."""

# response -> (row of the linkage curves, reduction, factor to the response's units)
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
class LinkageCurves:
    """The linkage [R1]–[R6] of one parameter set on a cam-angle grid (``ROW_*`` rows, SI)."""

    theta_deg: np.ndarray
    curves: np.ndarray
    status: int


@dataclass(slots=True)
class LinkageState(RunState):
    """Run state of a linkage chunk (the ``rocker`` scene, and the ``valve`` scenes on it)."""

    groups: dict[tuple, np.ndarray] = field(init=False)  # linkage key → its design points
    tappet: dict[tuple, TappetTable] = field(init=False, default_factory=dict)  # law per key
    kinematics: dict[tuple, LinkageCurves] = field(init=False)  # stage rocker: [R1]–[R6] per key


Linkage = TypeVar("Linkage", bound=LinkageState)


def linkage_groups(points: dict[str, np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """The first design point of each distinct linkage (its cam law and rocker parameters) and
    the linkage of each design point, numbered in order of first appearance. Vectorised (O(N log
    N) over the parameters that vary): a 10⁶-point study may have 10⁶ linkages."""
    coefficients = np.asarray(points["polydyne_coefficients"], dtype=float)
    return distinct([coefficients, *(np.asarray(points[name]) for name in KEY_NAMES)])


def linkage_keys(points: dict[str, np.ndarray]) -> dict[tuple, np.ndarray]:
    """The design points of each distinct linkage, keyed by the tuple of its linkage parameters
    (the keys of the scene's table caches, shared across chunks)."""
    first, linkage = linkage_groups(points)
    order = np.argsort(linkage, kind="stable")
    members = np.split(order, np.cumsum(np.bincount(linkage, minlength=first.size))[:-1])
    coefficients = np.asarray(points["polydyne_coefficients"], dtype=float)
    return {
        (*(points[name][i] for name in KEY_NAMES), tuple(coefficients[i].tolist())): idx
        for i, idx in zip(first.tolist(), members, strict=True)
    }


class LinkageScene(Scene[Linkage]):
    """The cam–rocker–valve linkage: two stages (``tappet``, ``rocker``), its tables cached per
    distinct parameter set, and its kinematic responses and curves."""

    parameters = PARAMETERS
    settings = SETTINGS
    responses = RESPONSES
    curves = CURVES
    curve_axis: CurveAxis | None = CAM_ANGLE
    stage_order: tuple[str, ...] = ("tappet", "rocker")
    state_type: type[RunState] = LinkageState
    status_responses: tuple[str, ...] = ("chain_status",)

    def __init__(self) -> None:
        super().__init__()
        self.tappet_cache = BoundedCache(CACHE_SIZE)
        self.walk_cache = BoundedCache(CACHE_SIZE)
        self.linkage_cache = BoundedCache(CACHE_SIZE)
        self.groups_seen: tuple[tuple[np.ndarray, ...], tuple[np.ndarray, np.ndarray]] | None = None

    def curve_coordinate(self, settings: dict[str, Any]) -> np.ndarray:
        step = step_deg(settings["angle_step"])
        return grid_deg(-HALF_TURN_DEG, step, HALF_TURN_DEG)

    # --- checks ---------------------------------------------------------------------------
    def check_points(self, points: Mapping[str, np.ndarray], settings: dict[str, Any]) -> list[str]:
        problem = angle_step_problem(settings["angle_step"], "setting angle_step")
        return ([problem] if problem else []) + on_distinct(
            points, LINKAGE_NAMES, self.linkage_point_problems
        )

    def point_warnings(
        self, points: Mapping[str, np.ndarray], settings: dict[str, Any]
    ) -> list[str]:
        """The linkages whose cam is concave: their points will not run (a result, not an error).
        The last user of the linkages :meth:`check_points` found: they are forgotten here."""

        def concave(values: dict[str, np.ndarray]) -> list[str]:
            groups = self.linkage_groups(values)
            self.groups_seen = None
            return concave_linkages(values, *groups)

        return on_distinct(points, LINKAGE_NAMES, concave)

    def linkage_point_problems(self, points: dict[str, np.ndarray]) -> list[str]:
        """Input errors of the cam laws and rocker geometries, grouped by design points."""
        return linkage_point_problems(points, *self.linkage_groups(points))

    def linkage_groups(self, points: dict[str, np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
        """:func:`linkage_groups`, computed once for the points ``check`` and ``run`` plan with
        (the same arrays: their checks and warnings share it)."""
        arrays = tuple(points.values())
        seen = self.groups_seen
        if (
            seen is None
            or len(seen[0]) != len(arrays)
            or any(a is not b for a, b in zip(seen[0], arrays, strict=True))
        ):
            seen = self.groups_seen = (arrays, linkage_groups(points))
        return seen[1]

    # --- evaluation -----------------------------------------------------------------------
    def prepare(self, state: Linkage) -> None:
        """The design points grouped by linkage (:func:`linkage_keys`)."""
        state.groups = linkage_keys(state.points)

    def finish(self, state: Linkage) -> SceneOutput:
        return SceneOutput(
            {r: self.scalar(state, r) for r in state.responses},
            {c: self.curve_values(state, c) for c in state.curves},
        )

    def kinematic_grid(self, settings: dict[str, Any]) -> tuple[float, float, float]:
        """(start, spacing, stop) [deg] of the grid of kinematic responses and curves."""
        return -HALF_TURN_DEG, step_deg(settings["angle_step"]), HALF_TURN_DEG

    def tappet_table(self, state: Linkage, key: tuple) -> TappetTable:
        """The flat-tappet law of the linkage ``key``: made once per chunk (the run state keeps
        it for every stage) and cached across chunks per key and tappet step. The cross-chunk
        cache alone would make it again in each stage of a chunk with more linkages than the
        cache holds."""
        table = state.tappet.get(key)
        if table is None:
            spacing = step_deg(state.settings["tappet_step"])
            i = int(state.groups[key][0])
            table = self.tappet_cache.get(
                (key, spacing), lambda: tappet_table(state.points, i, spacing)
            )
            state.tappet[key] = table
        return table

    def rocker_walk(self, state: Linkage, key: tuple, no_lash: bool = False) -> RockerWalk:
        """The linkage of ``key`` at every point of its tappet table (:func:`linkage_walk`),
        made once per key and tappet step and resampled onto every grid asked for (the walk
        is about 0.4 ms of a linkage's 0.4-0.6 ms; a valve point under a tolerance asks for
        five or six grids). ``no_lash``: with the stem raised by the lash and no lash (the
        unclipped valve lift, :mod:`studies.scenes.valve.excitation`)."""
        table = self.tappet_table(state, key)
        i = int(state.groups[key][0])
        spacing = step_deg(state.settings["tappet_step"])
        return self.walk_cache.get(
            (key, spacing, no_lash), lambda: linkage_walk(state.points, i, table, no_lash)
        )

    def linkage(
        self, state: Linkage, key: tuple, grid: tuple[float, float, float]
    ) -> LinkageCurves:
        """The linkage [R1]–[R6] of ``key`` on the cam-angle grid (start, spacing, stop) [deg]."""
        table = self.tappet_table(state, key)
        spacing = step_deg(state.settings["tappet_step"])
        return self.linkage_cache.get(
            (key, spacing, grid),
            lambda: _linkage_curves(self.rocker_walk(state, key), table, grid),
        )

    def stage_tappet(self, state: Linkage) -> None:
        for key in state.groups:
            self.tappet_table(state, key)

    def stage_rocker(self, state: Linkage) -> None:
        grid = self.kinematic_grid(state.settings)
        state.kinematics = {key: self.linkage(state, key, grid) for key in state.groups}

    # --- outputs --------------------------------------------------------------------------
    def scalar(self, state: Linkage, response: str) -> np.ndarray:
        """Values of a kinematic response per design point (response units)."""
        out = np.empty(state.n)
        for key, idx in state.groups.items():
            out[idx] = _kinematic_value(response, state, key)
        return out

    def curve_values(self, state: Linkage, name: str) -> np.ndarray:
        """A kinematic curve per design point on the curve axis (curve units)."""
        axis = self.curve_coordinate(state.settings)
        out = np.empty((state.n, axis.size))
        for key, idx in state.groups.items():
            if name == "tappet_lift":
                table = state.tappet[key]
                values = np.interp(np.radians(axis), table.phi, table.curves[0]) * MM
            else:
                row, scale = _CURVE_ROWS[name]
                values = state.kinematics[key].curves[row] * scale
            out[idx] = values
        return out


@dataclass(frozen=True)
class RockerWalk:
    """The linkage at every tappet point (rows ``rocker.W_*``), its ``ROCKER_*`` status and
    the lash [m] its stem was raised by (0: the linkage as designed)."""

    rows: np.ndarray
    status: int
    raised: float = 0.0


def linkage_walk(
    points: dict[str, np.ndarray], i: int, table: TappetTable, no_lash: bool
) -> RockerWalk:
    """:func:`engine_kernels.valvetrain.rocker.rocker_walk` of design point ``i`` on its
    tappet table; ``no_lash``: the stem raised by the lash and no lash."""
    geometry = geometry_row(points, i)
    raised = float(geometry[rocker.G_LASH]) if no_lash else 0.0
    if no_lash:
        geometry[rocker.G_STEM_HEIGHT] += geometry[rocker.G_LASH]
        geometry[rocker.G_LASH] = 0.0
    rows = np.empty((rocker.N_WALK, table.phi.size))
    status = rocker.rocker_walk(
        table.phi,
        table.curves[0],
        table.curves[1],
        table.curves[2],
        geometry,
        SIDES[str(points["pad_side"][i])],
        rows,
    )
    return RockerWalk(rows, int(status), raised)


def resampled_linkage(
    walk: RockerWalk, table: TappetTable, grid: tuple[float, float, float]
) -> np.ndarray:
    """The ``ROW_*`` curves of a walk on the cam-angle grid (start, spacing, stop) [deg]: what
    ``rocker.rocker_valve_lift`` gives there, to the last bit."""
    theta = np.radians(grid_deg(*grid))
    out = np.empty((len(rocker.ROCKER_CURVE_NAMES), theta.size))
    rocker.rocker_resample(table.phi, walk.rows, theta, out)
    return out


def _linkage_curves(
    walk: RockerWalk, table: TappetTable, grid: tuple[float, float, float]
) -> LinkageCurves:
    return LinkageCurves(grid_deg(*grid), resampled_linkage(walk, table, grid), walk.status)


def open_range(linkage: LinkageCurves) -> tuple[float, float]:
    """Cam angles [deg] of the first and last grid points with the valve open (NaN if none)."""
    open_idx = np.flatnonzero(linkage.curves[rocker.ROW_VALVE_LIFT] > 0.0)
    if open_idx.size == 0:
        return math.nan, math.nan
    return float(linkage.theta_deg[open_idx[0]]), float(linkage.theta_deg[open_idx[-1]])


def located_open_range(linkage: LinkageCurves) -> tuple[float, float]:
    """Cam angles [deg] where the valve opens and closes, located between the grid points: a
    Newton step back (forward) from the first (last) open grid point on its lift and velocity,
    kept inside the grid interval; NaN if the valve never opens. (The grid points themselves
    made the duration short by up to two steps.)"""
    theta, c = linkage.theta_deg, linkage.curves
    lift, velocity = c[rocker.ROW_VALVE_LIFT], c[rocker.ROW_VALVE_VELOCITY]
    open_idx = np.flatnonzero(lift > 0.0)
    if open_idx.size == 0:
        return math.nan, math.nan
    first, last = int(open_idx[0]), int(open_idx[-1])

    def root(i: int, neighbour: int) -> float:
        edge = float(theta[neighbour]) if 0 <= neighbour < theta.size else float(theta[i])
        if not velocity[i] * (i - neighbour) > 0.0:  # rising into the open side
            return edge
        guess = float(theta[i]) - math.degrees(float(lift[i]) / float(velocity[i]))
        return float(np.clip(guess, min(edge, theta[i]), max(edge, theta[i])))

    return root(first, first - 1), root(last, last + 1)


def _kinematic_value(response: str, state: LinkageState, key: tuple) -> float:
    if response in ("max_tappet_lift", "min_radius_of_curvature", "cam_convex"):
        table = state.tappet[key]
        if response == "cam_convex":
            return float(table.min_radius > 0.0)
        return (table.nose_lift if response == "max_tappet_lift" else table.min_radius) * MM
    linkage = state.kinematics[key]
    c = linkage.curves
    lift = c[rocker.ROW_VALVE_LIFT]
    is_open = lift > 0.0
    opening, closing = located_open_range(linkage)
    values: dict[str, Callable[[], float]] = {
        "max_valve_lift": lambda: lift.max() * MM,
        "max_valve_velocity": lambda: c[rocker.ROW_VALVE_VELOCITY].max() * MM,
        "min_valve_velocity": lambda: c[rocker.ROW_VALVE_VELOCITY].min() * MM,
        "max_valve_acceleration": lambda: c[rocker.ROW_VALVE_ACCELERATION].max() * MM,
        "min_valve_acceleration": lambda: c[rocker.ROW_VALVE_ACCELERATION].min() * MM,
        "valve_opening_angle": lambda: opening,
        "valve_closing_angle": lambda: closing,
        "valve_open_duration": lambda: closing - opening,
        "lift_ratio": lambda: lift.max() / state.tappet[key].nose_lift,
        "force_ratio_nose": lambda: float(
            np.interp(0.0, linkage.theta_deg, c[rocker.ROW_FORCE_RATIO])
        ),
        "max_force_ratio": lambda: _masked(c[rocker.ROW_FORCE_RATIO], is_open, np.max),
        "min_force_ratio": lambda: _masked(c[rocker.ROW_FORCE_RATIO], is_open, np.min),
        "rocker_swing": lambda: math.degrees(np.ptp(c[rocker.ROW_ROCKER_ANGLE])),
        "chain_status": lambda: float(linkage.status),
        "chain_ok": lambda: float(linkage.status == rocker.ROCKER_OK),
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
