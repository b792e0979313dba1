"""The RK4 stability guard of the valve kernels: the NumPy rows the plan checks with, against
the polynomial roots of each linear mode and against the compiled per-case guard."""

from __future__ import annotations

import numpy as np

from engine_kernels import valvetrain as valve
from engine_kernels.valvetrain.valve import guard


def random_rows(rng: np.random.Generator, n: int) -> np.ndarray:
    """Parameter rows over the ranges studies use, with some heavily over-damped modes."""
    rows = np.zeros((n, valve.P_INITIAL_VELOCITY + 1))
    rows[:, valve.P_SPEED] = rng.uniform(50.0, 1200.0, n)
    rows[:, valve.P_MASS] = rng.uniform(0.005, 0.5, n)
    rows[:, valve.P_DRIVE_STIFFNESS] = 10 ** rng.uniform(5.0, 9.0, n)
    rows[:, valve.P_SPRING_RATE] = 10 ** rng.uniform(3.0, 5.5, n)
    rows[:, valve.P_SEAT_STIFFNESS] = 10 ** rng.uniform(6.0, 10.5, n)
    for column in (valve.P_DRIVE_DAMPING, valve.P_SEAT_DAMPING, valve.P_EXTERNAL_DAMPING):
        rows[:, column] = 10 ** rng.uniform(-1.0, 6.0, n)
    return rows


def test_rows_match_the_roots_of_every_mode():
    # Independent: numpy's companion-matrix roots of M l^2 + c l + K for the four modes of
    # [V2], then the smallest sub-step count whose |h l| stays at the target.
    rng = np.random.default_rng(20261127)
    rows = random_rows(rng, 300)
    steps = np.radians(rng.uniform(0.05, 2.0, 300))
    needed, ratio = guard.stability_substeps_rows(rows, steps)
    for row, step, n, r in zip(rows, steps, needed, ratio, strict=True):
        m, k, b = row[valve.P_MASS], row[valve.P_DRIVE_STIFFNESS], row[valve.P_DRIVE_DAMPING]
        ks, gamma = row[valve.P_SPRING_RATE], row[valve.P_EXTERNAL_DAMPING]
        kz, bz = row[valve.P_SEAT_STIFFNESS], row[valve.P_SEAT_DAMPING]
        modes = ((b + bz + gamma, k + kz + ks), (b + gamma, k + ks), (bz + gamma, kz + ks))
        radius = max(np.abs(np.roots([m, c, s])).max() for c, s in (*modes, (gamma, ks)))
        h = step / row[valve.P_SPEED]
        assert r == np.float64(h * radius) or abs(r / (h * radius) - 1.0) < 1e-6
        assert h / n * radius <= guard.STEP_RATIO_TARGET * (1 + 1e-6)
        if n > 1:
            assert h / (n - 1) * radius > guard.STEP_RATIO_TARGET * (1 - 1e-6)


def test_rows_equal_the_compiled_guard_case_by_case():
    rng = np.random.default_rng(7)
    rows = random_rows(rng, 400)
    steps = np.radians(rng.uniform(0.05, 2.0, 400))
    rows[:5, valve.P_SPEED] = [1e-12, 1e-300, 5e-324, np.nan, 1e6]  # limits: no count would do
    rows[5, valve.P_MASS] = 2.2250738585072014e-308  # the smallest normal mass: infinite rates
    needed, ratio = guard.stability_substeps_rows(rows, steps)
    for row, step, n, r in zip(rows, steps, needed, ratio, strict=True):
        expected_n, expected_r = guard.stability_substeps(row, step)
        assert n == expected_n
        np.testing.assert_allclose(r, expected_r, rtol=1e-12)  # NaN where the guard gives NaN
