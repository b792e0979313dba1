"""The ``rocker`` scene: target lift, virtual work, convexity flags, stages, checks, caching."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest
from numpy.polynomial import polynomial as poly

from studies.define.definition import StudyFileError
from studies.define.plan import plan_text
from studies.run.runner import evaluate
from studies.scenes.linkage import scene as rocker_scene
from studies.scenes.linkage import tappet as rocker_tappet
from studies.scenes.linkage.parameters import CONVEX_POLYDYNE
from studies.scenes.rocker import RockerScene
from study_text import recorded_stages, scene_study


def study(
    responses: str = '["max_valve_lift"]',
    curves: str = "[]",
    parameters: str = "",
    factors: str = "[factors.valve_lift]\nlevels = [6.0, 7.815]",
    settings: str = "",
    scene: str = "rocker",
) -> str:
    return scene_study(
        scene,
        responses=responses,
        curves=curves,
        parameters=parameters,
        factors=factors,
        settings=settings,
    )


def test_chain_reaches_the_target_lift_and_the_published_tappet_lift() -> None:
    ev = evaluate(
        plan_text(study('["max_valve_lift", "max_tappet_lift", "cam_convex", "chain_ok"]')),
        progress=False,
    )
    # By construction [R3], [R6]: the nose of the chain gives the target valve lift exactly
    # (the nose, θ = 0, is a grid point).
    np.testing.assert_allclose(ev.scalars["max_valve_lift"], [6.0, 7.815], rtol=1e-9)
    # physics §3: 7.815 mm of valve lift is "about 6.30 mm" of tappet lift.
    assert ev.scalars["max_tappet_lift"][1] == pytest.approx(6.30, abs=0.01)
    assert (ev.scalars["cam_convex"] == 1).all()
    assert (ev.scalars["chain_ok"] == 1).all()


def test_force_ratio_curve_obeys_virtual_work() -> None:
    # Power balance (frictionless): cam force × h'(φ) ω = valve force × Y'(θ) ω, so the
    # force ratio i = h'(φ)/Y'(θ), with h' from the closed-form polydyne law at the tappet
    # angle φ in contact (numpy polynomial, independent of the kernels).
    rise = 80.0
    plan = plan_text(
        study(
            '["max_tappet_lift"]',
            '["valve_velocity", "force_ratio", "tappet_angle"]',
            parameters=f'law = "polydyne"\nrise_angle = {rise}',
            factors="[factors.lash]\nlevels = [0.05, 0.1]",
        )
    )
    ev = evaluate(plan, progress=False)
    coefficients = np.array(CONVEX_POLYDYNE)
    for i, height in enumerate(ev.scalars["max_tappet_lift"]):
        phi = np.radians(ev.curves["tappet_angle"][i])
        x = (np.clip(-np.abs(phi), -math.radians(rise), 0.0) + math.radians(rise)) / math.radians(
            rise
        )
        tappet_velocity = -np.sign(phi) * height * poly.polyval(x, poly.polyder(coefficients))
        tappet_velocity /= math.radians(rise)
        valve_velocity = ev.curves["valve_velocity"][i]
        usable = np.abs(valve_velocity) > 2.0
        assert usable.sum() > 200
        np.testing.assert_allclose(
            ev.curves["force_ratio"][i][usable],
            tappet_velocity[usable] / valve_velocity[usable],
            rtol=2e-3,
        )


def test_concave_cam_is_a_flag_not_an_error() -> None:
    # physics §3: a 3-4-5 law as high as 6.30 mm needs at least ±83° to stay convex; at ±65° the
    # closed form r0 + h + h'' = 12.5 + 6.30 (1 + ...) goes negative near the nose.
    ev = evaluate(
        plan_text(
            study(
                '["cam_convex", "min_radius_of_curvature", "chain_status", "chain_ok"]',
                parameters='law = "poly345"',
                factors="[factors.rise_angle]\nlevels = [65.0, 85.0]",
            )
        ),
        progress=False,
    )
    np.testing.assert_array_equal(ev.scalars["cam_convex"], [0.0, 1.0])
    assert ev.scalars["min_radius_of_curvature"][0] < 0.0 < ev.scalars["min_radius_of_curvature"][1]
    assert ev.scalars["chain_status"][0] % 2 == 1  # ROCKER_CONCAVE_CAM flag
    np.testing.assert_array_equal(ev.scalars["chain_ok"], [0.0, 1.0])


def test_the_valve_acceleration_does_not_grow_as_the_grid_is_refined() -> None:
    # The lash take-up is a step in valve velocity (Y is clipped at 0, [R6]), not an
    # acceleration: a quantity of the continuous curve must not depend on the grid. Differenced
    # across that step, max_valve_acceleration grew as 1/step with lash (151 mm/rad² at 0.2°,
    # 1435 at 0.02° for lash 0.05 mm) while without lash it converged (26.13).
    values = {}
    for step in (0.2, 0.02):
        ev = evaluate(
            plan_text(
                study(
                    '["max_valve_acceleration", "min_valve_acceleration"]',
                    parameters='law = "poly345"\nrise_angle = 80.0\npad_arm = 42.0\n'
                    "valve_arm = 35.0\nbase_radius = 13.5",
                    factors="[factors.lash]\nlevels = [0.0, 0.05, 0.2]",
                    settings=f"angle_step = {step}",
                )
            ),
            progress=False,
        )
        values[step] = ev.scalars
    for name in ("max_valve_acceleration", "min_valve_acceleration"):
        np.testing.assert_allclose(values[0.02][name], values[0.2][name], rtol=2e-3)
    # the lash moves the acceleration as it moves the geometry: by a few per cent, not 10x
    high = values[0.02]["max_valve_acceleration"]
    np.testing.assert_allclose(high[1:], high[0], rtol=0.1)


def test_opening_and_closing_are_located_between_the_grid_points() -> None:
    # Reference: the first and last open points of a 0.002° grid (within 0.002° of the roots
    # by construction). On a 0.5° grid the open grid points made the duration up to two steps
    # short (an audit: 7.3° against 7.429°); located, it is within 0.02° where the lash is
    # taken up at a finite velocity.
    def angles(step: float) -> dict[str, np.ndarray]:
        names = '["valve_opening_angle", "valve_closing_angle", "valve_open_duration"]'
        text = study(
            names,
            parameters='law = "poly345"\nrise_angle = 80.0',
            factors="[factors.lash]\nlevels = [0.05, 0.3]",
            settings=f"angle_step = {step}",
        )
        return evaluate(plan_text(text), progress=False).scalars

    coarse, fine = angles(0.5), angles(0.002)
    for name in ("valve_opening_angle", "valve_closing_angle", "valve_open_duration"):
        np.testing.assert_allclose(coarse[name], fine[name], rtol=0, atol=0.02)


def test_kinematic_responses_run_only_the_needed_stages() -> None:
    plan = plan_text(study('["max_tappet_lift", "min_radius_of_curvature"]'))
    assert plan.stages == ("tappet",)
    with recorded_stages(plan.scene) as calls:
        evaluate(plan, progress=False)
    assert set(calls) == {"tappet"}


@pytest.fixture
def counted(monkeypatch: pytest.MonkeyPatch) -> list[int]:
    """One entry per call of the cam kinematics kernel that makes a tappet law."""
    calls: list[int] = []
    kernel = rocker_tappet.cb.cam_kinematics_batch

    def counting(*args):
        calls.append(1)
        return kernel(*args)

    monkeypatch.setattr(rocker_tappet.cb, "cam_kinematics_batch", counting)
    return calls


def test_points_sharing_a_chain_compute_it_once(counted: list[int]) -> None:
    plan = plan_text(
        study(
            '["max_valve_lift"]',
            scene="valve",
            factors="[factors.cam_speed]\nlevels = [3000.0, 4000.0, 5000.0]\n"
            "[factors.spring_rate]\nlevels = [20.0, 30.0]",
        )
    )
    scene = RockerScene()
    for _ in range(2):
        scene.evaluate(plan.points, plan.settings, ["max_valve_lift"], [])
    assert len(counted) == 1


def test_a_chunk_with_more_linkages_than_the_cache_makes_each_tappet_law_once(
    counted: list[int],
) -> None:
    """The cross-chunk cache holds CACHE_SIZE laws; a chunk of more linkages used to make each
    again in the rocker stage after the tappet stage had evicted it (a noise study over the lash
    made every law three times). Counted: one cam kinematics call per distinct linkage."""
    lashes = np.round(np.linspace(0.05, 0.15, rocker_scene.CACHE_SIZE + 6), 6)
    plan = plan_text(study(factors=f'[factors.lash]\nlevels = {lashes.tolist()}\nunits = "mm"'))
    assert plan.stages == ("tappet", "rocker")
    RockerScene().evaluate(plan.points, plan.settings, ["max_valve_lift"], [])
    assert len(counted) == lashes.size


def test_a_linkage_is_walked_once_for_every_grid_of_a_valve_point(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    # A valve point reads its linkage on several grids (kinematics, window, the excitation
    # tables of its run and of its error bar's companion; under a tolerance five or six):
    # the walk over the tappet table (0.4 ms of each) is made once per linkage as designed
    # and once with the stem raised by the lash (dopri's unclipped lift), then resampled.
    walks: list[int] = []
    kernel = rocker_scene.rocker.rocker_walk

    def counting(*args: object) -> int:
        walks.append(1)
        return kernel(*args)

    monkeypatch.setattr(rocker_scene.rocker, "rocker_walk", counting)
    plan = plan_text(
        study(
            '["max_lift", "error_estimate"]',
            scene="valve",
            settings='integrator = "dopri"',
            factors="[factors.valve_lift]\nlevels = [6.0, 7.815]\n"
            "[factors.cam_speed]\nlevels = [3000.0, 5000.0]",
        )
    )
    scene = type(plan.scene)()  # its own caches: other tests' walks are not counted
    responses = ["max_lift", "error_estimate"]
    output = scene.evaluate(plan.points, plan.settings, responses, [])
    assert np.isfinite(output.scalars["error_estimate"]).all()
    assert len(walks) == 2 * 2


LIFTS = "[factors.valve_lift]\nlevels = [6.0, 7.815]"


@pytest.mark.parametrize(
    ("parameters", "settings", "factors", "expected"),
    [
        (
            "pad_arm = 5.0",
            "",
            LIFTS,
            (
                "design points 0–1: base_radius + pad_radius = 42.5 mm must lie between "
                "|pad_arm − centre_distance| = 25.28 mm and pad_arm + centre_distance = 35.28 mm"
            ),
        ),
        ("ball_radius = 40.0", "", LIFTS, "lash + ball_radius + stem_height = 41.7 mm"),
        (
            "valve_arm = 12.0",
            "",
            "[factors.valve_lift]\nlevels = [6.0, 25.0]",
            "design point 1: valve_lift = 25 mm is out of reach of this rocker",
        ),
        ("", "angle_step = 0.3", LIFTS, "setting angle_step = 0.3 deg is not allowed"),
        (
            'law = "polydyne"\npolydyne_coefficients = [0.0, 0.0, 3.0, -2.5]',
            "",
            LIFTS,
            "violate f(1) = 1, f'(1) = 0",
        ),
        (
            "ramp_height = 0.3\nramp_width = 10.0\nramp_velocity = 1.0",
            "",
            LIFTS,
            "ramp_width = 10 deg cannot carry a 0.3 mm ramp",
        ),
        (
            "rise_angle = 145.0\nramp_height = 0.3\nramp_width = 15.0\nramp_velocity = 1.5",
            "",
            LIFTS,
            "rise_angle + ramp_width = 160 deg exceeds 150 deg",
        ),
    ],
)
def test_bad_inputs_name_parameter_value_and_allowed(
    parameters: str, settings: str, factors: str, expected: str
) -> None:
    with pytest.raises(StudyFileError) as info:
        plan_text(study(parameters=parameters, settings=settings, factors=factors))
    assert expected in str(info.value)


def test_chain_keys_match_a_loop_over_the_points() -> None:
    # Brute force: group the design points with a dict keyed by each point's chain tuple.
    rng = np.random.default_rng(5)
    n = 500
    points = {name: np.full(n, 1.5) for name in rocker_scene.KEY_NAMES}
    varied = list(rocker_scene.KEY_NAMES)[:3]
    for name in varied:
        points[name] = rng.choice([1.0, 2.0, 3.0], n)
    coefficients = np.tile([0.0, 1.0, 2.0], (n, 1))
    coefficients[:, 1] = rng.choice([1.0, 4.0], n)
    points["polydyne_coefficients"] = coefficients
    expected: dict[tuple, list[int]] = {}
    for i in range(n):
        key = (
            *(points[name][i] for name in rocker_scene.KEY_NAMES),
            tuple(coefficients[i].tolist()),
        )
        expected.setdefault(key, []).append(i)
    got = rocker_scene.linkage_keys(points)
    assert {k: v.tolist() for k, v in got.items()} == expected
    assert len(got) == 3 * 3 * 3 * 2


def test_a_large_concave_grid_is_warned_in_a_few_lines_counting_what_the_run_flags() -> None:
    """400 chains: ten warned one by one, the rest counted in one line. The count is checked
    against the run's own per-point flag ``cam_convex`` (computed per chain on the scene's
    tappet grid; the check scans at 0.5°, so a marginal cam may differ: at most 1 %)."""
    levels = (
        f"[factors.valve_lift]\nlevels = {np.linspace(5.0, 9.0, 20).tolist()}\n"
        f"[factors.rise_angle]\nlevels = {np.linspace(50.0, 100.0, 20).tolist()}"
    )
    plan = plan_text(study('["cam_convex"]', parameters='law = "poly345"', factors=levels))
    warnings = plan.scene.point_warnings(plan.points, plan.settings)
    concave = evaluate(plan, progress=False).scalars["cam_convex"] == 0.0
    assert 100 < concave.sum() < 390  # the grid straddles the convexity limit
    assert len(warnings) == 11
    listed = [int(i) for w in warnings[:10] for i in re.findall(r"design point (\d+):", w)]
    assert concave[listed].all()
    more = re.search(r"(\d+) more concave cams at (\d+) more design points", warnings[-1])
    assert more, warnings[-1]
    assert abs(len(listed) + int(more.group(2)) - concave.sum()) <= 0.01 * concave.sum()
