"""Scene figures of a sampled design, where every sampled value is a level of its factor: a
bounded number of axes whatever the number of points (a scatter of every design point), or
not drawn with a one-line reason in the run's warnings; never a panel, line or cell per value.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from studies.common.errors import NotDrawn
from studies.define.plan import plan_text
from studies.pipeline import run_plan
from studies.scenes import get_scene
from study_text import scene_study

SAMPLES = 24  # distinct values per factor: twice the levels a figure lays out
SCATTER_AXES = 2  # the scatter and its colour bar


def sampled(
    scene: str,
    ranges: dict[str, tuple[float, float]],
    responses: list[str],
    curves: str = "[]",
    samples: int = SAMPLES,
) -> str:
    """An lhs study of ``scene`` over ``ranges``, with ``responses`` and ``curves``."""
    factors = "".join(f"[factors.{f}]\nrange = [{lo}, {hi}]\n" for f, (lo, hi) in ranges.items())
    design = f'[design]\ntype = "lhs"\nsamples = {samples}\nseed = 5\n'
    return scene_study(
        scene, responses=json.dumps(responses), curves=curves, factors=design + factors
    )


def finished(text: str, folder: Path) -> tuple[object, list[str]]:
    """The run of ``text`` (it must finish) and its warnings."""
    result = run_plan(plan_text(text), folder, progress=False)
    record = json.loads((result.folder / "run.json").read_text(encoding="utf-8"))
    assert record["status"] == "finished"
    return result, record["warnings"]


def test_luffing_figures_of_a_sampled_design_draw_every_point_on_one_axes(
    tmp_path: Path,
) -> None:
    """Before, motor_power.png had a panel per sampled friction coefficient and a line per
    sampled acceleration (the audit's 10 240-point Saltelli design never finished), and
    pass_fail_map.png a panel per friction coefficient of cells per value pair."""
    ranges = {
        "trolley_mass": (4.0, 20.0),
        "trolley_acceleration": (5.0, 30.0),
        "friction_coefficient": (0.05, 0.4),
    }
    checks = ["motor_ok", "coupling_ok", "deflection_ok", "key_ok"]
    responses = ["motor_power", "motor_rated_power", *checks]
    result, warnings = finished(sampled("luffing", ranges, responses), tmp_path)
    assert warnings == []
    for name, build in get_scene("luffing").figures().items():
        assert (result.folder / f"{name}.png").is_file()
        fig = build(result.dataset)
        assert len(fig.axes) == SCATTER_AXES, name
        assert len(fig.axes[0].collections[0].get_offsets()) == SAMPLES, name


@pytest.mark.parametrize(
    ("scene", "ranges", "responses", "curves", "figures"),
    [
        (
            "reed",
            {"length": (25.0, 40.0), "thickness": (0.2, 0.4), "width": (8.0, 12.0)},
            ["first_frequency", "first_margin", "band_min", "band_max", "events_per_revolution"],
            "[]",
            {"frequency_map": "drawn", "campbell": "drawn", "mode_shapes": "nothing to draw"},
        ),
        (
            "crank",
            {"engine_speed": (1000.0, 6000.0), "rod_ratio": (0.25, 0.35)},
            ["max_piston_velocity", "approx_error_acceleration"],
            '["engine_torque"]',
            {
                "torque_curve": "rod_ratio",
                "torque_harmonics": "rod_ratio",
                "approximation_error": "engine_speed",
            },
        ),
        (
            "valve",
            {"cam_speed": (3000.0, 7000.0), "spring_rate": (20.0, 40.0)},
            ["jump_speed"],
            '["valve_lift"]',
            {
                "jump_speed_map": "drawn",
                "valve_lift": "spring_rate",
                "surge_sweep": "nothing to draw",
            },
        ),
    ],
)
def test_other_scenes_figures_of_a_sampled_design_are_bounded_or_say_why_not(
    tmp_path: Path,
    scene: str,
    ranges: dict[str, tuple[float, float]],
    responses: list[str],
    curves: str,
    figures: dict[str, str],
) -> None:
    """``figures``: each figure's outcome, drawn on a bounded number of axes, None for lack of
    what it draws (curves, responses), or not drawn for the factor named. Before, the reed's frequency map had a
    panel per sampled width of cells per value pair, and the crank's figures a panel per
    sampled rod ratio or a line per sampled engine speed."""
    result, warnings = finished(sampled(scene, ranges, responses, curves), tmp_path)
    builders = get_scene(scene).figures()
    assert set(builders) == set(figures)
    refused = []
    for name, build in builders.items():
        if figures[name] == "drawn":
            assert len(build(result.dataset).axes) <= SCATTER_AXES, name
        elif figures[name] == "nothing to draw":
            assert build(result.dataset) is None, name
        else:
            reason = f"{figures[name]} is sampled \\({SAMPLES} distinct values"
            with pytest.raises(NotDrawn, match=reason):
                build(result.dataset)
            refused.append(f"{name}.png not drawn: {figures[name]} is sampled")
    assert sorted(w.split(" (")[0] for w in warnings) == sorted(refused)


def test_a_sample_with_few_points_is_not_laid_out_per_value_either(tmp_path: Path) -> None:
    """An audit: 12 lhs samples (not more than the 12 levels a figure lays out) gave the
    crank's torque_harmonics.png 144 empty panels, titled as held at a bore of one run and a
    mass of another: in a sample no two points share a value, so a held value selects none."""
    ranges = {"engine_speed": (1000.0, 6000.0), "rod_ratio": (0.25, 0.35), "bore": (100, 150)}
    text = sampled("crank", ranges, ["max_piston_velocity"], '["engine_torque"]', samples=12)
    result, warnings = finished(text, tmp_path)
    with pytest.raises(NotDrawn, match=r"is sampled \(12 distinct values in a lhs design\)"):
        get_scene("crank").figures()["torque_harmonics"](result.dataset)
    assert any(w.startswith("torque_harmonics.png not drawn: ") for w in warnings)
