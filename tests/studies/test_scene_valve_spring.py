"""The valve scene's spring-model ladder [V4]: which rung runs, what it answers, surge
resonances at the cam orders, the ladder scene and the two shipped spring studies."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from engine_kernels import valvetrain as valve
from engine_kernels.valvetrain.spring_chain import layout as sc
from engine_kernels.valvetrain.spring_chain.one_case import spring_chain_response
from studies.define.definition import StudyFileError
from studies.define.plan import plan_study, plan_text
from studies.pipeline import run_plan
from studies.run.runner import evaluate
from studies.scenes.valve import spring
from study_text import recorded_stages, run, scene_study

SPRING_MASS = 0.015  # kg, scene default
EQUIVALENT_MASS = 0.04252  # kg, scene default [V1] (includes SPRING_MASS/3)
SPRING_RATE = 30e3  # N/m, scene default
DYNAMIC = '["max_lift", "jump_start", "seating_velocity", "max_contact_force", "status"]'
WINDOW = 1.035  # search window around each order speed
SURGE = '["surge_amplitude", "min_retainer_force_ratio", "coil_clash_count"]'


def study(
    responses: str = DYNAMIC,
    settings: str = "",
    factors: str = "[factors.cam_speed]\nlevels = [3000.0, 6000.0]\nunits = 'rpm'",
    scene: str = "valve",
    parameters: str = "",
    curves: str = "[]",
) -> str:
    return scene_study(
        scene,
        responses=responses,
        curves=curves,
        parameters=parameters,
        factors=factors,
        settings=settings,
    )


@pytest.fixture
def chain_calls(monkeypatch: pytest.MonkeyPatch) -> list[str]:
    """Names of the chain runs the scene makes (single event, several revolutions)."""
    calls: list[str] = []
    for name in ("run_chain", "steady_surge"):
        original = getattr(spring, name)

        def counted(*args: Any, _name: str = name, _fn: Any = original, **kwargs: Any) -> Any:
            calls.append(_name)
            return _fn(*args, **kwargs)

        monkeypatch.setattr(spring, name, counted)
    return calls


# --- which rung runs --------------------------------------------------------------------------
def test_lumped_dynamics_and_kinematics_never_run_the_chain(chain_calls: list[str]) -> None:
    run(study())
    run(study('["max_valve_lift", "max_valve_acceleration"]'))
    assert chain_calls == []


def test_surge_responses_run_the_chain_and_leave_the_lumped_answers_alone(
    chain_calls: list[str],
) -> None:
    lumped = run(study())
    both = run(study(DYNAMIC[:-1] + ", " + SURGE[1:]))
    assert set(chain_calls) == {"run_chain"}  # one call per chunk of design points
    for name in ("max_lift", "jump_start", "seating_velocity", "max_contact_force"):
        np.testing.assert_array_equal(both.scalars[name], lumped.scalars[name])
    assert (both.scalars["surge_amplitude"] > 0.0).all()


@pytest.mark.parametrize(
    ("model", "stages"),
    [
        # the lumped rung answers the dynamics, the chain (surge stage) the spring responses
        ("lumped", ["tappet", "rocker", "dynamics", "surge"]),
        # under multi_mass the chain answers both: the surge stage runs once, dynamics never
        ("multi_mass", ["tappet", "rocker", "surge"]),
    ],
)
def test_the_spring_model_decides_which_stage_answers_the_dynamics(
    model: str, stages: list[str], chain_calls: list[str]
) -> None:
    plan = plan_text(study(DYNAMIC[:-1] + ", " + SURGE[1:], settings=f'spring_model = "{model}"'))
    with recorded_stages(plan.scene) as calls:
        evaluate(plan, progress=False)
    assert calls == stages + stages  # the runner's one-point warm-up, then the one chunk
    assert list(plan.stages) == stages  # what `check` and `run` print is what runs
    assert chain_calls == ["run_chain", "run_chain"]  # one chain run per evaluation


def test_multi_mass_answers_are_the_chain_kernels(chain_calls: list[str]) -> None:
    """The scene's multi-mass answers against a direct kernel call on rows written here from
    the scene's defaults: valve-side mass = equivalent mass − m_s/3 [V1], 8 coil masses."""
    settings = 'spring_model = "multi_mass"\nspring_masses = 8'
    plan = plan_text(study(settings=settings, curves='["actual_lift"]'))
    ev = evaluate(plan, progress=False)
    assert set(chain_calls) == {"run_chain"}  # one call per chunk of design points
    scene, key = plan.scene, None
    state = scene.start(plan.points, plan.settings, list(plan.responses), [])
    key = next(iter(state.groups))
    table, table_step, start = scene.excitation(state, key, 0.5)
    flags = valve.valve_settings(max_substeps=int(plan.settings["max_substeps"]))
    for i, rpm in enumerate((3000.0, 6000.0)):
        row = np.zeros(len(sc.CHAIN_PARAM_NAMES))
        row[sc.SC_SPEED] = rpm * math.pi / 30.0
        row[sc.SC_VALVE_MASS] = EQUIVALENT_MASS - SPRING_MASS / 3.0
        row[sc.SC_DRIVE_STIFFNESS] = 1.17e7
        row[sc.SC_DRIVE_DAMPING] = 150.0
        row[sc.SC_SPRING_RATE] = SPRING_RATE
        row[sc.SC_PRELOAD] = 205.8
        row[sc.SC_SEAT_STIFFNESS] = 5e7
        row[sc.SC_SEAT_DAMPING] = 900.0
        row[sc.SC_SPRING_MASS] = SPRING_MASS
        row[sc.SC_SPRING_MASSES] = 8
        row[sc.SC_SPRING_DAMPING_RATIO] = 0.02
        row[sc.SC_CLASH_TRAVEL] = 9.5e-3
        row[sc.SC_CLASH_STIFFNESS] = 1e7
        row[sc.SC_CLASH_DAMPING] = 10.0
        out = np.empty(len(sc.CHAIN_OUTPUT_NAMES))
        trace = np.empty((len(sc.CHAIN_CURVE_NAMES), (table.shape[1] - 1) // 2 + 1))
        spring_chain_response(table, table_step, start, row, flags, out, trace)
        assert ev.scalars["max_lift"][i] == pytest.approx(out[sc.CO_MAX_LIFT] * 1e3, rel=1e-12)
        assert ev.scalars["seating_velocity"][i] == pytest.approx(
            out[sc.CO_SEATING_VELOCITY], rel=1e-12
        )
        lift = ev.curves["actual_lift"][i]
        stored = lift[np.isfinite(lift)]
        np.testing.assert_allclose(stored, trace[sc.CC_LIFT] * 1e3, rtol=1e-12)
    assert np.isnan(ev.scalars["jump_start"][0])
    assert ev.scalars["jump_start"][1] < 0.0


def test_requests_the_multi_mass_model_cannot_answer_are_refused() -> None:
    text = study('["max_acceleration"]', 'spring_model = "multi_mass"')
    with pytest.raises(StudyFileError, match=r"max_acceleration.*spring_model = 'lumped'"):
        plan_text(text)
    text = study(settings='spring_model = "multi_mass"\ntolerance = 0.001')
    with pytest.raises(StudyFileError, match="tolerance"):
        plan_text(text)
    with pytest.raises(StudyFileError, match=r"spring_mass = 0\.2 kg"):
        plan_text(study(parameters="spring_mass = 0.2"))
    with pytest.raises(StudyFileError, match="spring_masses"):
        plan_text(study(settings='spring_model = "multi_mass"\nspring_masses = 25'))


def test_chain_jump_speed_brackets_the_first_separation() -> None:
    """The multi-mass jump speed against brute force: the chain follows the cam 0.5 % below
    it and separates at it (the search's relative tolerance is 1e-3)."""
    settings = 'spring_model = "multi_mass"\nspring_masses = 4'
    found = run(study('["jump_speed"]', settings)).scalars["jump_speed"][0]
    factors = f"[factors.cam_speed]\nlevels = [{0.995 * found}, {found}]\nunits = 'rpm'"
    jumps = run(study('["follows_cam"]', settings, factors)).scalars["follows_cam"]
    np.testing.assert_array_equal(jumps, [1.0, 0.0])


# --- surge resonance ---------------------------------------------------------------------------
def test_surge_peaks_where_a_cam_order_meets_the_first_surge_frequency() -> None:
    """Steady-state surge (8 revolutions, ζ_s = 0.5 %, no coil clash) over a 10-rpm sweep below the jump
    speed: the largest surge amplitude within ±3.5 % of each order speed 60·f_1/j lies within
    3 % of it, f_1 = the 8-mass chain's closed form [V4] written here."""
    masses = 8
    f1 = 2.0 * math.sqrt((masses + 1) * SPRING_RATE * masses / SPRING_MASS)
    f1 *= math.sin(math.pi / (2 * (masses + 1))) / (2.0 * math.pi)
    speeds = np.arange(2940.0, 4121.0, 10.0)
    factors = f"[factors.cam_speed]\nlevels = {speeds.tolist()}\nunits = 'rpm'"
    settings = f'spring_model = "multi_mass"\nspring_masses = {masses}\nrevolutions = 8'
    out = run(
        study(
            '["surge_amplitude", "surge_frequency", "follows_cam"]',
            settings,
            factors,
            parameters="spring_damping_ratio = 0.005",
        )
    ).scalars
    assert out["surge_frequency"] == pytest.approx(f1, rel=1e-12)
    assert (out["follows_cam"] == 1.0).all()  # below the jump speed: the valve follows
    amplitude = out["surge_amplitude"]
    orders = [j for j in range(1, 40) if speeds[0] * WINDOW < 60.0 * f1 / j < speeds[-1] / WINDOW]
    assert len(orders) >= 3
    for j in orders:
        at = 60.0 * f1 / j
        near = np.abs(speeds / at - 1.0) <= WINDOW - 1.0
        peak = speeds[near][np.argmax(amplitude[near])]
        assert abs(peak / at - 1.0) <= 0.03, (j, at, peak)
        edges = amplitude[near][[0, -1]]
        assert amplitude[near].max() > 1.3 * edges.min()  # a peak, not a slope


# --- the ladder scene and the shipped studies --------------------------------------------------
def test_ladder_rungs_equal_the_valve_scene_with_that_model() -> None:
    factors = "[factors.spring_masses]\nlevels = [0, 4]\n[factors.cam_speed]\nlevels = [5000.0]"
    ladder = run(
        study(DYNAMIC[:-1] + ', "surge_amplitude"]', scene="valve_spring_ladder", factors=factors)
    ).scalars
    one = "[factors.cam_speed]\nlevels = [5000.0, 5001.0]"
    lumped = run(study(factors=one)).scalars
    chain = run(
        study(settings='spring_model = "multi_mass"\nspring_masses = 4', factors=one)
    ).scalars
    for name in ("max_lift", "seating_velocity", "max_contact_force"):
        assert ladder[name][0] == lumped[name][0]
        assert ladder[name][1] == chain[name][0]
    assert ladder["surge_amplitude"][0] == 0.0  # the lumped rung has no surge by construction
    assert ladder["surge_amplitude"][1] > 0.0


@pytest.mark.parametrize("name", ["spring_model_ladder", "ohc125_spring_surge"])
def test_shipped_spring_studies_run(name: str, tmp_path: Path) -> None:
    result = run_plan(plan_study(name), tmp_path, progress=False)
    ds = result.dataset
    assert (ds["status"] == valve.STATUS_OK).all()
    lumped = ds["spring_masses"] == 0
    assert (ds["surge_amplitude"].where(lumped, drop=True) == 0.0).all()
    assert (ds["surge_amplitude"].where(~lumped, drop=True) > 0.0).all()
    figure = "spring_model_ladder.png" if name == "spring_model_ladder" else "surge_sweep.png"
    assert (result.folder / figure).stat().st_size > 10_000
    if name == "spring_model_ladder":
        assert (ds["cost_per_case"] > 0.0).all()


def test_every_dynamic_response_is_answered_or_refused_under_multi_mass() -> None:
    """Each response of the dynamics stage either comes from the chain run (finite at a point
    that follows the cam, or NaN by its meaning: no jump) or is refused by check."""
    scene_responses = plan_text(study()).scene.responses
    dynamic = [r.name for r in scene_responses if r.needs == ("tappet", "rocker", "dynamics")]
    answered = [r for r in dynamic if r not in spring.CHAIN_UNOBSERVED]
    settings = 'spring_model = "multi_mass"\nspring_masses = 2'
    out = run(study(json.dumps(answered), settings, "[factors.cam_speed]\nlevels = [3000.0]"))
    absent_when_following = {"jump_start"}
    for name in answered:
        assert np.isfinite(out.scalars[name]).all() or name in absent_when_following, name
    for name in set(dynamic) - set(answered):
        with pytest.raises(StudyFileError, match=name):
            plan_text(study(json.dumps([name]), settings))
