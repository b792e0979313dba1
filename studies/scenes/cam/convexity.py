"""Concave cams of the ``cam`` scene, found before anything runs (``Scene.point_warnings``).

A flat-faced tappet cam must be convex: ρ = r0 + h + h'' > 0 everywhere [C1]. A concave or
cusped cam still runs — its kinematics are what they are — but it has no Hertz line contact:
its contact stress is reported as inf and its EHL film as 0 (physics §2: a design error to
report, not to crash on). ``check`` and ``run`` warn per design point, with the rise angle from
which the law is convex: a standard rise law scales as h'' ∝ H/β², so its smallest radius of
curvature grows with the rise angle β, and a bisection finds where it turns positive.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import numpy as np

from engine_kernels._jit import claim
from studies.scenes import cam_radius
from studies.scenes.cam.scene import kernel_inputs
from studies.scenes.cam_laws import LAW_CODES, codes, first_convex_mark
from studies.scenes.checks import (
    PointProblems,
    convex_advice,
    distinct,
    more_concave_line,
    take_points,
)

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
LISTED_CAMS = 10
"""At most this many concave cams are warned one by one, each with a rise-angle search; the
others are counted in one line (a check of 10⁴ points stays short and fast)."""
ADVICE_RESOLUTION_DEG = 0.1  # then the first convex 0.1° mark (first_convex_mark)
NO_ADVICE = ("six_segment", "table")  # their shape does not scale with the rise angle alone
MM = 1e3


def concave_cams(
    scene: Scene, points: dict[str, np.ndarray], settings: dict[str, Any]
) -> list[str]:
    """A warning per concave cam (the first :data:`LISTED_CAMS`), naming its design points, and
    one line counting the rest; O(N) grouping, then one kernel call over the distinct cam
    shapes and one per bisection step of the advice."""
    claim(len(points["law"]), "distinct cam shapes")  # a quick check: no O(cams) preparation
    first, shape = _distinct(points)
    shapes = take_points(points, first)
    radius, scanned = _min_radii(scene, shapes, settings)
    concave = np.flatnonzero(radius <= 0.0)
    listed = concave[:LISTED_CAMS]
    advised = [int(g) for g in listed if str(shapes["law"][g]) not in NO_ADVICE]
    advice = convex_advice(advised, lambda: _convex_from(scene, shapes, advised, settings))
    found = PointProblems()
    for g in listed:
        law = str(shapes["law"][g])
        message = (
            f"law = {law!r} gives a concave cam at base_radius = "
            f"{shapes['base_radius'][g] * MM:g} mm, rise_angle = "
            f"{math.degrees(shapes['rise_angle'][g]):g} degree (smallest radius of curvature "
            f"r0 + h + h'' = {radius[g]:.3g} mm): no Hertz line contact, so max_contact_stress "
            "is inf and the film thickness 0 there"
        )
        found.add_all(
            np.flatnonzero(shape == g), message + (f"; {advice[g]}" if g in advice else "")
        )
    rest = concave[LISTED_CAMS:]
    if rest.size == 0:
        return found.messages()
    consequence = "their max_contact_stress is inf and their film thickness 0 too"
    return [*found.messages(), more_concave_line(rest, shape, radius, consequence) + scanned]


def _min_radii(
    scene: Scene, shapes: dict[str, np.ndarray], settings: dict[str, Any]
) -> tuple[np.ndarray, str]:
    """min ρ [mm] of every cam shape on the study's angle grid: the kernel laws through
    :func:`studies.scenes.cam_radius.min_radii` (rise laws by their shape groups), lift
    tables through the scene, both coarser beyond the scan budget (and what to say then)."""
    step = math.degrees(settings["angle_step"])
    table = shapes["law"] == "table"
    radius = np.empty(table.size)
    kernel = take_points(shapes, np.flatnonzero(~table)) if table.any() else shapes
    radius[~table], scanned = cam_radius.min_radii(
        codes(kernel["law"], LAW_CODES),
        np.asarray(kernel["lift"], dtype=float),
        np.asarray(kernel["rise_angle"], dtype=float),
        np.asarray(kernel["base_radius"], dtype=float),
        kernel["polydyne_coefficients"],
        lambda some: kernel_inputs(take_points(kernel, some)),
        step,
    )
    radius[~table] *= MM
    if table.any():
        coarse = cam_radius.scan_step_deg(int(table.sum()), step)
        tables = take_points(shapes, np.flatnonzero(table))
        radius[table] = _min_radius(scene, tables, settings | {"angle_step": math.radians(coarse)})
    return radius, scanned


def _distinct(points: dict[str, np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """The first design point of each distinct cam shape and the shape of each point."""
    columns = [np.asarray(points[name]) for name in SHAPE if name in points]
    return distinct([*columns, np.asarray(points["polydyne_coefficients"], dtype=float)])


def _min_radius(
    scene: Scene, points: dict[str, np.ndarray], settings: dict[str, Any]
) -> np.ndarray:
    out = scene.evaluate(points, settings, ["min_radius_of_curvature"], [])
    return np.asarray(out.scalars["min_radius_of_curvature"], dtype=float)


def _convex_from(
    scene: Scene, shapes: dict[str, np.ndarray], groups: list[int], settings: dict[str, Any]
) -> list[str]:
    """Where each cam shape of ``groups`` becomes convex as its rise angle grows: bisections
    side by side, one kernel call per step for all of them."""
    if not groups:
        return []
    some = {name: values[groups].copy() for name, values in shapes.items()}
    limit = scene.parameter("rise_angle")
    top = float(limit.maximum) if limit is not None and limit.maximum is not None else 170.0

    def convex(beta_deg: np.ndarray) -> np.ndarray:
        some["rise_angle"] = np.radians(beta_deg)
        return _min_radii(scene, some, settings)[0] > 0.0

    low = np.degrees(np.asarray(shapes["rise_angle"][groups], dtype=float))
    high = np.full(len(groups), top)
    reachable = convex(high)
    while (high - low).max() > ADVICE_RESOLUTION_DEG:
        middle = 0.5 * (low + high)
        ok = convex(middle)
        high, low = np.where(ok, middle, high), np.where(ok, low, middle)
    marks = first_convex_mark(low, convex)
    return [
        f"it is convex from rise_angle = {h:g} degree"
        if fine
        else (
            f"no rise angle up to {top:g} degree makes it convex: use a larger base_radius or "
            "a smaller lift"
        )
        for h, fine in zip(marks.tolist(), reachable, strict=True)
    ]
