"""Adaptive Dormand–Prince 5(4) for the valve model [V2] (engine_kernels.valvetrain.dopri.integrate).

Expected values come from scipy's event-restarted ``solve_ivp`` (DOP853, rtol 1e-12,
studies.scenes.valve.reference.valve_ivp) on the same model and the same excitation: the
cubic Hermite of the very table the kernel reads (``table_excitation``), so the comparison
measures the integrator alone. The parameter set is that of tests/engine_kernels/test_valve.py
(physics §4 thesis values plus stated assumptions) on its 1 − cos cam event.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from engine_kernels import valvetrain as valve
from engine_kernels.valvetrain.dopri import integrate as dopri
from engine_kernels.valvetrain.dopri import jump as dopri_jump
from studies.scenes.valve.reference.valve_ivp import table_excitation, valve_reference
from studies.scenes.valve.reference.valve_outputs import reference_outputs

RPM = 2 * math.pi / 60
MASS = valve.equivalent_mass(0.033, 0.015, 5e-6, 33.28e-3)
PARAMS = np.array([3500 * RPM, MASS, 1.17e7, 150.0, 3.0e4, 205.8, 5.0e7, 900.0, 0.0, 0.0, 0.0])
HEIGHT, HALF = 4e-3, 1.4  # Y = HEIGHT (1 + cos(pi theta / HALF)) for |theta| < HALF
WAVE = math.pi / HALF
TABLE_DEG, GRID_DEG = 1.0 / 32.0, 0.5


def cosine_event(theta):
    theta = np.asarray(theta, dtype=float)
    inside = np.abs(theta) < HALF
    return (
        np.where(inside, HEIGHT * (1 + np.cos(WAVE * theta)), 0.0),
        np.where(inside, -HEIGHT * WAVE * np.sin(WAVE * theta), 0.0),
        np.where(inside, -HEIGHT * WAVE**2 * np.cos(WAVE * theta), 0.0),
    )


def params(**changes):
    row = PARAMS.copy()
    for name, value in changes.items():
        row[valve.VALVE_PARAM_NAMES.index(name)] = value
    return row


def excitation(start_deg=-100.0, stop_deg=110.0):
    theta = np.radians(np.arange(start_deg, stop_deg + TABLE_DEG / 2, TABLE_DEG))
    return np.stack(cosine_event(theta)), math.radians(TABLE_DEG), theta[0]


def run(row, tolerance, max_steps=dopri.DEFAULT_MAX_STEPS):
    """Outputs, curves on the 0.5 deg grid and the grid angles [rad] of one dopri run."""
    table, step, start = excitation()
    grid = math.radians(GRID_DEG)
    n = dopri.grid_points(table, step, grid)
    out = np.empty(len(valve.VALVE_OUTPUT_NAMES))
    curves = np.empty((len(valve.VALVE_CURVE_NAMES), n))
    dopri.dopri_response(table, step, start, grid, row, tolerance, 0.0, max_steps, out, curves)
    return out, curves, start + grid * np.arange(n)


def reference(row, theta):
    return valve_reference(table_excitation(*excitation()), row, theta, rtol=1e-12, atol=1e-15)


@pytest.mark.parametrize("rpm", [2500.0, 7000.0])
def test_stiff_seat_error_follows_the_tolerance(rpm):
    # Seat 1e6 N/mm (1e9 N/m). Measured max |y − y_ref| over the grid: see the assertions'
    # multiples; 10× tighter tolerance per step gave ≥ 5× smaller true error.
    row = params(camshaft_speed=rpm * RPM, seat_stiffness=1e9)
    errors = []
    for tolerance in (1e-6, 1e-7):
        out, curves, theta = run(row, tolerance)
        assert out[valve.O_STATUS] == valve.STATUS_OK
        lift = reference(row, theta).lift
        errors.append(np.max(np.abs(curves[valve.C_LIFT] - lift)))
    print(f"{rpm} rpm: errors {errors}")
    assert errors[0] <= 3.0 * 1e-6
    assert errors[1] <= 3.0 * 1e-7
    assert errors[1] * 5.0 <= errors[0]


@pytest.mark.parametrize("rpm", [50.0, 10000.0])
@pytest.mark.parametrize("damping", [(0.0, 0.0), (150.0, 900.0)])
def test_extremes_finish_with_finite_physical_results(rpm, damping):
    # Seat 1e7 N/mm (1e10 N/m), with and without damping, at the ends of the speed range: the
    # steps adapt to the stiff seat (no stability guard), so the run finishes; at 10 000 rpm
    # the valve leaves the cam. At 50 rpm it follows the cam: its largest lift is the cam's
    # 2·HEIGHT less the quasi-static lag (Ps0 + ks·y)/k ≈ 38 µm, and with damping the whole
    # lift is within 1 µm of the reference (undamped, the reference needs more than 10 000
    # restarts on the ringing seat).
    row = params(
        camshaft_speed=rpm * RPM,
        seat_stiffness=1e10,
        drive_damping=damping[0],
        seat_damping=damping[1],
    )
    out, curves, theta = run(row, 1e-7)
    assert out[valve.O_STATUS] == valve.STATUS_OK
    assert np.isfinite(curves).all()
    # max lift is located between the grid points: at least the largest grid lift, above it
    # by less than a grid step's travel at the largest speed
    lift = curves[valve.C_LIFT]
    travel = np.max(np.abs(curves[valve.C_VELOCITY])) * math.radians(GRID_DEG) / (rpm * RPM)
    assert np.max(lift) <= out[valve.O_MAX_LIFT] <= np.max(lift) + travel
    if rpm == 50.0:
        assert out[valve.O_MAX_LIFT] == pytest.approx(2.0 * HEIGHT, abs=1e-4)
        if damping[1] > 0.0:
            # An implicit reference (Radau): the stiff seat over a 50 rpm event costs an
            # explicit solver 2.3× as long for the same answer (8e-10 m apart). At rtol 1e-8
            # its lift is within 1.3e-13 m of its own at 1e-10, in 24 s instead of 64 s.
            table = table_excitation(*excitation())
            found = valve_reference(table, row, theta, method="Radau", rtol=1e-8, atol=1e-15)
            assert np.max(np.abs(lift - found.lift)) <= 1e-6
            # the reference's maximum located on its dense output (the nose is at 0)
            true = reference_outputs(found, row, 0.0).max_lift
            assert out[valve.O_MAX_LIFT] == pytest.approx(true, abs=1e-6)
    else:
        assert out[valve.O_JUMP_DURATION] > 0.0


def test_step_limit_gives_a_status_not_a_hang():
    out, curves, _ = run(params(seat_stiffness=1e10), 1e-9, max_steps=50)
    assert out[valve.O_STATUS] == valve.STATUS_SUBSTEP_LIMIT
    assert np.isnan(np.delete(out, valve.O_STATUS)).all()
    assert np.isnan(curves).all()


@pytest.mark.parametrize(
    ("changes", "tolerance"),
    [({"camshaft_speed": -1.0}, 1e-7), ({"seat_stiffness": 0.0}, 1e-7), ({}, 0.0)],
)
def test_invalid_input_is_reported(changes, tolerance):
    out, _, _ = run(params(**changes), tolerance)
    assert out[valve.O_STATUS] == valve.STATUS_INVALID_INPUT


def test_batch_is_the_one_case_kernel():
    rows = np.stack([params(camshaft_speed=n * RPM) for n in (1000.0, 3500.0, 6000.0)])
    table, step, start = excitation()
    grid = math.radians(GRID_DEG)
    n = dopri.grid_points(table, step, grid)
    out = np.empty((3, len(valve.VALVE_OUTPUT_NAMES)))
    lifts = np.empty((3, n))
    dopri.dopri_batch(
        table, step, start, grid, rows, 1e-7, 0.0, dopri.DEFAULT_MAX_STEPS, out, lifts
    )
    for i, row in enumerate(rows):
        single, curves, _ = run(row, 1e-7)
        np.testing.assert_array_equal(out[i], single)
        np.testing.assert_array_equal(lifts[i], curves[valve.C_LIFT])


@pytest.mark.parametrize(
    ("rpm", "seat_stiffness"), [(3500, 5e7), (6000, 5e7), (1000, 1e9), (2000, 1e10)]
)
def test_seating_velocity_matches_reference(rpm, seat_stiffness):
    # Reference: velocity at the first seat contact after the nose, located as an event. The
    # kernel locates the same switch and reads the velocity at the end of that step.
    row = params(camshaft_speed=rpm * RPM, seat_stiffness=seat_stiffness)
    table, step, start = excitation()
    theta = start + step * np.arange(table.shape[1])
    found = reference(row, theta[theta < math.radians(79.0)])
    seat = next(t for t, kind in found.switches if "seat_gap" in kind and t > 0.0)
    closing = reference(row, np.array([theta[0], seat]))
    out, _, _ = run(row, 1e-7)
    assert out[valve.O_SEATING_VELOCITY] == pytest.approx(abs(closing.velocity[-1]), rel=1e-4)


def test_bounces_and_jump_start_match_reference():
    # Nearly undamped seat (damping ratio 0.007) at 3500 rpm, then 7000 rpm where the valve
    # leaves the cam. Reference (event-restarted DOP853 on the same table): a bounce is a
    # seat-gap switch off the seat after the first closure; the height is the largest y − δ0
    # after it and the jump starts at the drive switch that ends the contact, both located on
    # the reference's dense output (valve_outputs). The kernel locates both too: the bounce's
    # top between its observed points, the separation as a switch.
    row = params(seat_damping=20.0)
    out, _, theta = run(row, 1e-7)
    found = reference(row, theta)
    closing = [t for t, kind in found.switches if "seat_gap" in kind and t > 0.0]
    assert out[valve.O_STATUS] == valve.STATUS_OK
    assert out[valve.O_BOUNCE_COUNT] == (len(closing) - 1) // 2 >= 3
    height = reference_outputs(found, row, 0.0).bounce_height  # the nose is at 0
    # measured 1.2e-9 m low (2.5e-4): the integration error at 1e-7 m per step, which falls
    # 7-9x per decade of tolerance (2.6e-12 m at 1e-10), so the top itself is located
    assert out[valve.O_BOUNCE_HEIGHT] == pytest.approx(height, rel=5e-4)
    fast = params(camshaft_speed=7000 * RPM)
    out, _, theta = run(fast, 1e-7)
    found = reference(fast, theta)
    # the first drive switch takes up the lash at −HALF, the second is the separation
    separation = [t for t, kind in found.switches if "drive" in kind][1]
    assert reference_outputs(found, fast, 0.0).jump_start == separation
    # The drive force falls slowly through zero (~670 N/rad here), so 1 nm of lift error moves
    # the root by ~2e-5 rad: measured 5.5e-5 rad early at 1e-7 m per step, 2.6e-6 at 1e-8 and
    # 6e-8 at 1e-9 (read at the next grid point instead, it was 8.6e-4 rad late).
    assert out[valve.O_JUMP_START] == pytest.approx(separation, abs=1e-4)
    out, _, _ = run(fast, 1e-9)
    assert out[valve.O_JUMP_START] == pytest.approx(separation, abs=1e-6)


def test_jump_speed_by_dopri_is_the_rigid_separation_speed():
    # Stiff (10x reference), well-damped drive (as test_valve.py's RK4 search): separation
    # starts at the rigid closed form, where the spring force Ps0 + ks Y falls short of
    # M |Y''| ω² at the nose (Y = 2H, Y'' = −H w²), within 2 %. And the search's answer is
    # the upper end of its bracket: the valve separates there and not 2 search tolerances below.
    row = params(drive_stiffness=1e8, drive_damping=math.sqrt(1e8 * MASS))
    critical = math.sqrt(
        (row[valve.P_PRELOAD] + 2 * row[valve.P_SPRING_RATE] * HEIGHT)
        / (row[valve.P_MASS] * HEIGHT * WAVE**2)
    )
    table, step, start = excitation()
    grid = math.radians(GRID_DEG)
    speed, code = dopri_jump.dopri_jump_speed(
        table, step, start, grid, row, 1e-7, 0.3 * critical, 3.0 * critical, 12, 1e-3
    )
    assert code == valve.JUMP_FOUND
    assert speed == pytest.approx(critical, rel=0.02)
    for factor, separates in ((1.0, True), (1.0 - 2e-3, False)):
        at = row.copy()
        at[valve.P_SPEED] = factor * speed
        out, _, _ = run(at, 1e-7)
        assert (out[valve.O_JUMP_DURATION] > 0.0) == separates


def test_jump_speed_by_dopri_reports_a_failed_run():
    # An invalid row (zero seat stiffness) makes the first run fail: the search says so
    # (JUMP_RUN_FAILED, NaN speed) instead of scanning on.
    table, step, start = excitation()
    speed, code = dopri_jump.dopri_jump_speed(
        table,
        step,
        start,
        math.radians(GRID_DEG),
        params(seat_stiffness=0.0),
        1e-7,
        100.0,
        1000.0,
        4,
        1e-3,
    )
    assert code == valve.JUMP_RUN_FAILED
    assert math.isnan(speed)
