"""Input errors of the cam laws and rocker geometries of the ``rocker`` and ``valve`` scenes.

Every check runs over all distinct linkages at once (numpy masks, one kernel call for the nose
lifts and one for the segment widths); a message is formatted once per distinct set of the
values it shows and names every design point it concerns, in the order a loop over the
linkages gives (:class:`~studies.scenes.checks.LoopOrder`; the checks of one linkage: geometry,
nose, segments, ramp, polydyne, event width).
"""

from __future__ import annotations

import math

import numpy as np

from studies.scenes.cam_laws import fitted_widths, polydyne_problems
from studies.scenes.checks import LoopOrder, fixed, groups_of
from studies.scenes.linkage.tappet import nose_tappet_lifts

MM = 1e3
MAX_EVENT_HALF_DEG = 150.0
"""Largest event half-width (rise + ramp) that leaves room for the closing window."""


def linkage_point_problems(
    points: dict[str, np.ndarray], first: np.ndarray, linkage: np.ndarray
) -> list[str]:
    """Input errors of the linkages (``first`` design point of each, ``linkage`` of each design
    point, as :func:`studies.scenes.linkage.scene.linkage_groups` gives them), grouped by design points
    (mm and deg shown)."""
    p = {name: np.asarray(values) for name, values in points.items()}
    found = LoopOrder()
    arm = p["lash"] + p["ball_radius"] + p["stem_height"]
    bad_arm = ~(np.abs(arm) < p["valve_arm"])
    found.add(0, bad_arm, [arm, p["valve_arm"]], lambda i: _arm_message(p, i))
    reach = p["base_radius"] + p["pad_radius"]
    low = np.abs(p["pad_arm"] - p["centre_distance"])
    high = p["pad_arm"] + p["centre_distance"]
    bad_triangle = ~((low < reach) & (reach < high))
    found.add(1, bad_triangle, [reach, low, high], lambda i: _triangle_message(p, i))
    _nose_problems(p, first, linkage, ~(bad_arm | bad_triangle), found)
    six = p["law"] == "six_segment"
    _six_segment_problems(p, six, found)
    _polydyne_problems(p, found)
    half = p["rise_angle"] + np.where(six & (p["ramp_height"] > 0.0), p["ramp_width"], 0.0)
    found.add(
        8,
        np.degrees(half) > MAX_EVENT_HALF_DEG,
        [half],
        lambda i: (
            f"the event half-width rise_angle + ramp_width = {math.degrees(half[i]):g} deg "
            f"exceeds {MAX_EVENT_HALF_DEG:g} deg: the valve event and its closing window must "
            "fit in one camshaft turn"
        ),
    )
    return found.messages()


def _arm_message(p: dict[str, np.ndarray], i: int) -> str:
    arm = p["lash"][i] + p["ball_radius"][i] + p["stem_height"][i]
    return (
        f"lash + ball_radius + stem_height = {arm * MM:g} mm must be smaller in size than "
        f"valve_arm = {p['valve_arm'][i] * MM:g} mm: β0 = asin((Δ + ρb + z)/lb) [R6]"
    )


def _triangle_message(p: dict[str, np.ndarray], i: int) -> str:
    reach = p["base_radius"][i] + p["pad_radius"][i]
    low = abs(p["pad_arm"][i] - p["centre_distance"][i])
    high = p["pad_arm"][i] + p["centre_distance"][i]
    return (
        f"base_radius + pad_radius = {reach * MM:g} mm must lie between |pad_arm − "
        f"centre_distance| = {low * MM:g} mm and pad_arm + centre_distance = {high * MM:g} mm "
        "for the rocker triangle O–Oc–A to close on the base circle [R3], [R5]"
    )


def _nose_problems(
    p: dict[str, np.ndarray],
    first: np.ndarray,
    linkage: np.ndarray,
    closes: np.ndarray,
    found: LoopOrder,
) -> None:
    """The valve lift out of reach of the rocker, or a ramp above the tappet nose lift, at the
    points whose geometry closes (the nose lift of each distinct linkage, one kernel call)."""
    checked = np.flatnonzero(closes[first])
    nose = np.full(first.size, np.nan)
    nose[checked] = nose_tappet_lifts(p, first[checked])
    nose = nose[linkage]
    reach = p["base_radius"] + p["pad_radius"] + nose
    reachable = np.isfinite(nose) & (nose > 0.0) & (reach < p["pad_arm"] + p["centre_distance"])
    found.add(
        2,
        closes & ~reachable,
        [p["valve_lift"]],
        lambda i: (
            f"valve_lift = {p['valve_lift'][i] * MM:g} mm is out of reach of this rocker: the "
            "valve arm or the triangle O–Oc–A at the nose cannot close [R3], [R6] (use a "
            "smaller valve_lift or a longer valve_arm)"
        ),
    )
    high_ramp = closes & reachable & (p["law"] == "six_segment") & (p["ramp_height"] >= nose)
    found.add(
        3,
        high_ramp,
        [p["ramp_height"], nose, p["valve_lift"]],
        lambda i: (
            f"ramp_height = {p['ramp_height'][i] * MM:g} mm must be below the tappet nose lift "
            f"{nose[i] * MM:.4g} mm that valve_lift = {p['valve_lift'][i] * MM:g} mm needs"
        ),
    )


def _six_segment_problems(p: dict[str, np.ndarray], six: np.ndarray, found: LoopOrder) -> None:
    widths, adjusted, fits = fitted_widths(p, np.flatnonzero(six))
    found.add(
        4,
        six & ~fits,
        [widths, adjusted, p["rise_angle"]],
        lambda i: (
            f"segment widths {np.round(np.degrees(widths[i]), 3).tolist()} deg cannot be fitted "
            f"to the rise_angle = {math.degrees(p['rise_angle'][i]):g} deg half-event: the "
            "fillet and segment 6 would need widths "
            f"{np.round(np.degrees(adjusted[i]), 3).tolist()} deg (must be ≥ 0)"
        ),
    )
    height, width, velocity = p["ramp_height"], p["ramp_width"], p["ramp_velocity"]
    ramp = six & (height > 0.0)
    stopped = (velocity <= 0.0) | (width <= 0.0)
    found.add(
        5,
        ramp & stopped,
        [height],
        lambda i: f"ramp_height = {height[i] * MM:g} mm needs ramp_width > 0 and ramp_velocity > 0",
    )
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):  # 2e-3 / 2e-308
        shortest = height / velocity
        fits_ramp = (shortest <= width) & (width <= 2.0 * shortest)
    found.add(
        6,
        ramp & ~stopped & ~fits_ramp,
        [width, height, velocity],
        lambda i: (
            f"ramp_width = {math.degrees(width[i]):g} deg cannot carry a {height[i] * MM:g} mm "
            f"ramp ending at {velocity[i] * MM:g} mm/rad: constant acceleration then constant "
            f"velocity needs {math.degrees(shortest[i]):.4g} ≤ ramp_width ≤ "
            f"{math.degrees(2.0 * float(shortest[i])):.4g} deg"
        ),
    )


def _polydyne_problems(p: dict[str, np.ndarray], found: LoopOrder) -> None:
    """The polydyne coefficients that are not a rise law, checked once per distinct set."""
    coefficients = np.asarray(p["polydyne_coefficients"], dtype=float)
    idx = np.flatnonzero(p["law"] == "polydyne")
    for i, members in groups_of(idx, [coefficients]):
        where = np.zeros(p["law"].size, dtype=bool)
        where[members] = True
        for j, problem in enumerate(polydyne_problems(coefficients[i])):
            found.add(7 + j / 100, where, [], fixed(problem))
