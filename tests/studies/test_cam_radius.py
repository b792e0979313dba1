"""The convexity scans of the cam-driven scenes evaluate a rise law once per (law, rise angle,
coefficients) and scale it by lift and base radius; each test compares them with the brute
force, the kernel's smallest radius of curvature of every row on its own."""

from __future__ import annotations

import numpy as np
import pytest

from engine_kernels.cam import kinematics as cb
from engine_kernels.cam.lift_laws import LAW_SIX_SEGMENT
from studies.define.plan import plan_text
from studies.scenes import cam_radius
from studies.scenes.cam.scene import kernel_inputs
from studies.scenes.cam_laws import LAWS
from study_text import scene_study

N = 400
POLY345 = [0.0, 0.0, 0.0, 10.0, -15.0, 6.0]  # f = 10x³ − 15x⁴ + 6x⁵ (a valid polydyne)


def random_cams(seed: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Kernel inputs of N cams of every kernel law (the cam scene's defaults for the
    six-segment profile), with lift, base radius and rise angle drawn at random from few
    levels (so shapes repeat) and a few invalid rows."""
    text = scene_study(
        "cam", responses='["max_jerk"]', factors="[factors.lift]\nlevels = [8.0, 9.0]"
    )
    one = plan_text(text).points
    rng = np.random.default_rng(seed)
    points = {name: np.repeat(np.asarray(values)[:1], N, axis=0) for name, values in one.items()}
    kernel_laws = [law for law in LAWS if law != "table"]
    points["law"] = rng.choice(np.array(kernel_laws, dtype=object), N)
    points["lift"] = rng.choice(np.linspace(2e-3, 15e-3, 7), N)
    points["base_radius"] = rng.choice(np.linspace(5e-3, 40e-3, 9), N)
    points["rise_angle"] = np.radians(rng.choice(np.linspace(20.0, 120.0, 11), N))
    points["polydyne_coefficients"] = np.tile(np.array(POLY345 + [0.0] * 4), (N, 1))
    points["lift"][:3] = (0.0, -1e-3, np.nan)  # not scalable: evaluated row by row
    return kernel_inputs(points)


def scan(
    params: np.ndarray, shapes: np.ndarray, coeffs: np.ndarray, step_deg: float
) -> tuple[np.ndarray, str]:
    """:func:`cam_radius.min_radii` of the kernel rows ``params, shapes, coeffs``."""
    column = {c: params[:, c] for c in (cb.P_LAW, cb.P_LIFT, cb.P_RISE_ANGLE, cb.P_BASE_RADIUS)}
    return cam_radius.min_radii(
        *column.values(), coeffs, lambda idx: (params[idx], shapes[idx], coeffs[idx]), step_deg
    )


@pytest.mark.parametrize("step_deg", [0.5, 1.0])
def test_scaled_rise_laws_equal_each_row_evaluated_alone(step_deg: float) -> None:
    params, shapes, coeffs = random_cams(5)
    radius, said = scan(params, shapes, coeffs, step_deg)
    theta = cam_radius.angle_grid(step_deg)
    reference = np.empty(N)
    for i in range(N):
        one = np.empty(1)
        cb.min_radius_of_curvature_batch(
            params[i : i + 1], shapes[i : i + 1], coeffs[i : i + 1], theta, one
        )
        reference[i] = one[0]
    assert said == ""
    scale = params[:, cb.P_BASE_RADIUS] + np.abs(params[:, cb.P_LIFT])
    np.testing.assert_allclose(radius, reference, rtol=0.0, atol=1e-12 * np.nanmax(scale))
    assert np.array_equal(np.isnan(radius), np.isnan(reference))
    assert 20 < (reference <= 0.0).sum() < N - 20  # concave and convex cams both in the sample


def test_too_many_row_by_row_laws_are_scanned_coarser_and_it_is_said(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    params, shapes, coeffs = random_cams(6)
    monkeypatch.setattr(cam_radius, "SCAN_BUDGET", 2000)
    radius, said = scan(params, shapes, coeffs, 0.5)
    six = params[:, cb.P_LAW] == LAW_SIX_SEGMENT
    rest = six.copy()
    rest[:3] = True  # lift 0, negative and NaN: not scalable, scanned row by row
    assert cam_radius.scan_step_deg(int(rest.sum()), 0.5) == 2.0  # the coarsest grid
    assert said == f" ({int(rest.sum())} cams of other laws scanned every 2 degree)"
    coarse = np.empty(int(rest.sum()))
    cb.min_radius_of_curvature_batch(
        params[rest], shapes[rest], coeffs[rest], cam_radius.angle_grid(2.0), coarse
    )
    np.testing.assert_array_equal(radius[rest], coarse)
    fine, _ = scan(params[~rest], shapes[~rest], coeffs[~rest], 0.5)
    np.testing.assert_array_equal(radius[~rest], fine)  # the rise laws keep the study's grid
