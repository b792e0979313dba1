"""The valve error bar and the tolerance mode against scipy's reference (issue #15).

Expected values: scipy's event-restarted DOP853 (studies.scenes.valve.reference.valve_ivp:
a terminal event at every drive and seat switch, rtol 1e-10) on the same model and on the
chain's valve lift tabulated every ``acc.REFERENCE_TABLE_DEG`` (1/512 deg, finer than the
finest table the tolerance ladder uses). Its own floor, measured on eight points of this
sample at 1/64 deg: ≤ 1e-4 µm against rtol 1e-12 and against Radau, ≤ 0.023 µm against a
1/128 deg table; in violent separation the 1/64 deg table error grew to 0.1–0.3 µm and made 7
of the 200 points seem to miss 1e-4 mm (against 1/512 deg one does).
The true error of a point is max |y − y_ref| over the stored curve (every 0.5 deg).

The sample (fixed seed): camshaft 500…8000 rpm, seat stiffness 1e4…1e7 N/mm (log-uniform),
spring preload and drive stiffness ±30 % around the thesis values (205.8 N, 1.17e4 N/mm).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest

from engine_kernels import valvetrain as valve
from studies.plan import plan_text
from studies.scenes.valve import accuracy_reference as acc
from studies.scenes.valve.parameters import INTEGRATORS
from studies.scenes.valve.scene import valve_rows
from study_text import scene_study

SAMPLE = 200
SEED = 15
RPM = math.pi / 30.0
RESPONSES = '["error_estimate", "status", "angle_step_used", "tolerance_met", "integrator_used"]'


def sample_plan(integrator: str, tolerance: float, speeds: list[float], seats: list[float]) -> Any:
    """A valve study over the given camshaft speeds [rpm] and seat stiffnesses [N/mm]."""
    text = scene_study(
        "valve",
        responses=RESPONSES,
        curves='["actual_lift"]',
        settings=f'integrator = "{integrator}"\ntolerance = {tolerance}',
        factors=(
            f"[factors.cam_speed]\nlevels = {speeds}\n[factors.seat_stiffness]\nlevels = {seats}"
        ),
    )
    return plan_text(text)


def random_points(plan: Any) -> dict[str, np.ndarray]:
    """The plan's first point repeated SAMPLE times with the issue's factors drawn at random."""
    rng = np.random.default_rng(SEED)
    points = {k: np.repeat(v[:1], SAMPLE, axis=0) for k, v in plan.points.items()}
    points["cam_speed"] = rng.uniform(500.0, 8000.0, SAMPLE) * RPM
    points["seat_stiffness"] = 10.0 ** rng.uniform(4.0, 7.0, SAMPLE) * 1e3
    points["spring_preload"] = points["spring_preload"] * rng.uniform(0.7, 1.3, SAMPLE)
    points["drive_stiffness"] = points["drive_stiffness"] * rng.uniform(0.7, 1.3, SAMPLE)
    return points


def reference_lifts(
    plan: Any, points: dict[str, np.ndarray], table_deg: float
) -> tuple[np.ndarray, np.ndarray]:
    """The curve points inside the integration window, and the reference lift [m] there
    (the chain's valve lift tabulated every ``table_deg`` for the reference)."""
    scene = plan.scene
    ctx = scene.context(points, plan.settings, [], [])
    ((key, idx),) = ctx["groups"].items()
    fine = scene.excitation(ctx, key, 2.0 * table_deg)
    start, stop = scene.window(ctx, key)
    axis = scene.curve_coordinate(plan.settings)
    inside = (axis >= start) & (axis <= stop)
    theta = np.radians(axis[inside])
    rows = valve_rows(points, idx)
    return inside, np.array([acc.reference_lift(fine, row, theta, "DOP853", 1e-10) for row in rows])


def run_modes(
    modes: tuple[tuple[str, float], ...],
    speeds: list[float],
    seats: list[float],
    randomise: bool,
    table_deg: float = acc.REFERENCE_TABLE_DEG,
) -> list[tuple[dict[str, np.ndarray], np.ndarray]]:
    """Each (integrator, tolerance [mm]) on the same points: its responses and true errors
    [mm]; the points are the factorial of speeds × seats, or the random sample."""
    results = []
    reference: tuple[np.ndarray, np.ndarray] | None = None
    for integrator, tolerance in modes:
        plan = sample_plan(integrator, tolerance, speeds, seats)
        points = random_points(plan) if randomise else plan.points
        output = plan.scene.evaluate(points, plan.settings, list(plan.responses), ["actual_lift"])
        if reference is None:
            reference = reference_lifts(plan, points, table_deg)
        inside, lift = reference
        curve = output.curves["actual_lift"][:, inside] * 1e-3
        results.append((output.scalars, np.max(np.abs(curve - lift), axis=1) * 1e3))
    return results


@pytest.fixture(scope="module")
def sample() -> dict[str, tuple[dict[str, np.ndarray], np.ndarray]]:
    """The default lanes, switch-aware RK4 at 0.5 deg and dopri with their error bars, and
    the tolerance mode at 1e-3 and 1e-4 mm, on the same random points."""
    modes = {
        "lanes": ("lanes", 0.0),
        "rk4_switch_aware": ("rk4_switch_aware", 0.0),
        "dopri": ("dopri", 0.0),
        "1e-3": ("lanes", 1e-3),
        "1e-4": ("lanes", 1e-4),
    }
    results = run_modes(tuple(modes.values()), [3500.0], [5e4], randomise=True)
    return dict(zip(modes, results, strict=True))


@pytest.mark.slow
@pytest.mark.parametrize("mode", ["lanes", "rk4_switch_aware", "dopri"])
def test_error_bar_is_never_nan_bounds_the_error_and_is_useful(
    sample: dict[str, tuple[dict[str, np.ndarray], np.ndarray]], mode: str
) -> None:
    scalars, errors = sample[mode]
    finished = scalars["status"] == 0
    assert finished.mean() > 0.95
    bar = scalars["error_estimate"][finished]
    error = errors[finished]
    assert np.isfinite(bar).all()
    bound = error <= bar
    print(
        f"{mode}: bound {bound.mean():.3f}, within 10x {(bound & (bar <= 10 * error)).mean():.3f}"
    )
    assert bound.mean() >= 0.95
    assert (bound & (bar <= 10.0 * error)).mean() >= 0.90


@pytest.mark.slow
@pytest.mark.parametrize(("mode", "share"), [("1e-3", 0.99), ("1e-4", 0.95)])
def test_tolerance_is_met_by_the_true_error(
    sample: dict[str, tuple[dict[str, np.ndarray], np.ndarray]], mode: str, share: float
) -> None:
    scalars, errors = sample[mode]
    tolerance = float(mode)
    finished = scalars["status"] == 0
    met = scalars["tolerance_met"][finished] == 1.0
    within = errors[finished] <= tolerance
    print(f"tolerance {mode} mm: met {met.mean():.3f}, true error within {within.mean():.3f}")
    assert within.mean() >= share
    # tolerance_met is a promise: where it is 1 the bar, and so far the error, is within it
    assert (scalars["error_estimate"][finished][met] <= tolerance).all()
    used = scalars["integrator_used"]
    print(
        f"integrators used: { {m: int((used == INTEGRATORS.index(m)).sum()) for m in INTEGRATORS} }"
    )
    assert set(np.unique(used)) <= {
        INTEGRATORS.index("lanes"),
        INTEGRATORS.index("dopri"),
        INTEGRATORS.index("rk4_switch_aware"),
    }


@pytest.mark.slow
def test_error_converges_with_the_tolerance_on_a_stiff_seat() -> None:
    # Issue #15: on the 1e6 N/mm seat the error did not shrink with the step (each contact
    # lasts about one sub-step and the guard kept the sub-step). The tolerance mode now
    # answers these points with the adaptive Dormand–Prince rung (switches located inside
    # its steps, its table refined with the tolerance), and the true error follows the
    # tolerance down. The reference's own table is 1/1024 deg here (at 1/64 deg its floor,
    # ~0.01–0.03 µm, is as large as the errors at 1e-4 mm). Measured at 2500 and 7000 rpm:
    # 0.017 and 0.154 µm at 1e-3 mm, 0.0021 and 0.0152 µm at 1e-4 mm: 8.0× and 10.1× for the
    # tenfold tolerance (the issue asks ≥ 5×; with the switch-aware RK4 ladder alone it was
    # 2.7× at 2500 rpm, the order of the excitation table's error).
    modes = (("lanes", 1e-3), ("lanes", 1e-4))
    (loose, loose_error), (tight, tight_error) = run_modes(
        modes, [2500.0, 7000.0], [1e6], randomise=False, table_deg=1.0 / 1024.0
    )
    assert (loose["status"] == 0).all()
    assert (tight["status"] == 0).all()
    assert (loose_error <= 1e-3).all()
    assert (tight_error <= 1e-4).all()
    assert (tight_error * 5.0 <= loose_error).all()


@pytest.mark.slow
def test_extremes_get_a_bar_that_holds_or_a_status_that_says_why() -> None:
    # The stability matrix (camshaft 50…10 000 rpm, seat 1e4…1e7 N/mm, no damping or heavy
    # damping: 5000 N s/m on the drive, 1e5 on the seat). A finished point has a finite bar;
    # one the guard refuses (more sub-steps than max_substeps) has the status that says so
    # and no bar. Where the reference is affordable (it needs more than 10 000 restarts on
    # an undamped 1e7 N/mm seat, and minutes at 50 rpm) the bar must hold.
    speeds, seats = [50.0, 500.0, 3500.0, 10000.0], [1e4, 1e6, 1e7]
    dampings = [(0.0, 0.0), (5000.0, 1e5)]
    combos = [(n, kz, b) for n in speeds for kz in seats for b in dampings]
    plan = sample_plan("lanes", 0.0, [3500.0], [5e4])
    points = {k: np.repeat(v[:1], len(combos), axis=0) for k, v in plan.points.items()}
    points["cam_speed"] = np.array([c[0] for c in combos]) * RPM
    points["seat_stiffness"] = np.array([c[1] for c in combos]) * 1e3
    points["drive_damping"] = np.array([c[2][0] for c in combos])
    points["seat_damping"] = np.array([c[2][1] for c in combos])
    output = plan.scene.evaluate(points, plan.settings, list(plan.responses), ["actual_lift"])
    status, bar = output.scalars["status"], output.scalars["error_estimate"]
    finished = status == 0
    assert np.isfinite(bar[finished]).all()
    assert np.isnan(bar[~finished]).all()
    refused = [valve.VALVE_STATUS_NAMES[int(s)] for s in status[~finished]]
    assert set(refused) == {"substep_limit"}
    assert finished.sum() >= len(combos) // 2
    checked = np.array([c[0] >= 3500.0 and c[1] <= 1e6 for c in combos])
    inside, reference = reference_lifts(
        plan, {k: v[checked] for k, v in points.items()}, acc.REFERENCE_TABLE_DEG
    )
    curve = output.curves["actual_lift"][checked][:, inside] * 1e-3
    error = np.max(np.abs(curve - reference), axis=1) * 1e3
    assert (error <= bar[checked]).all()
