"""The flat-tappet cam law of a rocker chain, and advice where that cam is concave.

Every design point's tappet law comes from :func:`engine_kernels.cam.kinematics.cam_kinematics_batch`
with the nose lift that gives the target valve lift through the rocker
(:func:`engine_kernels.valvetrain.rocker.tappet_lift_for_valve_lift`). A concave cam (r0 + h + h'' ≤ 0
somewhere, physics §3) is a per-point result, not an error; :func:`concave_chains` says before a
run which points will have one and from which rise angle their law is convex.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from engine_kernels.cam import kinematics as cb
from engine_kernels.cam import lift_laws, multi_segment
from engine_kernels.valvetrain import rocker
from studies.scenes.cam_laws import LAW_CODES, SHAPE_CODES
from studies.scenes.checks import PointProblems, more_concave_line

HALF_TURN_DEG = 180.0
ADVICE_STEP_DEG = 0.5
"""Tappet-angle grid of the convexity search (the cam's own grid decides the run)."""
ADVICE_LIMIT_DEG = 150.0
"""Largest rise angle the search tries (the event must fit in one camshaft turn)."""
LISTED_CHAINS = 10
"""At most this many concave chains are warned one by one, each with a rise-angle search; the
others are counted in one line (a check of 10⁴ points stays short and fast)."""


@dataclass(frozen=True)
class TappetTable:
    """Flat-tappet law of one chain on the tappet-angle grid ``phi`` [rad]."""

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
    return np.array([float(points[name][i]) for name in rocker.ROCKER_GEOMETRY_NAMES])


def nose_tappet_lift(points: dict[str, np.ndarray], i: int) -> float:
    """Tappet lift at the nose that gives the target valve lift [m] (NaN if unreachable)."""
    return rocker.tappet_lift_for_valve_lift(
        float(points["valve_lift"][i]), geometry_row(points, i)
    )


def tappet_parameters(
    points: dict[str, np.ndarray], i: int, nose: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """One row of ``cam_kinematics_batch`` inputs (params, shapes, coefficients) for point i."""
    params = np.zeros((1, cb.N_PARAMS))
    law = str(points["law"][i])
    six = law == "six_segment"
    params[0, cb.P_LAW] = LAW_CODES[law]
    params[0, cb.P_CAM_SPEED] = 1.0
    params[0, cb.P_BASE_RADIUS] = points["base_radius"][i]
    params[0, cb.P_LIFT] = nose - (points["ramp_height"][i] if six else 0.0)
    params[0, cb.P_RISE_ANGLE] = points["rise_angle"][i]
    if six:
        params[0, cb.P_RAMP_HEIGHT] = points["ramp_height"][i]
        params[0, cb.P_RAMP_WIDTH] = points["ramp_width"][i]
        params[0, cb.P_RAMP_VELOCITY] = points["ramp_velocity"][i]
    for k in range(multi_segment.N_SEGMENTS):
        params[0, cb.P_SEG_WIDTH0 + k] = points[f"seg{k + 1}_width"][i]
        params[0, cb.P_SEG_ACCEL0 + k] = points[f"seg{k + 1}_accel"][i]
        params[0, cb.P_SEG_AMP0 + k] = points[f"seg{k + 1}_amplitude"][i]
    shapes = np.array(
        [[SHAPE_CODES[points[f"seg{k}_shape"][i]] for k in range(1, 7)]], dtype=np.int64
    )
    coeffs = np.zeros((1, lift_laws.NCOEF))
    given = np.asarray(points["polydyne_coefficients"][i], dtype=float)[: lift_laws.NCOEF]
    coeffs[0, : given.size] = given
    return params, shapes, coeffs


def tappet_table(points: dict[str, np.ndarray], i: int, spacing: float) -> TappetTable:
    phi_deg = grid_deg(-HALF_TURN_DEG, spacing, HALF_TURN_DEG)
    phi = np.radians(phi_deg)
    nose = nose_tappet_lift(points, i)
    params, shapes, coeffs = tappet_parameters(points, i, nose)
    curves = np.empty((1, 4, phi.size))
    diag = np.empty((1, multi_segment.N_DIAG))
    cb.cam_kinematics_batch(params, shapes, coeffs, phi, curves, diag)
    law = np.ascontiguousarray(curves[0, :3])
    radius = float(np.min(points["base_radius"][i] + law[0] + law[2]))
    return TappetTable(phi, law, nose, radius)


def concave_chains(points: dict[str, np.ndarray], chains: dict[tuple, np.ndarray]) -> list[str]:
    """Warnings for the chains whose tappet cam is concave, grouped by design points: these
    points will not run (``chain_status`` says so per point); the first
    :data:`LISTED_CHAINS` one by one, the others counted in one line. One kernel call scans
    every chain. A standard rise law scales as h'' ∝ lift/β², so its smallest radius of
    curvature rises with the rise angle β: bisection finds the rise angle from which the law is
    convex."""
    members = list(chains.values())
    first = np.array([int(idx[0]) for idx in members], dtype=np.int64)
    radius = min_radii(points, first, ADVICE_STEP_DEG)
    concave = np.flatnonzero(radius <= 0.0)
    found = PointProblems()
    for g in concave[:LISTED_CHAINS]:
        i = int(first[g])
        law = str(points["law"][i])
        message = (
            f"law = {law!r} gives a concave cam at rise_angle = "
            f"{math.degrees(points['rise_angle'][i]):g} degree (smallest radius of curvature "
            f"{radius[g] * 1e3:.3g} mm): these points will not run"
        )
        if law != "six_segment":
            message += "; " + _convex_from(points, i)
        found.add_all(members[g].tolist(), message)
    rest = concave[LISTED_CHAINS:]
    if rest.size == 0:
        return found.messages()
    more = more_concave_line(rest, members, radius * 1e3, "these points will not run either")
    return [*found.messages(), more]


def min_radii(points: dict[str, np.ndarray], idx: np.ndarray, spacing: float) -> np.ndarray:
    """Smallest radius of curvature r0 + h + h'' [m] of the tappet laws of design points
    ``idx`` on a tappet-angle grid of ``spacing`` [deg], in one kernel call."""
    rows = [tappet_parameters(points, int(i), nose_tappet_lift(points, int(i))) for i in idx]
    if not rows:
        return np.empty(0)
    params, shapes, coeffs = (np.concatenate(part) for part in zip(*rows, strict=True))
    phi = np.radians(grid_deg(-HALF_TURN_DEG, spacing, HALF_TURN_DEG))
    curves = np.empty((len(idx), 4, phi.size))
    diag = np.empty((len(idx), multi_segment.N_DIAG))
    cb.cam_kinematics_batch(params, shapes, coeffs, phi, curves, diag)
    base = np.asarray(points["base_radius"], dtype=float)[idx]
    return np.min(base[:, None] + curves[:, 0, :] + curves[:, 2, :], axis=1)


def _convex_from(points: dict[str, np.ndarray], i: int) -> str:
    """Where the law of point ``i`` becomes convex as its rise angle grows (0.1° bisection)."""
    one = {name: values[i : i + 1] for name, values in points.items()}

    def convex(beta_deg: float) -> bool:
        one["rise_angle"] = np.array([math.radians(beta_deg)])
        return tappet_table(one, 0, ADVICE_STEP_DEG).min_radius > 0.0

    low, high = math.degrees(points["rise_angle"][i]), ADVICE_LIMIT_DEG
    if not convex(high):
        return (
            f"no rise angle up to {ADVICE_LIMIT_DEG:g} degree makes it convex: use a larger "
            "base_radius or a smaller valve_lift"
        )
    while high - low > 0.1:
        middle = 0.5 * (low + high)
        low, high = (low, middle) if convex(middle) else (middle, high)
    return f"it is convex from rise_angle = {math.ceil(high * 10) / 10:g} degree"
