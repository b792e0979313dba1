"""Valve dynamics [V2] in SIMD lanes: same numbers as the one-case kernel, vectorised loops.

The expected values come from the one-case kernel (``valve.valve_response_batch``): the same
model, arithmetic and observations integrated one case at a time with plain loops and
branches, an independent second implementation of the block-and-lane bookkeeping. Reference
valve train as in test_valve.py (physics §4 thesis data plus stated assumptions).

Single precision (integrator ``lanes_f32``, a float32 table): expected values from the
double-precision kernels and the float32 round-off bound. Each grid step rounds the state
once, so after ``n`` steps the lift may have drifted by at most about ``n · ε32 · max|y|``
(ε32 = 2⁻²³). The extremes of the stability guard (as in test_valve.py) check that the energy
and mode checks, in float32 there, neither miss an instability nor invent one.
"""

from __future__ import annotations

import itertools
import math

import numba
import numpy as np
import pytest
from hypothesis import given
from hypothesis import settings as hypothesis_settings
from hypothesis import strategies as st
from llvmlite import binding as llvmlite_binding

from engine_kernels import valvetrain as valve
from engine_kernels._jit import FASTMATH
from engine_kernels.valvetrain.valve import lane_batch as valve_lanes
from engine_kernels.valvetrain.valve import lanes as lane_loops
from studies.common.simd import host_lanes, target_features, widest_vector

RPM = 2 * math.pi / 60
MASS = 0.033 + 0.015 / 3 + 5e-6 / 33.28e-3**2
PARAMS = np.array([3500 * RPM, MASS, 1.17e7, 150.0, 3.0e4, 205.8, 5.0e7, 900.0, 0.0, 0.0, 0.0])
HEIGHT, HALF = 4e-3, 1.4  # 1 - cos event: Y = HEIGHT (1 + cos(pi theta / HALF)), |theta| < HALF


def cosine_event_table(step_deg, start_deg=-100.0, stop_deg=110.0):
    """Excitation table at half the RK4 step (physics §9): rows Y, Y', Y''."""
    theta = np.radians(np.arange(start_deg, stop_deg + step_deg / 4, step_deg / 2))
    wave = math.pi / HALF
    inside = np.abs(theta) < HALF
    rows = (
        np.where(inside, HEIGHT * (1 + np.cos(wave * theta)), 0.0),
        np.where(inside, -HEIGHT * wave * np.sin(wave * theta), 0.0),
        np.where(inside, -HEIGHT * wave**2 * np.cos(wave * theta), 0.0),
    )
    return np.stack(rows), math.radians(step_deg / 2), theta[0]


def mixed_batch(n, seed):
    """Cases that separate, bounce, need sub-steps, hit the sub-step cap or are invalid."""
    rng = np.random.default_rng(seed)
    rows = np.tile(PARAMS, (n, 1))
    rows[:, valve.P_SPEED] = rng.uniform(300, 9000, n) * RPM
    rows[:, valve.P_SPRING_RATE] = rng.uniform(1e4, 6e4, n)
    rows[:, valve.P_SEAT_DAMPING] = rng.uniform(0.0, 900.0, n)
    rows[::9, valve.P_SEAT_STIFFNESS] = 1e10
    rows[3, valve.P_MASS] = -1.0
    rows[5, valve.P_SPEED] = 20 * RPM
    rows[9, valve.P_SPEED] = 20 * RPM
    return rows


def run_both(rows, settings, step_deg=0.5):
    excitation, step, start = cosine_event_table(step_deg)
    single = np.empty((rows.shape[0], len(valve.VALVE_OUTPUT_NAMES)))
    valve.valve_response_batch(excitation, step, start, rows, settings, single)
    return single, run_lanes(rows, excitation, step, start, settings)


def test_lanes_match_one_case_kernel():
    # 75 cases: two full blocks of 32 and a partial one before grouping by sub-step count.
    rows = mixed_batch(75, 7)
    single, lanes = run_both(rows, valve.valve_settings(estimate_error=True))
    status = single[:, valve.O_STATUS]
    covered = {valve.STATUS_OK, valve.STATUS_SUBSTEP_LIMIT, valve.STATUS_INVALID_INPUT}
    assert covered <= set(status)
    assert (single[:, valve.O_SUBSTEPS] > 1).any()
    assert (single[:, valve.O_JUMP_DURATION] > 0).any()
    assert (single[:, valve.O_BOUNCE_COUNT] > 0).any()
    assert np.isfinite(single[:, valve.O_ERROR_ESTIMATE]).any()
    np.testing.assert_array_equal(lanes[:, valve.O_STATUS], status)
    # Same arithmetic in both kernels: agreement to round-off, 1e-12 relative, or 1e-15 m
    # where an output is a small difference of nearly equal lifts (the jump gap and the error
    # estimate: measured 9e-17 m apart, from the order the lanes sum in).
    np.testing.assert_allclose(lanes, single, rtol=1e-12, atol=1e-15)


@pytest.mark.parametrize("forced", [0, 3], ids=["guard", "3 sub-steps forced"])
def test_lane_lifts_match_one_case_kernel(forced: int) -> None:
    # The error bars' runs (valve_lift_lanes) against the one-case valve_lift_batch: outputs
    # and the lift at every grid point to round-off, NaN lifts for the refused cases.
    rows = mixed_batch(75, 13)
    excitation, step, start = cosine_event_table(0.5)
    settings = valve.valve_settings(substeps=forced)
    n_grid = (excitation.shape[1] - 1) // 2 + 1
    results = []
    for kernel in (valve.valve_lift_batch, valve_lanes.valve_lift_lanes):
        out = np.empty((rows.shape[0], len(valve.VALVE_OUTPUT_NAMES)))
        lifts = np.empty((rows.shape[0], n_grid))
        kernel(excitation, step, start, rows, settings, out, lifts)
        results.append((out, lifts))
    (single, single_lifts), (lanes, lane_lifts) = results
    refused = single[:, valve.O_STATUS] != valve.STATUS_OK
    assert refused.any()
    assert (~refused).any()
    assert np.isnan(single_lifts[refused]).all()
    np.testing.assert_array_equal(lanes[:, valve.O_STATUS], single[:, valve.O_STATUS])
    np.testing.assert_allclose(lanes, single, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(lane_lifts, single_lifts, rtol=1e-12, atol=1e-15)


def test_lane_results_do_not_depend_on_block_neighbours():
    # Each case keeps its own sub-step count, whatever cases share its block: a shuffled
    # batch and cases run alone give exactly the same rows.
    rows = mixed_batch(40, 11)
    excitation, step, start = cosine_event_table(0.5)
    settings = valve.valve_settings()
    together = np.empty((rows.shape[0], len(valve.VALVE_OUTPUT_NAMES)))
    valve_lanes.valve_response_lanes(excitation, step, start, rows, settings, together)
    order = np.random.default_rng(3).permutation(rows.shape[0])
    shuffled = np.empty_like(together)
    valve_lanes.valve_response_lanes(excitation, step, start, rows[order], settings, shuffled)
    np.testing.assert_array_equal(shuffled, together[order])
    for i in (0, 5, 17):
        alone = np.empty((1, together.shape[1]))
        valve_lanes.valve_response_lanes(excitation, step, start, rows[i : i + 1], settings, alone)
        np.testing.assert_array_equal(alone[0], together[i])


def test_lane_driver_as_plain_python_gives_the_same_rows():
    # The batch driver (guard, grouping, block order, prange) run as plain Python around the
    # compiled blocks: a check of its bookkeeping independent of Numba's parallel lowering.
    rows = mixed_batch(40, 5)
    excitation, step, start = cosine_event_table(1.0)
    settings = valve.valve_settings(estimate_error=True)
    compiled = np.empty((rows.shape[0], len(valve.VALVE_OUTPUT_NAMES)))
    python = np.empty_like(compiled)
    valve_lanes.valve_response_lanes(excitation, step, start, rows, settings, compiled)
    valve_lanes.valve_response_lanes.py_func(excitation, step, start, rows, settings, python)
    np.testing.assert_array_equal(python, compiled)


def test_lanes_handle_batches_without_runnable_cases():
    excitation, step, start = cosine_event_table(0.5)
    settings = valve.valve_settings()
    empty = np.empty((0, len(valve.VALVE_OUTPUT_NAMES)))
    valve_lanes.valve_response_lanes(excitation, step, start, np.empty((0, 11)), settings, empty)
    refused = np.tile(PARAMS, (3, 1))
    refused[:, valve.P_MASS] = 0.0
    out = np.zeros((3, len(valve.VALVE_OUTPUT_NAMES)))
    valve_lanes.valve_response_lanes(excitation, step, start, refused, settings, out)
    assert (out[:, valve.O_STATUS] == valve.STATUS_INVALID_INPUT).all()
    assert np.isnan(out[:, valve.O_MAX_LIFT]).all()


@hypothesis_settings(max_examples=40, deadline=None)
@given(st.lists(st.integers(min_value=0, max_value=4), max_size=150))
def test_blocks_hold_one_substep_count_each(counts):
    # Closed form: a count held by c cases fills ceil(c / LANES) blocks; refused cases (0)
    # get none.
    substeps = np.array(counts, dtype=np.int64)
    order = np.argsort(substeps, kind="mergesort")
    starts = valve_lanes.block_starts(substeps, order)
    blocks = [order[a:b] for a, b in itertools.pairwise(starts)]
    assert all(0 < len(block) <= lane_loops.LANES for block in blocks)
    assert all(len(set(substeps[block])) == 1 for block in blocks)
    cases = np.concatenate(blocks) if blocks else np.empty(0, dtype=np.int64)
    assert sorted(cases.tolist()) == np.flatnonzero(substeps).tolist()
    expected = sum(math.ceil(np.sum(substeps == c) / lane_loops.LANES) for c in range(1, 5))
    assert len(blocks) == expected


def test_spread_order_balances_contiguous_shares():
    # Numba splits a prange into equal contiguous shares, one per thread. Blocks sorted by
    # cost and run in this order must give each half a fair mix: the mean sorted index of
    # either half stays near the middle (the plain order would be off by n/4).
    for n in range(1, 200):
        order = valve_lanes.spread_order(n)
        assert sorted(order.tolist()) == list(range(n))
        if n >= 8:
            for half in np.array_split(order, 2):
                assert abs(half.mean() - (n - 1) / 2) <= 0.07 * n


def expected_lanes(dtype: type) -> int:
    """Lanes the lane loops must reach: the host's vector width (studies.common.simd.host_lanes) on
    targets with AVX; a target without it (SSE-only, e.g. NUMBA_CPU_NAME=generic) has no
    blends, and LLVM keeps these select-heavy loops scalar there (precision still checked)."""
    return host_lanes(dtype) if "+avx" in target_features() else 1


def fresh_compilation(loop: str):
    """A lane loop compiled afresh (uncached) with the kernel's own options: the fastmath
    contract and its error model (NumPy's for ``jit_lanes`` loops, whose divisions must not
    branch on a zero divisor)."""
    kernel = getattr(lane_loops, loop)
    error_model = kernel.targetoptions.get("error_model", "python")
    return numba.njit(fastmath=FASTMATH, error_model=error_model)(kernel.py_func)


@pytest.mark.parametrize(
    "loop", ["_observe_lanes", "_step_lanes", "_substep_lanes", "_observe_seat_lanes"]
)
def test_lane_loops_vectorise(loop):
    # The point of the lane kernel (STYLE, "Hot integrators"): each loop over lanes must
    # compile to vector arithmetic. A call or a load under a branch in the loop body stops
    # that silently, so look at the LLVM IR of a fresh (uncached) compilation.
    compiled = fresh_compilation(loop)
    data = np.zeros(lane_loops.N_LANE_ROWS * lane_loops.LANES)
    arguments = {
        "_observe_lanes": (0.0, 0.0, 0.0, True),
        "_step_lanes": (0.0,) * 4,
        "_substep_lanes": (0.0,) * 6,
        "_observe_seat_lanes": (True,),
    }[loop]
    compiled(data, *arguments)
    llvm = compiled.inspect_llvm(compiled.signatures[0])
    assert widest_vector(llvm, np.float64) >= min(expected_lanes(np.float64), 4)


EPS32 = 2.0**-23


def run_lanes(rows, table, step, start, settings):
    out = np.empty((rows.shape[0], len(valve.VALVE_OUTPUT_NAMES)))
    valve_lanes.valve_response_lanes(table, step, start, rows, settings, out)
    return out


def round_off_bound(table, lift):
    """Largest drift [m] of n float32 roundings of a lift of size max|y|."""
    steps = (table.shape[1] - 1) // 2
    return steps * EPS32 * np.max(np.abs(lift))


@pytest.mark.parametrize("rpm", [3500.0, 6000.0, 9000.0])
def test_single_precision_trajectory_is_within_round_off(rpm):
    # 3500 rpm follows the cam, 6000 and 9000 rpm jump and bounce.
    table, step, start = cosine_event_table(0.5)
    row = PARAMS.copy()
    row[valve.P_SPEED] = rpm * RPM
    settings = valve.valve_settings()
    out = np.empty(len(valve.VALVE_OUTPUT_NAMES))
    curves = np.empty((len(valve.VALVE_CURVE_NAMES), (table.shape[1] - 1) // 2 + 1))
    valve.valve_response(table, step, start, row, settings, out, curves)
    double = curves[valve.C_LIFT]
    single = np.empty_like(double)
    valve_lanes.lift_trace_lanes(table.astype(np.float32), step, start, row, settings, single)
    drift = np.max(np.abs(single - double))
    assert 0.0 < drift <= round_off_bound(table, double)


def test_single_precision_outputs_track_double_precision():
    # Where the run follows the cam, the outputs stay within the round-off bound. Where it
    # separates and bounces, the flight amplifies any perturbation, round-off included; there
    # the difference must stay below a tenth of the RK4 truncation error the step carries
    # anyway (double precision at this step against half of it).
    rows = mixed_batch(75, 7)
    table, step, start = cosine_event_table(0.5)
    settings = valve.valve_settings()
    double = run_lanes(rows, table, step, start, settings)
    single = run_lanes(rows, table.astype(np.float32), step, start, settings)
    finer = run_lanes(rows, *cosine_event_table(0.25), settings)
    np.testing.assert_array_equal(single[:, valve.O_STATUS], double[:, valve.O_STATUS])
    np.testing.assert_array_equal(single[:, valve.O_SUBSTEPS], double[:, valve.O_SUBSTEPS])
    ok = double[:, valve.O_STATUS] == valve.STATUS_OK
    assert ok.sum() > 50
    bound = round_off_bound(table, double[ok, valve.O_MAX_LIFT])
    for column in (valve.O_MAX_LIFT, valve.O_JUMP_GAP):
        truncation = np.abs(double[ok, column] - finer[ok, column])
        allowed = np.maximum(bound, 0.1 * truncation)
        assert (np.abs(single[ok, column] - double[ok, column]) <= allowed).all()
    # The jump starts on the same grid point, or one point off where the drive force
    # crosses zero within round-off of a grid point.
    jumped = ok & np.isfinite(double[:, valve.O_JUMP_START])
    assert jumped.any()
    shift = np.abs(single[jumped, valve.O_JUMP_START] - double[jumped, valve.O_JUMP_START])
    assert (shift <= 2 * step * (1 + 1e-6)).all()


@pytest.mark.parametrize(
    "changes",
    [
        {valve.P_SPEED: 10_000 * RPM},
        {valve.P_SPEED: 50 * RPM},
        {valve.P_SEAT_STIFFNESS: 1e10},
        {valve.P_DRIVE_DAMPING: 0.0, valve.P_SEAT_DAMPING: 0.0},
        {valve.P_SEAT_DAMPING: 1e5},
    ],
)
@pytest.mark.parametrize("guard", [True, False])
def test_single_precision_status_at_the_extremes(changes, guard):
    # With the guard the status is ok in both precisions; without it (|h λ| > 2.6 in all but
    # the undamped and 10 000 rpm cases) the float32 energy and mode checks must flag the
    # same runs as unstable as the float64 ones.
    row = PARAMS.copy()
    for column, value in changes.items():
        row[column] = value
    rows = row[np.newaxis, :]
    table, step, start = cosine_event_table(0.5)
    settings = valve.valve_settings(stability_guard=guard)
    double = run_lanes(rows, table, step, start, settings)
    single = run_lanes(rows, table.astype(np.float32), step, start, settings)
    assert single[0, valve.O_STATUS] == double[0, valve.O_STATUS]
    if guard:
        assert single[0, valve.O_STATUS] == valve.STATUS_OK
    assert math.isfinite(single[0, valve.O_MAX_LIFT])


def test_host_lanes_match_the_cpu_features():
    # Every x86-64 CPU has SSE2 (4 float lanes, 2 double); with AVX2 and no forced target,
    # LLVM must use at least 8 and 4. Guards the reference loop (studies.common.simd) against
    # vectorising nothing, which would make the width tests below pass vacuously.
    lanes = host_lanes(np.float32)
    assert lanes >= 4
    assert host_lanes(np.float64) * 2 == lanes
    features = numba.core.config.CPU_FEATURES or llvmlite_binding.get_host_cpu_features().flatten()
    if "+avx2" in features and numba.core.config.CPU_NAME in (None, "host"):
        assert lanes >= 8
        assert "+avx" in target_features()


@pytest.mark.parametrize(
    ("loop", "arguments"),
    [
        ("_observe_lanes", (0.0, 0.0, 0.0, True)),
        ("_step_lanes", (0.0,) * 4),
        ("_energy_lanes", (0.0,) * 2),
        ("_observe_seat_lanes", (True,)),
    ],
)
def test_single_precision_loops_fill_the_host_vectors(loop, arguments):
    # The point of float32: twice the lanes per vector of float64 (8 per AVX2 vector, 16 per
    # AVX-512 one). A float64 literal or a 64-bit integer in a loop would promote it back to
    # double arithmetic or narrower vectors without notice. The width is the host's, never
    # pinned to one instruction set (expected_lanes: 8 on AVX2, 16 or 8 on AVX-512).
    lanes = expected_lanes(np.float32)
    function = fresh_compilation(loop)
    data = np.zeros(lane_loops.N_LANE_ROWS * lane_loops.LANES, np.float32)
    function(data, *(np.float32(a) if isinstance(a, float) else a for a in arguments))
    llvm = function.inspect_llvm(function.signatures[0])
    assert widest_vector(llvm, np.float32) >= lanes
    assert " x double>" not in llvm
    assert "fpext" not in llvm  # no float → double promotion, vector or scalar
