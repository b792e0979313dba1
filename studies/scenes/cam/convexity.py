"""Concave cams of the ``cam`` scene, found before anything runs (``Scene.point_warnings``).

A flat-faced tappet cam must be convex: ρ = r0 + h + h'' > 0 everywhere [C1]. A concave or
cusped cam still runs — its kinematics are what they are — but it has no Hertz line contact:
its contact stress is reported as inf and its EHL film as 0 (SPEC §2: a design error to
report, not to crash on). ``check`` and ``run`` warn per design point, with the rise angle from
which the law is convex: a standard rise law scales as h'' ∝ H/β², so its smallest radius of
curvature grows with the rise angle β, and a bisection finds where it turns positive.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import numpy as np
import pandas as pd

from studies.scenes.checks import PointProblems

if TYPE_CHECKING:
    from studies.scenes.base import Scene

SHAPE = (
    "law",
    "base_radius",
    "lift",
    "rise_angle",
    "ramp_height",
    "ramp_width",
    "ramp_velocity",
    *(f"seg{k}_{part}" for k in range(1, 7) for part in ("width", "accel", "amplitude", "shape")),
    "lift_table",
)
"""The parameters that set the cam's shape (speed, loads and limits do not change ρ)."""
ADVICE_CAMS = 32
"""At most this many concave cams get a rise-angle search (the others a plain warning)."""
ADVICE_RESOLUTION_DEG = 0.01  # the advice is rounded up to 0.1°
NO_ADVICE = ("six_segment", "table")  # their shape does not scale with the rise angle alone
MM = 1e3


def concave_cams(
    scene: Scene, points: dict[str, np.ndarray], settings: dict[str, Any]
) -> list[str]:
    """A warning per concave cam, naming its design points; O(N) grouping, then one kernel
    call over the distinct cam shapes."""
    first, members = _distinct(points)
    shapes = {name: values[first] for name, values in points.items()}
    radius = _min_radius(scene, shapes, settings)
    found = PointProblems()
    searched = 0
    for g in np.flatnonzero(radius <= 0.0):
        law = str(shapes["law"][g])
        message = (
            f"law = {law!r} gives a concave cam at base_radius = "
            f"{shapes['base_radius'][g] * MM:g} mm, rise_angle = "
            f"{math.degrees(shapes['rise_angle'][g]):g} degree (smallest radius of curvature "
            f"r0 + h + h'' = {radius[g]:.3g} mm): no Hertz line contact, so max_contact_stress "
            "is inf and the film thickness 0 there"
        )
        if law not in NO_ADVICE and searched < ADVICE_CAMS:
            searched += 1
            message += "; " + _convex_from(scene, shapes, int(g), settings)
        found.add_all(members[g].tolist(), message)
    return found.messages()


def _distinct(points: dict[str, np.ndarray]) -> tuple[np.ndarray, list[np.ndarray]]:
    """The first design point of each distinct cam shape and the points of each shape."""
    columns = [np.asarray(points[name]) for name in SHAPE if name in points]
    coefficients = np.asarray(points["polydyne_coefficients"], dtype=float)
    columns.append(np.unique(coefficients, axis=0, return_inverse=True)[1].ravel())
    group = np.zeros(len(columns[0]), dtype=np.int64)
    for column in columns:
        codes, uniques = pd.factorize(column)
        group = pd.factorize(group * len(uniques) + codes)[0]
    order = np.argsort(group, kind="stable")
    members = np.split(order, np.cumsum(np.bincount(group))[:-1])
    return np.array([m[0] for m in members], dtype=np.int64), members


def _min_radius(
    scene: Scene, points: dict[str, np.ndarray], settings: dict[str, Any]
) -> np.ndarray:
    out = scene.evaluate(points, settings, ["min_radius_of_curvature"], [])
    return np.asarray(out.scalars["min_radius_of_curvature"], dtype=float)


def _convex_from(
    scene: Scene, shapes: dict[str, np.ndarray], g: int, settings: dict[str, Any]
) -> str:
    """Where the cam of shape ``g`` becomes convex as its rise angle grows (bisection)."""
    one = {name: values[g : g + 1].copy() for name, values in shapes.items()}
    limit = scene.parameter("rise_angle")
    high = float(limit.maximum) if limit is not None and limit.maximum is not None else 170.0

    def convex(beta_deg: float) -> bool:
        one["rise_angle"] = np.array([math.radians(beta_deg)])
        return bool(_min_radius(scene, one, settings)[0] > 0.0)

    low = math.degrees(float(shapes["rise_angle"][g]))
    if not convex(high):
        return (
            f"no rise angle up to {high:g} degree makes it convex: use a larger base_radius or "
            "a smaller lift"
        )
    while high - low > ADVICE_RESOLUTION_DEG:
        middle = 0.5 * (low + high)
        low, high = (low, middle) if convex(middle) else (middle, high)
    return f"it is convex from rise_angle = {math.ceil(high * 10) / 10:g} degree"
