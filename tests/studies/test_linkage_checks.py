"""The rocker and valve checks work on every chain at once; each test compares them with a
brute-force loop over the design points, one point at a time (the reference)."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest

from studies.define.plan import plan_text
from studies.scenes.checks import point_list
from studies.scenes.linkage import scene as linkage_scene
from studies.scenes.linkage import tappet as linkage_tappet
from studies.scenes.linkage.checks import linkage_point_problems
from studies.scenes.linkage.parameters import CONVEX_POLYDYNE
from studies.scenes.linkage.scene import linkage_groups
from study_text import scene_study

N = 240
DEG = math.radians(1.0)


def grid_points(n: int, law: str = "six_segment") -> dict[str, np.ndarray]:
    """The SI points of a valid rocker study of ``n`` valve lifts (then edited by the tests)."""
    levels = np.linspace(6.0, 7.8, n).round(6).tolist()
    text = scene_study(
        "rocker",
        responses='["max_valve_lift"]',
        parameters=f'law = "{law}"',
        factors=f"[factors.valve_lift]\nlevels = {levels}",
    )
    return {name: np.array(values) for name, values in plan_text(text).points.items()}


def per_point_problems(points: dict[str, np.ndarray]) -> list[str]:
    """Reference: each design point checked alone, identical messages then merged in the
    order a loop over the points first meets them."""
    found: dict[str, list[int]] = {}
    for i in range(len(points["valve_lift"])):
        one = {name: values[i : i + 1] for name, values in points.items()}
        for line in linkage_point_problems(one, *linkage_groups(one)):
            found.setdefault(line.removeprefix("design point 0: "), []).append(i)
    return [f"{point_list(idx)}: {text}" for text, idx in found.items()]


def test_problems_of_a_mixed_grid_equal_a_loop_over_its_points() -> None:
    rng = np.random.default_rng(11)
    points = grid_points(N)

    def pick(name: str, *choices: float | str) -> None:
        points[name] = rng.choice(
            np.array(choices, dtype=object if isinstance(choices[0], str) else float), N
        )

    pick("law", "six_segment", "poly345", "polydyne")
    pick("ball_radius", 10e-3, 40e-3)  # 40 mm: the valve arm cannot reach [R6]
    pick("pad_arm", 39.61e-3, 5e-3)  # 5 mm: the rocker triangle cannot close [R3]
    pick("valve_lift", 6e-3, 7.815e-3, 50e-3)  # 50 mm: out of reach [R6]
    pick("ramp_height", 0.0, 0.3e-3, 9e-3)  # 9 mm: above the nose lift
    pick("ramp_width", 10 * DEG, 15 * DEG, 0.0)
    pick("ramp_velocity", 1.0e-3, 1.5e-3)
    pick("rise_angle", 70 * DEG, 145 * DEG)  # 145° + a ramp: beyond 150°
    pick("seg2_width", points["seg2_width"][0], 80 * DEG)  # 80°: the widths cannot fit
    bad = np.array([0.0, 0.0, 3.0, -2.5] + [0.0] * (len(CONVEX_POLYDYNE) - 4))
    rows = rng.integers(0, 2, N)
    points["polydyne_coefficients"] = np.where(rows[:, None] == 0, CONVEX_POLYDYNE, bad)
    expected = per_point_problems(points)
    kinds = (
        "must be smaller in size than valve_arm",
        "rocker triangle",
        "out of reach of this rocker",
        "must be below the tappet nose lift",
        "cannot be fitted",
        "needs ramp_width > 0",
        "cannot carry",
        "violate",
        "exceeds 150 deg",
    )
    assert all(any(kind in line for line in expected) for kind in kinds)
    assert linkage_point_problems(points, *linkage_groups(points)) == expected


def test_concave_chains_count_what_a_loop_over_the_points_finds() -> None:
    # Reference: each point's own tappet table on the whole 0.5° grid (the path a run takes
    # per chain), its smallest radius of curvature r0 + h + h'' <= 0 means concave.
    points = grid_points(N, law="poly345")
    rng = np.random.default_rng(3)
    points["rise_angle"] = np.radians(rng.choice(np.linspace(45.0, 95.0, 21), N))
    points["law"] = rng.choice(np.array(["poly345", "six_segment", "cycloidal"], object), N)
    radius = np.array(
        [
            linkage_tappet.tappet_table(points, i, linkage_tappet.ADVICE_STEP_DEG).min_radius
            for i in range(N)
        ]
    )
    # The scan keeps no curves and scales each rise law by its lift: the same values to
    # rounding (r0 + H·min(f + f″) against min(r0 + h + h″)).
    scanned, said = linkage_tappet.min_radii(points, np.arange(N), linkage_tappet.ADVICE_STEP_DEG)
    np.testing.assert_allclose(scanned, radius, rtol=0.0, atol=1e-15)
    assert said == ""
    concave = radius <= 0.0
    assert 20 < concave.sum() < N - 20  # the grid straddles the convexity limit
    first, linkage = linkage_groups(points)
    warnings = linkage_tappet.concave_linkages(points, first, linkage)
    listed = [[int(i) for i in re.findall(r"(\d+)", w.split(":")[0])] for w in warnings[:10]]
    assert all(concave[idx].all() for idx in listed)
    for idx, line in zip(listed, warnings, strict=False):
        shown = re.search(r"smallest radius of curvature (\S+) mm", line)
        assert shown
        assert shown.group(1) == f"{radius[idx[0]] * 1e3:.3g}"
    more = re.search(r"(\d+) more concave cams at (\d+) more design points", warnings[-1])
    assert more, warnings[-1]
    assert sum(map(len, listed)) + int(more.group(2)) == concave.sum()


def test_rise_angle_advice_names_the_first_convex_mark_one_chain_at_a_time() -> None:
    # The claim "convex from rise_angle = X": each law alone on its own tappet table is convex
    # at X and concave 0.1° below. Rounding the bisection's convex end up named 73.8° for an
    # audit's harmonic law convex from 73.684°.
    points = grid_points(12, law="poly345")
    points["rise_angle"] = np.radians(np.linspace(40.0, 60.0, 12))
    idx = np.arange(12)

    def convex(i: int, beta_deg: float) -> bool:
        one = {name: values[i : i + 1].copy() for name, values in points.items()}
        one["rise_angle"] = np.array([math.radians(beta_deg)])
        return linkage_tappet.tappet_table(one, 0, linkage_tappet.ADVICE_STEP_DEG).min_radius > 0.0

    said = linkage_tappet._convex_from(points, idx)
    for i, line in zip(idx, said, strict=True):
        found = re.fullmatch(r"it is convex from rise_angle = ([\d.]+) degree", line)
        assert found, line
        mark = float(found.group(1))
        assert round(mark * 10) == pytest.approx(mark * 10, abs=1e-9)
        assert convex(i, mark)
        assert not convex(i, mark - 0.1)


def test_check_and_warnings_group_the_chains_once(monkeypatch: pytest.MonkeyPatch) -> None:
    calls = []

    def counted(points: dict[str, np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
        calls.append(len(points["valve_lift"]))
        return linkage_groups(points)

    monkeypatch.setattr(linkage_scene, "linkage_groups", counted)
    levels = np.linspace(6.0, 7.8, 30).round(6).tolist()
    text = scene_study(
        "rocker",
        responses='["max_valve_lift"]',
        parameters='law = "poly345"',
        factors=f"[factors.valve_lift]\nlevels = {levels}",
    )
    plan = plan_text(text)  # check_points
    plan.scene.point_warnings(plan.points, plan.settings)
    assert calls == [30]
    plan.scene.point_warnings(plan.points, plan.settings)  # forgotten after the warnings
    assert calls == [30, 30]
