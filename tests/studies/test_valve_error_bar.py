"""The valve error bars and the tolerance mode against scipy's reference (issues #15, #26).

Expected values: scipy's event-restarted DOP853 at rtol 1e-10 on two random samples of 200
design points (tests/valve_samples.py: ``A``, the six-segment cam with speed, seat,
preload and drive stiffness varied; ``B``, every lift law with lash, damping, mass, spring and
drive varied, 500…9000 rpm), solved once and kept in
tests/studies/data/valve_error_bar_reference.nc (made by refresh_error_bar_reference.py, which
records how; ``test_the_reference_file_is_reproduced`` solves some of its points again). The
true error of a point's lift is max |y − y_ref| over the stored curve (every 0.5 deg); of an
output, |output − reference output| (0 where neither has the event, inf where only one has it).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest
import xarray as xr
from valve_samples import (
    OUTPUTS,
    REFERENCE_FILE,
    points_digest,
    reference_of,
    sample_plan,
    sample_points,
)

from engine_kernels import valvetrain as valve
from studies.scenes.valve.parameters import INTEGRATORS
from studies.scenes.valve.reference import accuracy as acc
from studies.scenes.valve.scene import valve_rows

RPM = math.pi / 30.0
BARS = {f"{name}_error": name for name in OUTPUTS}
"""Error bar response -> the output it bounds."""
RESPONSES = [
    "error_estimate",
    "status",
    "angle_step_used",
    "tolerance_met",
    "integrator_used",
    *OUTPUTS,
    *BARS,
]
TO_RESPONSE_UNITS = {"max_lift": 1e3, "jump_start": math.degrees(1.0), "seating_velocity": 1.0}
TO_RESPONSE_UNITS["bounce_height"] = 1e3
MODES = {
    "lanes": ("lanes", 0.0),
    "rk4_switch_aware": ("rk4_switch_aware", 0.0),
    "dopri": ("dopri", 0.0),
    "1e-3": ("lanes", 1e-3),
    "1e-4": ("lanes", 1e-4),
}
"""Integrator and tolerance [mm] of each checked mode (the tolerance mode starts from lanes)."""


@pytest.fixture(scope="module")
def reference() -> xr.Dataset:
    """The stored reference, after checking it belongs to the samples of valve_samples.py."""
    with xr.open_dataset(REFERENCE_FILE) as stored:
        ds = stored.load()
    plan = sample_plan(RESPONSES, "lanes", 0.0)
    digests = dict(item.split(":") for item in ds.attrs["points_digest"].split(","))
    for name in ds["sample"].values:
        assert digests[name] == points_digest(sample_points(plan, name)), (
            f"{REFERENCE_FILE.name} was made for other points of sample {name}: run "
            "tests/studies/refresh_error_bar_reference.py"
        )
    return ds


def output_errors(run: np.ndarray, true: np.ndarray) -> np.ndarray:
    """|run − true|: 0 where neither has the event (NaN), inf where only one has it."""
    both, one = np.isnan(run) & np.isnan(true), np.isnan(run) ^ np.isnan(true)
    return np.where(both, 0.0, np.where(one, np.inf, np.abs(run - true)))


def run_modes(reference: xr.Dataset, name: str) -> dict[str, dict[str, Any]]:
    """Every mode on sample ``name``: its responses, and the true error of its lift [mm] and
    of each output (response units), with the points where that output exists."""
    true = reference.sel(sample=name)
    results = {}
    for mode, (integrator, tolerance) in MODES.items():
        plan = sample_plan(RESPONSES, integrator, tolerance)
        points = sample_points(plan, name)
        output = plan.scene.evaluate(points, plan.settings, RESPONSES, ["actual_lift"])
        scalars = output.scalars
        lift = true["lift"].values * 1e3
        errors = {"error_estimate": np.nanmax(np.abs(output.curves["actual_lift"] - lift), axis=1)}
        present = {"error_estimate": np.isfinite(lift).any(axis=1)}
        for output_name in OUTPUTS:
            exact = true[output_name].values * TO_RESPONSE_UNITS[output_name]
            reported = scalars[output_name]
            errors[f"{output_name}_error"] = output_errors(reported, exact)
            happens = np.isfinite(reported) | np.isfinite(exact)
            if output_name == "bounce_height":  # NaN: unknown (the valve had not settled)
                happens = np.isfinite(reported) & ((reported > 0.0) | (exact > 0.0))
            present[f"{output_name}_error"] = happens
        finished = scalars["status"] == 0
        results[mode] = {"scalars": scalars, "errors": errors, "present": present, "ok": finished}
    return results


@pytest.fixture(scope="module", params=["A", "B"])
def sample(request: pytest.FixtureRequest, reference: xr.Dataset) -> dict[str, dict[str, Any]]:
    return run_modes(reference, request.param)


@pytest.mark.slow
@pytest.mark.parametrize("mode", list(MODES))
def test_every_error_bar_bounds_its_true_error(
    sample: dict[str, dict[str, Any]], mode: str
) -> None:
    # Issue #26: every *_error bar bounds its output's true error in >= 95 % of both samples
    # and is within 10x of it in >= 90 %; never NaN for a finished point.
    result = sample[mode]
    assert result["ok"].mean() > 0.95
    report = []
    for bar_name, errors in result["errors"].items():
        points = result["ok"] & result["present"][bar_name]
        bar, error = result["scalars"][bar_name][points], errors[points]
        assert not np.isnan(bar).any(), bar_name
        bound = error <= bar
        useful = bound & (bar <= 10.0 * error)
        report.append(f"{bar_name} n={points.sum()} {bound.mean():.3f} {useful.mean():.3f}")
        assert bound.mean() >= 0.95, report[-1]
        assert useful.mean() >= 0.90, report[-1]
    print(f"{mode}: " + "; ".join(report))


@pytest.mark.slow
@pytest.mark.parametrize("mode", list(MODES))
def test_a_bounce_height_is_unknown_only_where_the_reference_valve_is_still_moving(
    sample: dict[str, dict[str, Any]],
    mode: str,
    reference: xr.Dataset,
    request: pytest.FixtureRequest,
) -> None:
    # A NaN bounce height says the valve's energy could still lift it above its largest
    # bounce when the window ended; a valve the reference has at rest there (its lift at the
    # window's last two grid points equal to 1e-12 m, on its seat: y < δ0 = Ps0/kz) must have
    # its height given.
    result = sample[mode]
    name = request.node.callspec.params["sample"]
    points = sample_points(sample_plan(RESPONSES, "lanes", 0.0), name)
    seat = points["spring_preload"] / points["seat_stiffness"]
    lift = reference.sel(sample=name)["lift"].values
    ends = np.array([row[np.isfinite(row)][-2:] for row in lift])
    at_rest = (np.abs(ends[:, 1] - ends[:, 0]) <= 1e-12) & (ends[:, 1] < seat)
    unknown = np.isnan(result["scalars"]["bounce_height"]) & result["ok"]
    print(f"{mode} {name}: unknown bounces at {unknown.sum()} points, at rest {at_rest.sum()}")
    assert not (unknown & at_rest).any()


@pytest.mark.slow
@pytest.mark.parametrize("mode", ["1e-3", "1e-4"])
def test_tolerance_met_is_never_claimed_above_the_tolerance(
    sample: dict[str, dict[str, Any]], mode: str
) -> None:
    # tolerance_met is a promise: no point says 1 with a true error above the tolerance; and
    # the tolerance is met by the true error on at least 99 % of the points.
    result = sample[mode]
    tolerance = float(mode)
    scalars, error = result["scalars"], result["errors"]["error_estimate"]
    finished = result["ok"]
    met = (scalars["tolerance_met"] == 1.0) & finished
    print(
        f"tolerance {mode} mm: met {met[finished].mean():.3f}, true error within "
        f"{(error[finished] <= tolerance).mean():.3f}, largest {error[finished].max():.3g} mm"
    )
    assert (error[met] <= tolerance).all()
    assert (scalars["error_estimate"][met] <= tolerance).all()
    assert (error[finished] <= tolerance).mean() >= 0.99
    used = {m: int((scalars["integrator_used"] == INTEGRATORS.index(m)).sum()) for m in INTEGRATORS}
    print(f"integrators used: {used}")
    assert used["lanes_f32"] == used["rk4"] == 0


@pytest.mark.slow
@pytest.mark.parametrize("tolerance", [1e-3, 1e-4])
def test_slow_valves_the_first_dopri_rung_leaves_above_are_met_by_the_second(
    reference: xr.Dataset, monkeypatch: pytest.MonkeyPatch, tolerance: float
) -> None:
    # Points 81 and 120 of sample A (726 and 544 rpm, a stiff seat): dopri at a tenth of
    # the tolerance per step leaves its bar above it (a bounce on landing shorter than a
    # step). The second dopri rung, as for a 100x tighter tolerance, must meet it with a bar
    # that bounds the true error (scipy reference), so that the switch-aware ladder (50-400
    # times a dopri run per point) is not reached. At 1e-4 mm since dopri dates a jump at
    # the drive force's root (tests/studies/test_dopri_jump_start.py).
    from studies.scenes.valve import error_bar

    which = np.array([81, 120])
    rungs: list[tuple[float, np.ndarray]] = []
    first_rung = error_bar.dopri_ladder

    def recorded(*args: Any) -> error_bar.Ladder:
        ladder = first_rung(*args)
        rungs.append((args[4] if len(args) > 4 else 1.0, ladder.met.copy()))
        return ladder

    monkeypatch.setattr(error_bar, "dopri_ladder", recorded)
    plan = sample_plan(RESPONSES, "lanes", tolerance)
    points = {k: v[which] for k, v in sample_points(plan, "A").items()}
    scalars = plan.scene.evaluate(points, plan.settings, RESPONSES, ["actual_lift"])
    assert [(t, met.tolist()) for t, met in rungs[:2]] == [
        (1.0, [0.0, 0.0]),
        (error_bar.DOPRI_RETRY, [1.0, 1.0]),
    ]
    lift = reference.sel(sample="A", point=which)["lift"].values * 1e3
    error = np.nanmax(np.abs(scalars.curves["actual_lift"] - lift), axis=1)
    assert (scalars.scalars["integrator_used"] == INTEGRATORS.index("dopri")).all()
    assert (scalars.scalars["tolerance_met"] == 1.0).all()
    assert (error <= scalars.scalars["error_estimate"]).all()
    assert (scalars.scalars["error_estimate"] <= tolerance).all()


@pytest.mark.slow
def test_the_reference_file_is_reproduced(reference: xr.Dataset) -> None:
    # The stored reference is what valve_samples.py solves today: two points of each sample
    # (one of them separating) solved again, lift within 10 nm over the curve and outputs to
    # 1e-5 relative. Not closer: on another CPU the solver does not repeat its own last bits
    # (NumPy's vectorised sin and pow round differently on AVX-512 than on AVX2, and the
    # adaptive steps follow): measured on an AVX-512 machine against the stored file (made
    # where NumPy's power equals the C library's), 0.58 nm and 4.7e-7 relative (seating
    # velocity, bounce height), far below the µm bars this file checks.
    plan = sample_plan(RESPONSES, "lanes", 0.0)
    for name, which in (("A", np.array([0, 9])), ("B", np.array([0, 1]))):
        points = sample_points(plan, name)
        lift, outputs = reference_of(plan, points, which)
        stored = reference.sel(sample=name, point=which)
        np.testing.assert_allclose(lift, stored["lift"].values, rtol=0, atol=1e-8)
        for j, output_name in enumerate(OUTPUTS):
            np.testing.assert_allclose(outputs[:, j], stored[output_name].values, rtol=1e-5)


def factorial_errors(
    modes: tuple[tuple[str, float], ...], speeds: list[float], seats: list[float], table_deg: float
) -> list[tuple[dict[str, np.ndarray], np.ndarray]]:
    """Each (integrator, tolerance [mm]) on the factorial of speeds [rpm] × seats [N/mm]: its
    responses and the true error of its lift [mm] against a reference on a ``table_deg`` table."""
    results = []
    for integrator, tolerance in modes:
        plan = sample_plan(RESPONSES, integrator, tolerance)
        points = {k: v.copy() for k, v in plan.points.items()}
        pairs = [(n, kz) for n in speeds for kz in seats]
        points = {k: np.repeat(v[:1], len(pairs), axis=0) for k, v in points.items()}
        points["cam_speed"] = np.array([n for n, _ in pairs]) * RPM
        points["seat_stiffness"] = np.array([kz for _, kz in pairs]) * 1e3
        output = plan.scene.evaluate(points, plan.settings, RESPONSES, ["actual_lift"])
        lift = reference_lifts(plan, points, table_deg)
        errors = np.nanmax(np.abs(output.curves["actual_lift"] - lift * 1e3), axis=1)
        results.append((output.scalars, errors))
    return results


def reference_lifts(plan: Any, points: dict[str, np.ndarray], table_deg: float) -> np.ndarray:
    """Reference lift [m] on the curve axis (NaN outside the window) on a ``table_deg`` table."""
    scene = plan.scene
    state = scene.start(points, plan.settings, [], [])
    axis = scene.curve_coordinate(plan.settings)
    lift = np.full((len(points["cam_speed"]), axis.size), np.nan)
    for key, idx in state.groups.items():
        fine = scene.excitation(state, key, 2.0 * table_deg, unclipped=True)
        start, stop = scene.window(state, key)
        inside = (axis >= start) & (axis <= stop)
        theta = np.radians(axis[inside])
        for i, row in zip(idx, valve_rows(points, idx), strict=True):
            lift[i, inside] = acc.reference_lift(fine, row, theta, "DOP853", 1e-10)
    return lift


@pytest.mark.slow
def test_error_converges_with_the_tolerance_on_a_stiff_seat() -> None:
    # Issue #15: on the 1e6 N/mm seat the error did not shrink with the step (each contact
    # lasts about one sub-step and the guard kept the sub-step). The tolerance mode answers
    # these points with the adaptive Dormand–Prince rung (switches located inside its steps,
    # its table refined with the tolerance), and the true error follows the tolerance down.
    # The reference's own table is 1/1024 deg here.
    modes = (("lanes", 1e-3), ("lanes", 1e-4))
    (loose, loose_error), (tight, tight_error) = factorial_errors(
        modes, [2500.0, 7000.0], [1e6], table_deg=1.0 / 1024.0
    )
    print(f"true errors: {loose_error} mm at 1e-3, {tight_error} mm at 1e-4")
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
    plan = sample_plan(RESPONSES, "lanes", 0.0)
    points = {k: np.repeat(v[:1], len(combos), axis=0) for k, v in plan.points.items()}
    points["cam_speed"] = np.array([c[0] for c in combos]) * RPM
    points["seat_stiffness"] = np.array([c[1] for c in combos]) * 1e3
    points["drive_damping"] = np.array([c[2][0] for c in combos])
    points["seat_damping"] = np.array([c[2][1] for c in combos])
    output = plan.scene.evaluate(points, plan.settings, RESPONSES, ["actual_lift"])
    status, bar = output.scalars["status"], output.scalars["error_estimate"]
    finished = status == 0
    assert np.isfinite(bar[finished]).all()
    assert np.isnan(bar[~finished]).all()
    refused = [valve.VALVE_STATUS_NAMES[int(s)] for s in status[~finished]]
    assert set(refused) == {"substep_limit"}
    assert finished.sum() >= len(combos) // 2
    checked = np.array([c[0] >= 3500.0 and c[1] <= 1e6 for c in combos])
    lift = reference_lifts(
        plan, {k: v[checked] for k, v in points.items()}, acc.REFERENCE_TABLE_DEG
    )
    error = np.nanmax(np.abs(output.curves["actual_lift"][checked] - lift * 1e3), axis=1)
    assert (error <= bar[checked]).all()
