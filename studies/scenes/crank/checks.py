"""Per-design-point input checks of the ``crank`` scene that read several parameters at once:
the cylinder layout and the combustion cycle. ``CrankScene.check_points`` calls each once per
distinct combination of the parameters it reads (:meth:`PointProblems.add_checked`)."""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np

EXHAUST_OPENING_DEG = 180.0  # after firing TDC: the cycle opens the exhaust at BDC


def firing_order_problem(order: np.ndarray, cylinders: float) -> str | None:
    """Why ``order`` is not a firing order of ``cylinders`` cylinders, or None."""
    shown = "[" + ", ".join(f"{v:g}" for v in order) + "]"
    if order.size == 0:
        return "firing_order is empty: list every cylinder 1…z once"
    if not np.all(order == np.round(order)):
        return f"firing_order = {shown} must list whole cylinder numbers"
    z = int(cylinders)
    numbers = [int(v) for v in order]
    issues = []
    if len(numbers) != z:
        issues.append(f"it has {len(numbers)} entries for cylinders = {z}")
    missing = sorted(set(range(1, z + 1)) - set(numbers))
    repeated = sorted({c for c in numbers if numbers.count(c) > 1})
    foreign = sorted({c for c in numbers if not 1 <= c <= z})
    if missing:
        issues.append("missing " + ", ".join(map(str, missing)))
    if repeated:
        issues.append("repeated " + ", ".join(map(str, repeated)))
    if foreign:
        issues.append("no such cylinder " + ", ".join(map(str, foreign)))
    if not issues:
        return None
    return (
        f"firing_order = {shown} must list every cylinder 1…{z} exactly once ({'; '.join(issues)})"
    )


LAYOUT_NAMES = (
    "cylinders",
    "firing_order",
    "firing",
    "layout",
    "cylinder_positions",
    "firing_angles",
)
"""The parameters :func:`layout_problems` reads."""
CYCLE_NAMES = (
    "combustion_start",
    "combustion_duration",
    "heat_input",
    "intake_pressure",
    "compression_ratio",
    "polytropic_exponent",
    "max_pressure",
)
"""The parameters :func:`cycle_problems` reads."""
CHECKED_NAMES = ("rod_ratio", *LAYOUT_NAMES, "pressure_model", "pressure_table", *CYCLE_NAMES)
"""Every parameter ``CrankScene.check_points`` reads."""


def layout_problems(points: Mapping[str, np.ndarray], i: int) -> list[str]:
    """The firing order, crankpins, positions and firing angles of design point ``i`` that do
    not fit its number of cylinders."""
    out = []
    z = points["cylinders"][i]
    problem = firing_order_problem(points["firing_order"][i], z)
    if problem:
        out.append(problem)
    kind, layout = points["firing"][i], points["layout"][i]
    if kind == "shared_crankpins" and (layout != "v" or z % 2):
        out.append(
            f"firing = 'shared_crankpins' needs layout = 'v' and an even "
            f"number of cylinders (layout = {layout!r}, cylinders = {z:g})"
        )
    positions = points["cylinder_positions"][i]
    if positions.size and positions.size != z:
        out.append(
            f"cylinder_positions has {positions.size} values for cylinders = {z:g} "
            "(one per cylinder, or none)"
        )
    given = points["firing_angles"][i]
    if kind == "given" and given.size != z:
        out.append(
            f"firing = 'given' needs one firing angle per cylinder: "
            f"firing_angles has {given.size} for cylinders = {z:g}"
        )
    return out


def cycle_problems(points: Mapping[str, np.ndarray], i: int) -> list[str]:
    """The combustion settings of design point ``i`` (``pressure_model = "cycle"``) that
    cannot work."""
    out = []
    end = math.degrees(points["combustion_start"][i] + points["combustion_duration"][i])
    if end > EXHAUST_OPENING_DEG:
        out.append(
            f"combustion_start + combustion_duration = {end:g} deg after "
            "firing TDC must be ≤ 180 deg (the exhaust opens at BDC)"
        )
    if points["heat_input"][i] != "max_pressure":
        return out
    p_c = (
        points["intake_pressure"][i]
        * points["compression_ratio"][i] ** points["polytropic_exponent"][i]
    )
    if p_c >= points["max_pressure"][i]:
        out.append(
            f"max_pressure = {points['max_pressure'][i] / 1e6:g} MPa is not "
            f"above the compression pressure p_a ε^k = {p_c / 1e6:.4g} MPa: "
            "no heat release can reach it"
        )
    return out
