"""A scene's physical checks run over the distinct combinations of the parameters they read
(``DesignPoints.distinct``), not over every design point (issue #28: a 10⁷-point study of
operating factors has one cam to check). The reference is the same check over every point,
the columns made whole (a plain dict is checked point by point, as before): messages, their
order and the design points they name must be equal, on full factorials (combinations from
the level counts), arrays (combinations found in the codes) and studies with noise."""

from __future__ import annotations

import numpy as np
import pytest

from studies.define.plan import Plan, plan_study, plan_text
from studies.scenes import design_points
from studies.scenes.checks import per_noise_case, point_list
from studies.scenes.design_points import DesignPoints
from study_text import scene_study

VALVE_FACTORS = """
[factors.valve_lift]
levels = [6.0, 7.0, 7.5]
[factors.cam_speed]
levels = [3000.0, 4000.0, 5000.0]
[factors.ball_radius]
levels = [5.0, 6.0]
[factors.seat_stiffness]
levels = [9000.0, 12000.0]
[factors.equivalent_mass]
levels = [0.05, 0.06]
[factors.spring_preload]
levels = [200.0, 220.0]
"""
BAD_VALVE_LEVELS = {  # factor: (level, SI value that some check refuses)
    "valve_lift": (2, 50e-3),  # out of reach of the rocker [R6]
    "ball_radius": (1, 40e-3),  # the valve arm cannot reach [R6]
    "seat_stiffness": (1, 1e11),  # more RK4 sub-steps than max_substeps
    "equivalent_mass": (0, 1e-3),  # below a third of the spring mass
}

NOISE = '[noise]\ntype = "L4"\n[noise.{name}]\ndistribution = "normal"\nsd = 2.0\n'


def valve_plan(design: str = "full_factorial", noise: str = "") -> Plan:
    text = scene_study(
        "valve",
        responses='["max_lift"]',
        settings="max_substeps = 4",
        parameters='law = "poly345"\nspring_mass = 0.03',
        factors=VALVE_FACTORS,
    )
    text = text.replace("[settings]", f'[design]\ntype = "{design}"\n[settings]') + noise
    return plan_text(text)


def spoil(points: DesignPoints, bad: dict[str, tuple[int, float]]) -> None:
    """Give one level of each factor in ``bad`` a value its check refuses (after planning,
    which refuses them)."""
    for name, (level, value) in bad.items():
        points.factors[name].levels[level] = value
    points._distinct.clear()


def whole(points: DesignPoints) -> dict[str, np.ndarray]:
    """Every point's values: the checks see a plain dict and check every point."""
    return points.at(slice(None))


@pytest.mark.parametrize(
    ("design", "noise"),
    [
        ("full_factorial", ""),
        ("L18", ""),
        ("full_factorial", NOISE.format(name="spring_preload")),  # not read by the checks
        ("full_factorial", NOISE.format(name="drive_stiffness")),  # read: every case checked
    ],
)
def test_valve_checks_over_combinations_equal_the_checks_over_every_point(
    design: str, noise: str
) -> None:
    plan = valve_plan(design, noise)
    spoil(plan.points, BAD_VALVE_LEVELS)
    scene, points = plan.scene, plan.points
    reduced = scene.check_points(points, plan.settings)
    with per_noise_case(points.cases):  # every computed point, labelled the same way
        reference = scene.check_points(whole(points), plan.settings)
    assert reduced == reference
    for text in ("valve arm", "out of reach", "spring mass", "sub-steps"):
        assert any(text in line for line in reduced), text


def test_the_combinations_of_a_full_factorial_number_back_to_its_design_points() -> None:
    plan = valve_plan()
    points = plan.points
    values, numbering = points.distinct(["cam_speed", "ball_radius"])
    assert len(values["cam_speed"]) == 3 * 2
    every = whole(points)
    for combination in range(6):
        speed, ball = values["cam_speed"][combination], values["ball_radius"][combination]
        expected = np.flatnonzero((every["cam_speed"] == speed) & (every["ball_radius"] == ball))
        np.testing.assert_array_equal(numbering(np.array([combination])), expected)


def test_cam_checks_and_concave_warnings_over_combinations_equal_every_point() -> None:
    text = scene_study(
        "cam",
        responses='["max_contact_stress"]',
        parameters="",
        factors=(
            '[factors.law]\nlevels = ["poly345", "cycloidal", "harmonic"]\n'
            "[factors.base_radius]\nlevels = [5.0, 12.5, 20.0]\n"
            "[factors.rise_angle]\nlevels = [30.0, 50.0, 70.0]\n"
            "[factors.cam_speed]\nlevels = [1000.0, 2000.0, 3000.0, 4000.0]\n"
        ),
    )
    plan = plan_text(text)
    spoil(plan.points, {"rise_angle": (2, np.radians(200.0))})  # beyond a half turn
    scene, points = plan.scene, plan.points
    reduced = scene.check_points(points, plan.settings)
    assert reduced == scene.check_points(whole(points), plan.settings)
    assert reduced
    warned = scene.point_warnings(points, plan.settings)
    assert warned == scene.point_warnings(whole(points), plan.settings)
    assert any("concave" in line for line in warned)


def test_a_long_list_of_design_points_is_cut_and_counted() -> None:
    line = point_list(np.arange(0, 1000, 2))
    assert line.startswith("design points 0, 2, 4,")
    assert line.endswith("… (500 in all)")
    assert point_list(np.r_[0:5, 7]) == "design points 0–4, 7"


@pytest.mark.parametrize(
    ("study", "bad", "expected"),
    [
        ("crank_lambda_sweep", {"rod_ratio": (1, 1.2)}, "must be < 1"),
        ("v12_torque", {"max_pressure": (0, 1e5)}, "compression pressure"),
        ("reed_resonance", {"length": (0, 1e-3)}, "not a slender beam"),
    ],
)
def test_checks_of_the_other_scenes_over_combinations_equal_every_point(
    study: str, bad: dict[str, tuple[int, float]], expected: str
) -> None:
    plan = plan_study(study)
    spoil(plan.points, bad)
    reduced = plan.scene.check_points(plan.points, plan.settings)
    assert reduced == plan.scene.check_points(whole(plan.points), plan.settings)
    assert any(expected in line for line in reduced)


@pytest.mark.parametrize(
    ("design", "noise"),
    [
        ("full_factorial", ""),
        ("L18", ""),
        ("full_factorial", NOISE.format(name="spring_preload")),
        ("L18", NOISE.format(name="drive_stiffness")),
    ],
)
def test_what_a_task_carries_makes_its_chunk_exactly(design: str, noise: str) -> None:
    # DesignPoints.for_chunk: the codes and noise values of the chunk only, the same values
    plan = valve_plan(design, noise)
    points, cases = plan.points, plan.noise_cases
    for first, last in [(0, 1), (2, 5), (plan.runs - 3, plan.runs)]:
        part = slice(first * cases, last * cases)
        chunk = points.for_chunk(part)
        expected = points.at(part)
        for name, values in chunk.at(part).items():
            np.testing.assert_array_equal(values, expected[name], err_msg=name)
        assert all(v.shape[0] == part.stop - part.start for v in chunk.noise.values())


def test_large_answers_are_made_again_not_kept(monkeypatch) -> None:
    # A 10⁸-point study's checks see ~10⁶ combinations (tens of MB): kept for the whole run
    # they raised its memory. Above KEPT_COMBINATIONS an answer is made again when asked, the
    # same answer; at or below it, kept.
    points = valve_plan().points
    names = list(points.factors)
    kept_values, kept_numbering = points.distinct(names)
    assert tuple(names) in points._distinct
    points._distinct.clear()
    monkeypatch.setattr(design_points, "KEPT_COMBINATIONS", 1)
    values, numbering = points.distinct(names)
    assert not points._distinct
    assert values.keys() == kept_values.keys()
    for name in values:
        np.testing.assert_array_equal(values[name], kept_values[name])
    everything = np.arange(len(next(iter(values.values()))))
    np.testing.assert_array_equal(numbering(everything), kept_numbering(everything))
