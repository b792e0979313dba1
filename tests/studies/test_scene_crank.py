"""The ``crank`` scene: shipped studies, checks of bad parameters, stages, closed-form plumbing."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from studies.define.definition import StudyFileError
from studies.define.plan import plan_study, plan_text
from studies.pipeline import run_plan
from studies.run.runner import evaluate
from study_text import recorded_stages, run, scene_study

RPM = math.pi / 30.0


def study(
    parameters: str = "",
    responses: str = '["max_piston_velocity"]',
    curves: str = "[]",
    factors: str = "[factors.engine_speed]\nlevels = [1000.0, 2000.0]",
    settings: str = "",
) -> str:
    return scene_study(
        "crank",
        parameters=parameters,
        responses=responses,
        curves=curves,
        factors=factors,
        settings=settings,
    )


def textbook_displacement(r, lam, alpha):
    """[K1] as written in physics §5: x = r(1 − cos α) + l(1 − cos β), sin β = λ sin α."""
    beta = np.arcsin(lam * np.sin(alpha))
    return r * (1 - np.cos(alpha)) + r / lam * (1 - np.cos(beta))


# --- shipped studies --------------------------------------------------------------------------
def test_crank_lambda_sweep_runs_and_matches_brute_force_errors(tmp_path: Path) -> None:
    result = run_plan(plan_study("crank_lambda_sweep"), tmp_path, progress=False)
    ds = result.dataset
    assert ds.sizes["run"] == 21
    assert ds["rod_ratio"].attrs["units"] == "1"
    assert ds["engine_speed"].attrs["units"] == "rpm"
    assert ds["approx_error_displacement"].attrs["units"] == "mm"
    assert ds["approx_error_acceleration"].attrs["units"] == "m/s^2"
    assert ds["approx_error_acceleration_relative"].attrs["units"] == "1"
    assert (result.folder / "results.nc").exists()
    figure = result.folder / "approximation_error.png"
    assert figure in result.files
    assert figure.stat().st_size > 10_000
    # Expected: grid maxima (0.5° steps, the study's grid) of |textbook [K1] − [K2]| and of
    # |ẍ − [K4]| with ẍ = ω² d²x/dα² from the five-point central difference of [K1]
    # (step 1e-3 rad: truncation ~h⁴, round-off ~1e-10 relative).
    alpha = np.radians(np.arange(0.0, 720.0, 0.5))
    h = 1e-3
    r = 0.090  # stroke 180 mm
    for point in range(ds.sizes["run"]):
        lam = float(ds["rod_ratio"][point])
        omega = float(ds["engine_speed"][point]) * RPM
        x = textbook_displacement(r, lam, alpha)
        x2 = r * ((1 - np.cos(alpha)) + lam / 4 * (1 - np.cos(2 * alpha)))
        assert float(ds["approx_error_displacement"][point]) == pytest.approx(
            np.abs(x - x2).max() * 1e3, rel=1e-9
        )

        def at(k, lam=lam):
            return textbook_displacement(r, lam, alpha + k * h)

        curvature = (-at(2) + 16 * at(1) - 30 * x + 16 * at(-1) - at(-2)) / (12 * h**2)
        a2 = r * (np.cos(alpha) + lam * np.cos(2 * alpha))
        expected = np.abs(curvature - a2).max()
        assert float(ds["approx_error_acceleration"][point]) == pytest.approx(
            expected * omega**2, rel=1e-5
        )
        assert float(ds["approx_error_acceleration_relative"][point]) == pytest.approx(
            expected / r, rel=1e-5
        )


def test_v12_torque_runs_with_curves_figures_and_energy_balance(tmp_path: Path) -> None:
    result = run_plan(plan_study("v12_torque"), tmp_path, progress=False)
    ds = result.dataset
    assert ds.sizes["run"] == 27
    assert ds["engine_torque"].dims == ("run", "crank_angle")
    assert ds["engine_torque"].attrs["units"] == "N*m"
    assert ds["cylinder_pressure"].attrs["units"] == "MPa"
    assert ds["crank_angle"].attrs["units"] == "degree"
    assert ds["mean_power"].attrs["units"] == "kW"
    assert "assumption" in ds["stroke"].attrs["long_name"]
    assert "NOT in the source" in ds.attrs["study_toml"]
    for name in ("torque_curve.png", "torque_harmonics.png"):
        assert (result.folder / name).stat().st_size > 10_000
    # The peak of the single-zone cycle is the max_pressure factor (the heat input is found
    # from it, kernel docstring), located between the grid points: the stored curve (1°)
    # comes within its sampling of it and never above.
    grid_peak = ds["cylinder_pressure"].max("crank_angle")
    assert (grid_peak <= ds["max_pressure"] * (1 + 1e-12)).all()
    np.testing.assert_allclose(grid_peak, ds["max_pressure"], rtol=1e-3)
    # Energy balance: mean torque × 4π = z × indicated work per cycle = 12 imep V_d; the
    # reciprocating inertia does no net work over a cycle (1° grid: sums, not integrals).
    v_d = math.pi / 4 * 0.150**2 * ds["stroke"].values * 1e-3
    work_torque = 12 * ds["imep"].values * 1e6 * v_d / (4 * math.pi)
    np.testing.assert_allclose(ds["mean_torque"].values, work_torque, rtol=2e-3)
    omega = ds["engine_speed"].values * RPM
    np.testing.assert_allclose(
        ds["mean_power"].values * 1e3, ds["mean_torque"].values * omega, rtol=1e-12
    )
    # Harmonic orders against numpy's FFT of the stored curve (engine order q/2 is harmonic q
    # of the 720° cycle). 90°/30° firing pairs: order 6 cancels (6 × 90° = 540°), 3 does not.
    torque = ds["engine_torque"].values
    amplitude = 2 * np.abs(np.fft.rfft(torque, axis=1)) / torque.shape[1]
    np.testing.assert_allclose(ds["torque_order_3"], amplitude[:, 6], rtol=1e-9)
    np.testing.assert_allclose(ds["torque_order_12"], amplitude[:, 24], rtol=1e-9)
    assert (amplitude[:, 12] < 1e-9 * amplitude[:, 6]).all()
    assert (ds["dominant_torque_order"] == 3.0).all()


def test_the_engine_torque_is_on_cylinder_1s_crank_angle_whenever_cylinder_1_fires() -> None:
    # An audit: an inline twin firing cylinder 1 at 270 deg and cylinder 2 at 0 deg stored the
    # summed torque shifted by cylinder 1's firing angle (off by 10 951 N·m at a peak of
    # 11 929 N·m), while the axis it is on, like the cylinder curves', is cylinder 1's crank
    # angle. Expected, by hand from the single-cylinder curve on the same 1 deg grid:
    # cylinder 2 runs 270 deg ahead of cylinder 1, T(a) = T1(a) + T1(a + 270 deg).
    ev = run(
        scene_study(
            "crank",
            responses='["mean_torque"]',
            curves='["cylinder_torque", "engine_torque"]',
            parameters='cylinders = 2\nlayout = "inline"\nfiring_order = [2, 1]\n'
            'firing = "given"\nfiring_angles = [270.0, 0.0]',
            factors="[factors.engine_speed]\nlevels = [3000.0, 4000.0]",
            settings="angle_step = 1.0",
        )
    )
    single = ev.curves["cylinder_torque"]
    expected = single + np.roll(single, -270, axis=1)
    np.testing.assert_allclose(ev.curves["engine_torque"], expected, rtol=1e-12, atol=1e-9)


# --- bad parameters give clear messages -------------------------------------------------------
@pytest.mark.parametrize(
    ("parameters", "factors", "expected"),
    [
        (
            "",
            "[factors.rod_ratio]\nlevels = [0.3, 1.2]",
            "design point 1: rod_ratio λ = r/l = 1.2 must be < 1",
        ),
        (
            "",
            "[factors.stroke]\nlevels = [-180.0, 180.0]",
            "stroke = -180 mm is physically impossible",
        ),
        (
            "firing_order = []",
            "[factors.engine_speed]\nlevels = [1000.0, 2000.0]",
            "firing_order = [] is empty",
        ),
        (
            'cylinders = 4\nlayout = "inline"\nfiring_order = [1, 2, 2, 4]',
            "[factors.engine_speed]\nlevels = [1000.0, 2000.0]",
            (
                "design points 0–1: firing_order = [1, 2, 2, 4] must list every cylinder 1…4 "
                "exactly once (missing 3; repeated 2)"
            ),
        ),
        (
            "cylinders = 6",
            "[factors.engine_speed]\nlevels = [1000.0, 2000.0]",
            "it has 12 entries for cylinders = 6",
        ),
        (
            'cylinders = 4\nlayout = "inline"\nfiring_order = [1, 3, 4, 2]\nfiring = "shared_crankpins"',
            "[factors.engine_speed]\nlevels = [1000.0]",
            "firing = 'shared_crankpins' needs layout = 'v'",
        ),
        (
            "max_pressure = 5.0",
            "[factors.engine_speed]\nlevels = [1000.0]",
            "max_pressure = 5 MPa is not above the compression pressure",
        ),
    ],
)
def test_bad_parameters_give_clear_messages(parameters: str, factors: str, expected: str) -> None:
    with pytest.raises(StudyFileError) as info:
        plan_text(study(parameters=parameters, factors=factors))
    assert expected in str(info.value)


def test_angle_step_must_divide_the_cycle() -> None:
    with pytest.raises(StudyFileError, match=r"angle_step = 0\.7 deg must divide 720 deg"):
        plan_text(study(settings="angle_step = 0.7"))


# --- stages -----------------------------------------------------------------------------------
def test_kinematic_responses_run_only_the_kinematics_stage() -> None:
    plan = plan_text(
        study(
            responses='["max_piston_velocity", "approx_error_acceleration"]',
            curves='["piston_velocity"]',
        )
    )
    assert plan.stages == ("kinematics",)
    with recorded_stages(plan.scene) as calls:
        ev = evaluate(plan, progress=False)
    assert calls
    assert set(calls) == {"kinematics"}
    # v_max of the exact model is at least rω (the two-term value at 90°), closed form.
    assert (ev.scalars["max_piston_velocity"] > 0.090 * np.array([1000, 2000]) * RPM).all()


def test_torque_responses_need_pressure_and_layout_stages() -> None:
    assert plan_text(study(responses='["mean_torque"]')).stages == ("pressure", "multicylinder")
    assert plan_text(study(responses='["max_side_force"]')).stages == ("pressure", "forces")


# --- closed forms through the scene -----------------------------------------------------------
@pytest.mark.parametrize("model", ["exact", "approximate"])
def test_kinematic_curves_follow_the_model_setting(model: str) -> None:
    ev = run(
        study(
            curves='["piston_displacement", "piston_acceleration"]',
            settings=f'model = "{model}"\nangle_step = 2.0',
            factors="[factors.rod_ratio]\nlevels = [0.2, 0.4]",
        )
    )
    alpha = np.radians(np.arange(0.0, 720.0, 2.0))
    r, omega = 0.090, 2600 * RPM
    for i, lam in enumerate([0.2, 0.4]):
        if model == "exact":
            x = textbook_displacement(r, lam, alpha)  # [K1]
            np.testing.assert_allclose(
                ev.curves["piston_displacement"][i], x * 1e3, rtol=1e-12, atol=1e-12
            )
        else:
            a = r * omega**2 * (np.cos(alpha) + lam * np.cos(2 * alpha))  # [K4]
            np.testing.assert_allclose(
                ev.curves["piston_acceleration"][i], a, rtol=1e-12, atol=1e-9
            )


def test_inline_four_free_forces_closed_form() -> None:
    # Inline four, firing 1-3-4-2 evenly: first orders cancel, second orders add up to
    # 4 mj r ω² λ (physics §5 [F2] summed over the four cylinders).
    ev = run(
        study(
            parameters='cylinders = 4\nlayout = "inline"\nfiring_order = [1, 3, 4, 2]',
            responses='["free_first_order_force", "free_second_order_force"]',
        )
    )
    omega = np.array([1000.0, 2000.0]) * RPM
    expected = 4 * 3.5 * 0.090 * omega**2 * 0.28 / 1e3  # kN
    np.testing.assert_allclose(ev.scalars["free_second_order_force"], expected, rtol=1e-12)
    assert np.all(np.abs(ev.scalars["free_first_order_force"]) < 1e-9 * expected)


def test_inline_three_free_moments_closed_form_and_v_layouts_have_none() -> None:
    # Inline three, firing 1-3-2 (120° throws), pitch a: both the first- and second-order
    # moments about the middle are √3·a·mj r ω² λ^(order−1) (Taylor, vol. 2, ch. 8).
    moments = '["free_first_order_moment", "free_second_order_moment"]'
    ev = run(
        study(
            parameters='cylinders = 3\nlayout = "inline"\nfiring_order = [1, 3, 2]\n'
            "cylinder_pitch = 150.0",
            responses=moments,
        )
    )
    omega = np.array([1000.0, 2000.0]) * RPM
    first = math.sqrt(3) * 0.150 * 3.5 * 0.090 * omega**2  # N m
    np.testing.assert_allclose(ev.scalars["free_first_order_moment"], first, rtol=1e-12)
    np.testing.assert_allclose(ev.scalars["free_second_order_moment"], 0.28 * first, rtol=1e-12)
    v12 = run(study(responses=moments))  # the 12V150 defaults: a V layout
    assert np.isnan(v12.scalars["free_first_order_moment"]).all()


def test_v_twin_moment_from_given_cylinder_positions() -> None:
    # 90° V-twin on one crankpin, rods side by side d apart: the first-order force rotates
    # with constant magnitude F = mj r ω² (see test_crank.py), and the two cylinders' forces,
    # d apart along the shaft, leave a couple. Expected: brute force over a revolution of
    # Σ (z_i − z̄) ẑ × F_i e_i, the cylinders' forces along their axes.
    d = 0.040
    ev = run(
        study(
            parameters='cylinders = 2\nlayout = "v"\nfiring_order = [1, 2]\n'
            'firing = "shared_crankpins"\nbank_angle = 90.0\ncylinder_positions = [0.0, 40.0]',
            responses='["free_first_order_moment", "free_first_order_force"]',
        )
    )
    omega = np.array([1000.0, 2000.0]) * RPM
    alpha = np.linspace(0, 2 * np.pi, 20_001)
    firing = np.array([0.0, np.pi / 2])  # the second cylinder fires one bank angle later
    axes = np.array([-np.pi / 4, np.pi / 4])
    arms = np.array([-d / 2, d / 2])
    force = np.cos(alpha[:, None] - firing)  # per unit mj r ω²
    mx = (-arms * force * np.cos(axes)).sum(axis=1)
    my = (arms * force * np.sin(axes)).sum(axis=1)
    expected = np.hypot(mx, my).max() * 3.5 * 0.090 * omega**2
    np.testing.assert_allclose(ev.scalars["free_first_order_moment"], expected, rtol=1e-6)
    np.testing.assert_allclose(ev.scalars["free_first_order_force"], 3.5 * 0.090 * omega**2 / 1e3)
    with pytest.raises(StudyFileError, match="cylinder_positions has 1 values for cylinders = 2"):
        plan_text(
            study(parameters="cylinders = 2\nfiring_order = [1, 2]\ncylinder_positions = [0.0]")
        )


def write_table(path: Path, angle_deg: np.ndarray, pressure_mpa: np.ndarray) -> Path:
    rows = "\n".join(f"{a:.6f},{p:.9f}" for a, p in zip(angle_deg, pressure_mpa, strict=True))
    path.write_text(
        "# crank angle [deg] from firing TDC, pressure [MPa]\nangle,pressure\n" + rows + "\n"
    )
    return path


def test_constant_pressure_table_gives_the_closed_form_gas_torque(tmp_path: Path) -> None:
    table = write_table(tmp_path / "p.csv", np.arange(-360.0, 360.0, 5.0), np.full(144, 2.0))
    ev = run(
        study(
            parameters=(
                f'pressure_model = "table"\npressure_table = "{table}"\nreciprocating_mass = 0.0'
            ),
            responses='["peak_pressure", "cylinder_mean_torque"]',
            curves='["cylinder_torque"]',
            factors="[factors.rod_ratio]\nlevels = [0.25, 0.3]",
        )
    )
    # Gas force only: M = (π D²/4)(p − p0) r sin(α + β)/cos β (physics §5), p = 2 MPa everywhere.
    alpha = np.radians(np.arange(0.0, 720.0, 1.0))
    force = math.pi / 4 * 0.150**2 * (2.0e6 - 101325.0)
    for i, lam in enumerate([0.25, 0.3]):
        beta = np.arcsin(lam * np.sin(alpha))
        torque = force * 0.090 * np.sin(alpha + beta) / np.cos(beta)
        np.testing.assert_allclose(
            ev.curves["cylinder_torque"][i], torque, rtol=1e-12, atol=1e-9 * force
        )
    np.testing.assert_allclose(ev.scalars["peak_pressure"], 2.0, rtol=1e-12)
    np.testing.assert_allclose(ev.scalars["cylinder_mean_torque"], 0.0, atol=1e-9 * force)


def test_pressure_table_firing_tdc_is_shifted_onto_the_grid(tmp_path: Path) -> None:
    # A triangular pressure pulse peaking at firing TDC (0° in the table) must land at 360° on
    # the scene's grid, and its peak be reported 0° after firing TDC.
    angle = np.arange(-360.0, 360.0, 1.0)
    pressure = 0.1 + np.clip(10.0 - np.abs(angle) / 3.0, 0.0, None)
    table = write_table(tmp_path / "pulse.csv", angle, pressure)
    ev = run(
        study(
            parameters=f'pressure_model = "table"\npressure_table = "{table}"',
            responses='["peak_pressure", "peak_pressure_angle"]',
            curves='["cylinder_pressure"]',
        )
    )
    assert np.argmax(ev.curves["cylinder_pressure"][0]) == 360
    np.testing.assert_allclose(ev.scalars["peak_pressure"], 10.1, rtol=1e-12)
    np.testing.assert_allclose(ev.scalars["peak_pressure_angle"], 0.0, atol=1e-9)


def test_missing_pressure_table_is_reported_before_running(tmp_path: Path) -> None:
    missing = tmp_path / "nope.csv"
    with pytest.raises(StudyFileError, match="no such file"):
        plan_text(study(parameters=f'pressure_model = "table"\npressure_table = "{missing}"'))
