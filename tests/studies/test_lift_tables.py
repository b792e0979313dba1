"""Measured lift tables: CSV import, spline smoothing, and the measurable effect of smoothing."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from studies.define.plan import plan_text
from studies.run.runner import evaluate
from studies.scenes.cam.lift_tables import read_lift_table, table_kinematics

H, BETA = 8e-3, np.deg2rad(60.0)  # 8 mm cycloidal rise over 60 deg cam, nose at 0


def cycloidal(theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Closed-form rise-return cycloidal lift and acceleration (the reference)."""
    x = np.clip((BETA - np.abs(theta)) / BETA, 0.0, 1.0)
    h = H * (x - np.sin(2 * np.pi * x) / (2 * np.pi))
    a = H * 2 * np.pi * np.sin(2 * np.pi * x) / BETA**2
    return h, a


def measured_table(path: Path, noise: float, seed: int = 1) -> Path:
    """A 'measured' table: cycloidal lift at 1 deg steps plus gauge noise [mm]."""
    deg = np.arange(-75.0, 75.0 + 0.5, 1.0)
    h, _ = cycloidal(np.deg2rad(deg))
    rng = np.random.default_rng(seed)
    lift_mm = h * 1e3 + rng.normal(0.0, noise, deg.size)
    np.savetxt(path, np.c_[deg, lift_mm], delimiter=",", header="cam angle deg,lift mm")
    return path


def test_exact_table_reproduces_the_law(tmp_path: Path) -> None:
    angle, lift = read_lift_table(measured_table(tmp_path / "t.csv", noise=0.0))
    theta = np.deg2rad(np.linspace(-50, 50, 201))
    curves = table_kinematics(np.deg2rad(angle), lift * 1e-3, 0.0, theta)
    h, a = cycloidal(theta)
    assert np.max(np.abs(curves[0] - h)) < 1e-7  # m: 0.1 µm
    assert np.max(np.abs(curves[2] - a)) < 0.02 * np.max(np.abs(a))


def test_smoothing_tames_spurious_acceleration(tmp_path: Path) -> None:
    """2 µm gauge noise: interpolating it gives accelerations several times the true peak;
    a spline allowed the noise level as residual brings the peak back within 15 %."""
    angle, lift = read_lift_table(measured_table(tmp_path / "t.csv", noise=0.002))
    theta = np.deg2rad(np.linspace(-70, 70, 1401))
    _, a = cycloidal(theta)
    raw = table_kinematics(np.deg2rad(angle), lift * 1e-3, 0.0, theta)
    smooth = table_kinematics(np.deg2rad(angle), lift * 1e-3, 2e-6, theta)
    true_peak = np.max(np.abs(a))
    assert np.max(np.abs(raw[2])) > 1.5 * true_peak
    assert np.max(np.abs(smooth[2])) == pytest.approx(true_peak, rel=0.15)


@pytest.mark.parametrize(
    ("content", "words"),
    [
        ("0,1\n1,2\n", "need at least"),
        ("a,b\nc,d\n" * 5, "two numeric columns"),
        ("\n".join(f"{-i},{i}" for i in range(10)), "increase strictly"),
    ],
)
def test_bad_tables_are_explained(tmp_path: Path, content: str, words: str) -> None:
    path = tmp_path / "bad.csv"
    path.write_text(content)
    with pytest.raises(ValueError, match=words):
        read_lift_table(path)


def test_table_law_in_a_study(tmp_path: Path) -> None:
    table = measured_table(tmp_path / "t.csv", noise=0.0)
    text = f"""
name = "table"
scene = "cam"
responses = ["max_lift", "min_radius_of_curvature"]
design = "full_factorial"
[settings]
table_smoothing = 0.0
[parameters]
law = "table"
lift_table = "{table}"
rise_angle = 60.0
[factors.base_radius]
levels = [15.0, 20.0]
"""
    ev = evaluate(plan_text(text), progress=False)
    np.testing.assert_allclose(ev.scalars["max_lift"], 8.0, rtol=1e-6)
    # closed form: ρ_min = r0 + min(h + h''); the cycloid's h + h'' is smallest on the flanks
    theta = np.deg2rad(np.linspace(-180, 180, 3601))
    h, a = cycloidal(theta)
    expected = np.array([15.0, 20.0]) + np.min(h + a) * 1e3
    np.testing.assert_allclose(ev.scalars["min_radius_of_curvature"], expected, rtol=2e-3)


def test_missing_table_is_a_study_problem(tmp_path: Path) -> None:
    from studies.define.definition import StudyFileError

    text = f"""
name = "table"
scene = "cam"
responses = ["max_lift"]
[parameters]
law = "table"
lift_table = "{tmp_path / "missing.csv"}"
[factors.base_radius]
levels = [15.0, 20.0]
"""
    with pytest.raises(StudyFileError, match="no such file"):
        plan_text(text)
