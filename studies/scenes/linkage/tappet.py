"""The flat-tappet cam law of a rocker linkage, and advice where that cam is concave.

Every design point's tappet law comes from :func:`engine_kernels.cam.kinematics.cam_kinematics_batch`
with the nose lift that gives the target valve lift through the rocker
(:func:`engine_kernels.valvetrain.rocker.tappet_lift_for_valve_lift`). A concave cam (r0 + h + h'' ≤ 0
somewhere, physics §3) is a per-point result, not an error; :func:`concave_linkages` says before a
run which points will have one and from which rise angle their law is convex.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from engine_kernels._jit import call_small, claim
from engine_kernels.cam import kinematics as cb
from engine_kernels.cam import lift_laws, multi_segment
from engine_kernels.valvetrain import rocker, rocker_batches
from studies.scenes import cam_radius
from studies.scenes.cam_laws import (
    LAW_CODES,
    SHAPE_CODES,
    codes,
    drop_empty_ramps,
    first_convex_mark,
)
from studies.scenes.checks import PointProblems, convex_advice, more_concave_line, take

HALF_TURN_DEG = 180.0
ADVICE_STEP_DEG = 0.5
"""Tappet-angle grid of the convexity search (the cam's own grid decides the run)."""
ADVICE_LIMIT_DEG = 150.0
"""Largest rise angle the search tries (the event must fit in one camshaft turn)."""
LISTED_CHAINS = 10
"""At most this many concave linkages are warned one by one, each with a rise-angle search; the
others are counted in one line (a check of 10⁴ points stays short and fast)."""
BISECT_DEPTH = 4
"""Bisection steps of the rise-angle advice per kernel call (15 candidate angles per law)."""


@dataclass(frozen=True)
class TappetTable:
    """Flat-tappet law of one linkage on the tappet-angle grid ``phi`` [rad]."""

    phi: np.ndarray
    curves: np.ndarray  # (3, m): h [m], h' [m/rad], h'' [m/rad²]
    nose_lift: float  # [m]
    min_radius: float  # min r0 + h + h'' [m]


def grid_deg(start: float, spacing: float, stop: float) -> np.ndarray:
    """Angles start, start + spacing, … stop [deg] (stop − start a multiple of spacing)."""
    count = round((stop - start) / spacing)
    return start + spacing * np.arange(count + 1)


def step_deg(step_rad: float) -> float:
    """A grid step from settings [rad] in degrees, rounded so grids compare exactly."""
    return round(math.degrees(step_rad), 9)


def geometry_row(points: dict[str, np.ndarray], i: int) -> np.ndarray:
    """Rocker geometry of design point ``i`` indexed by ``engine_kernels.valvetrain.rocker.G_*`` [m]."""
    return geometry_rows(points, np.array([i]))[0]


def geometry_rows(points: dict[str, np.ndarray], idx: np.ndarray) -> np.ndarray:
    """Rocker geometries of design points ``idx``, one row each (``rocker.G_*`` columns) [m]."""
    names = rocker.ROCKER_GEOMETRY_NAMES
    rows = np.empty((len(idx), len(names)))
    for column, name in enumerate(names):
        rows[:, column] = take(points[name], idx)
    return rows


def nose_tappet_lift(points: dict[str, np.ndarray], i: int) -> float:
    """Tappet lift at the nose that gives the target valve lift [m] (NaN if unreachable)."""
    return float(nose_tappet_lifts(points, np.array([i]))[0])


def nose_tappet_lifts(points: dict[str, np.ndarray], idx: np.ndarray) -> np.ndarray:
    """:func:`nose_tappet_lift` of design points ``idx`` in one kernel call [m]."""
    claim(len(idx))
    out = np.empty(len(idx))
    lift = np.ascontiguousarray(take(points["valve_lift"], idx), dtype=float)
    geometry = geometry_rows(points, idx)
    call_small(rocker_batches.tappet_lift_for_valve_lift_batch, len(idx), lift, geometry, out)
    return out


def shape_codes(points: dict[str, np.ndarray], idx: np.ndarray) -> np.ndarray:
    """Six-segment shape codes of design points ``idx``, shape (len(idx), 6)."""
    columns = [codes(take(points[f"seg{k}_shape"], idx), SHAPE_CODES) for k in range(1, 7)]
    return np.stack(columns, axis=1).reshape(len(idx), multi_segment.N_SEGMENTS)


def tappet_parameters(
    points: dict[str, np.ndarray], idx: np.ndarray, nose: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``cam_kinematics_batch`` inputs (params, shapes, coefficients) of design points ``idx``
    whose tappet nose lifts are ``nose`` [m]."""
    n = len(idx)

    def column(name: str) -> np.ndarray:
        return take(points[name], idx).astype(float, copy=False)

    params = np.zeros((n, cb.N_PARAMS))
    law = codes(take(points["law"], idx), LAW_CODES)
    six = law == LAW_CODES["six_segment"]
    params[:, cb.P_LAW] = law
    params[:, cb.P_CAM_SPEED] = 1.0
    params[:, cb.P_BASE_RADIUS] = column("base_radius")
    params[:, cb.P_LIFT] = nose - np.where(six, column("ramp_height"), 0.0)
    params[:, cb.P_RISE_ANGLE] = column("rise_angle")
    for name, where in (
        ("ramp_height", cb.P_RAMP_HEIGHT),
        ("ramp_width", cb.P_RAMP_WIDTH),
        ("ramp_velocity", cb.P_RAMP_VELOCITY),
    ):
        params[:, where] = np.where(six, column(name), 0.0)
    drop_empty_ramps(params)
    for k in range(multi_segment.N_SEGMENTS):
        params[:, cb.P_SEG_WIDTH0 + k] = column(f"seg{k + 1}_width")
        params[:, cb.P_SEG_ACCEL0 + k] = column(f"seg{k + 1}_accel")
        params[:, cb.P_SEG_AMP0 + k] = column(f"seg{k + 1}_amplitude")
    coeffs = np.zeros((n, lift_laws.NCOEF))
    given = take(points["polydyne_coefficients"], idx).astype(float, copy=False)
    given = given.reshape(n, -1)[:, : lift_laws.NCOEF]
    coeffs[:, : given.shape[1]] = given
    return params, shape_codes(points, idx), coeffs


def tappet_table(points: dict[str, np.ndarray], i: int, spacing: float) -> TappetTable:
    phi_deg = grid_deg(-HALF_TURN_DEG, spacing, HALF_TURN_DEG)
    phi = np.radians(phi_deg)
    idx = np.array([i])
    nose = nose_tappet_lifts(points, idx)
    params, shapes, coeffs = tappet_parameters(points, idx, nose)
    curves = np.empty((1, 4, phi.size))
    diag = np.empty((1, multi_segment.N_DIAG))
    cb.cam_kinematics_batch(params, shapes, coeffs, phi, curves, diag)
    law = np.ascontiguousarray(curves[0, :3])
    radius = float(np.min(points["base_radius"][i] + law[0] + law[2]))
    return TappetTable(phi, law, float(nose[0]), radius)


def concave_linkages(
    points: dict[str, np.ndarray], first: np.ndarray, linkage: np.ndarray
) -> list[str]:
    """Warnings for the linkages whose tappet cam is concave, grouped by design points: these
    points will not run (``chain_status`` says so per point); the first
    :data:`LISTED_CHAINS` one by one, the others counted in one line. ``first`` is the first
    design point of each linkage and ``linkage`` the linkage of each design point
    (:func:`studies.scenes.linkage.scene.linkage_groups`). One kernel call per block scans every linkage.
    A standard rise law scales as h'' ∝ lift/β², so its smallest radius of curvature rises
    with the rise angle β: bisections side by side find the rise angle from which each listed
    law is convex."""
    radius, scanned = min_radii(points, first, ADVICE_STEP_DEG)
    concave = np.flatnonzero(radius <= 0.0)
    listed = concave[:LISTED_CHAINS]
    members = {int(g): np.flatnonzero(linkage == g) for g in listed}
    laws = np.asarray(points["law"])[first[listed]].astype(str)
    advised = [int(g) for g, law in zip(listed, laws, strict=True) if law != "six_segment"]
    advice = convex_advice(advised, lambda: _convex_from(points, first[advised]))
    found = PointProblems()
    for g, law in zip(listed.tolist(), laws.tolist(), strict=True):
        i = int(first[g])
        message = (
            f"law = {law!r} gives a concave cam at rise_angle = "
            f"{math.degrees(points['rise_angle'][i]):g} degree (smallest radius of curvature "
            f"{radius[g] * 1e3:.3g} mm): these points will not run"
        )
        if g in advice:
            message += "; " + advice[g]
        found.add_all(members[g], message)
    rest = concave[LISTED_CHAINS:]
    if rest.size == 0:
        return found.messages()
    more = more_concave_line(rest, linkage, radius * 1e3, "these points will not run either")
    return [*found.messages(), more + scanned]


def min_radii(
    points: dict[str, np.ndarray], idx: np.ndarray, spacing: float, nose: np.ndarray | None = None
) -> tuple[np.ndarray, str]:
    """Smallest radius of curvature r0 + h + h'' [m] of the tappet laws of design points
    ``idx`` on a tappet-angle grid of ``spacing`` [deg] (``nose`` [m], their tappet nose
    lifts, if known: they do not depend on the rise angle), and what to say if some were
    scanned coarser (:func:`studies.scenes.cam_radius.min_radii`: O(len(idx)) memory)."""
    nose = nose_tappet_lifts(points, idx) if nose is None else nose
    law = codes(take(points["law"], idx), LAW_CODES)
    return cam_radius.min_radii(
        law,
        nose,
        take(points["rise_angle"], idx).astype(float),
        take(points["base_radius"], idx).astype(float),
        take(points["polydyne_coefficients"], idx),
        lambda some: tappet_parameters(points, idx[some], nose[some]),
        spacing,
    )


def _convex_from(points: dict[str, np.ndarray], idx: np.ndarray) -> list[str]:
    """Where the laws of design points ``idx`` become convex as their rise angles grow: a 0.1°
    bisection each (:func:`_bisect`)."""
    if len(idx) == 0:
        return []
    nose = nose_tappet_lifts(points, idx)

    def convex(which: np.ndarray, beta_deg: np.ndarray) -> np.ndarray:
        some = {name: np.asarray(values)[idx[which]] for name, values in points.items()}
        some["rise_angle"] = np.radians(beta_deg)
        every = np.arange(len(which))
        return min_radii(some, every, ADVICE_STEP_DEG, nose[which])[0] > 0.0

    every = np.arange(len(idx))
    high = np.full(len(idx), ADVICE_LIMIT_DEG)
    reachable = convex(every, high)
    low = np.degrees(np.asarray(points["rise_angle"], dtype=float)[idx])
    low = _bisect(low, high, convex)
    marks = first_convex_mark(low, lambda beta: convex(every, beta))
    return [
        f"it is convex from rise_angle = {h:g} degree"
        if fine
        else (
            f"no rise angle up to {ADVICE_LIMIT_DEG:g} degree makes it convex: use a larger "
            "base_radius or a smaller valve_lift"
        )
        for h, fine in zip(marks.tolist(), reachable.tolist(), strict=True)
    ]


def _bisect(
    low: np.ndarray,
    high: np.ndarray,
    convex: Callable[[np.ndarray, np.ndarray], np.ndarray],
) -> np.ndarray:
    """The lower (concave) ends [deg] of bisections of [low, high] (convex at high) down to
    0.1°, each stopping at its own 0.1° as if alone: ``convex(which, beta)`` says whether laws
    ``which`` are convex at rise angles ``beta``. Every midpoint the next :data:`BISECT_DEPTH` steps
    could visit is evaluated in one call (a tree of 2^depth − 1 per law), then walked."""
    rows = np.arange(low.size)
    nodes = 2**BISECT_DEPTH
    while (high - low > 0.1).any():
        lows, highs = np.empty((low.size, nodes)), np.empty((low.size, nodes))
        mids = np.empty((low.size, nodes))
        lows[:, 1], highs[:, 1] = low, high
        for node in range(1, nodes):
            mids[:, node] = 0.5 * (lows[:, node] + highs[:, node])
            if 2 * node < nodes:
                lows[:, 2 * node], highs[:, 2 * node] = lows[:, node], mids[:, node]
                lows[:, 2 * node + 1], highs[:, 2 * node + 1] = mids[:, node], highs[:, node]
        ok = np.zeros((low.size, nodes), dtype=bool)
        ok[:, 1:] = convex(np.repeat(rows, nodes - 1), mids[:, 1:].ravel()).reshape(
            low.size, nodes - 1
        )
        at = np.ones(low.size, dtype=np.int64)  # each law's node of the tree
        for _ in range(BISECT_DEPTH):
            active = high - low > 0.1
            middle, fine = mids[rows, at], ok[rows, at]
            low = np.where(active & ~fine, middle, low)
            high = np.where(active & fine, middle, high)
            at = np.where(fine, 2 * at, 2 * at + 1)
    return low
