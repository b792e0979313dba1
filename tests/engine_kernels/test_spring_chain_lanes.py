"""Multi-mass valve spring [V4] in SIMD lanes: the one-case kernel's numbers, vectorised loops.

The expected values come from the one-case kernel (``spring_chain_response``, validated against
scipy's event-restarted DOP853 in test_spring_chain.py): the same model and observations
integrated one case at a time with plain loops and branches, the brute-force alternative to
the node sweeps, lane loops, selects and block bookkeeping checked here. Both keep the same
arithmetic, so the agreement asked for is round-off (1e-12 relative); measured: bit for bit.
Reference valve train as in test_spring_chain.py (physics §4 thesis data plus stated choices).
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

from engine_kernels import valvetrain as valve
from engine_kernels._jit import FASTMATH
from engine_kernels.valvetrain.spring_chain import lane_batch, lane_layout, layout
from engine_kernels.valvetrain.spring_chain import lanes as lane_loops
from engine_kernels.valvetrain.spring_chain.guard import prepare_chain_case
from engine_kernels.valvetrain.spring_chain.one_case import (
    spring_chain_one_case_batch,
    spring_chain_response_batch,
)
from engine_kernels.valvetrain.valve.lane_batch import block_starts
from studies.common.simd import host_lanes, target_features, widest_vector

RPM = 2 * math.pi / 60
VALVE_MASS = 0.033 + 5e-6 / 33.28e-3**2
HEIGHT, HALF = 4e-3, 1.4  # 1 - cos event as in test_spring_chain.py
LUMPED = [3500 * RPM, VALVE_MASS, 1.17e7, 150.0, 3.0e4, 205.8, 5e7, 900.0, 0, 0, 0]
BASE = np.array([*LUMPED, 0.015, 4, 0.03, 1.0, 0.0, 0.0])  # 15 g spring, N = 4, zeta 0.03
OUTPUTS = len(layout.CHAIN_OUTPUT_NAMES)
SETTINGS = valve.valve_settings()


def column(name):
    return layout.CHAIN_PARAM_NAMES.index(name)


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


def mixed_cases(n, seed, masses):
    """Cases that follow the cam, jump, land on the seat and bounce, clash their coils, need
    sub-steps; then one invalid row and one past the sub-step limit (stiff coil contact)."""
    rng = np.random.default_rng(seed)
    rows = np.tile(BASE, (n, 1))
    rows[:, column("spring_masses")] = rng.choice(masses, n)
    rows[:, column("camshaft_speed")] = rng.uniform(500, 8000, n) * RPM
    rows[:, column("spring_preload")] = rng.uniform(120, 260, n)
    rows[:, column("spring_damping_ratio")] = rng.uniform(0, 0.05, n)
    rows[:, column("seat_damping")] = rng.uniform(0, 900, n)
    rows[::5, column("initial_lift")] = 1e-4
    rows[::7, column("initial_velocity")] = -0.5
    clash = rng.random(n) < 0.4
    rows[clash, column("clash_travel")] = rng.uniform(4e-3, 8e-3, clash.sum())
    rows[clash, column("clash_stiffness")] = 1e8
    rows[clash, column("clash_damping")] = 20.0
    rows[::6, column("seat_stiffness")] = 1e10
    rows[1, column("spring_mass")] = -1.0
    rows[2, column("clash_stiffness")] = 1e13
    rows[2, column("clash_travel")] = 3e-3
    return rows


def one_case(rows, table=None, settings=SETTINGS):
    excitation, step, start = table or cosine_event_table(0.5)
    out = np.empty((rows.shape[0], OUTPUTS))
    spring_chain_one_case_batch(excitation, step, start, rows, settings, out)
    return out


def batch(rows, table=None, settings=SETTINGS):
    excitation, step, start = table or cosine_event_table(0.5)
    out = np.empty((rows.shape[0], OUTPUTS))
    spring_chain_response_batch(excitation, step, start, rows, settings, out)
    return out


def lane_blocks(rows, settings=SETTINGS):
    """Every case through the lane kernel itself, in blocks of one N and sub-step count
    however few cases share them (the batch entry runs small groups one at a time)."""
    excitation, step, start = cosine_event_table(0.5)
    out = np.empty((rows.shape[0], OUTPUTS))
    groups: dict[tuple[int, int], list[int]] = {}
    for i, row in enumerate(rows):
        substeps = prepare_chain_case(excitation, step, row, settings, out[i])
        if substeps:
            groups.setdefault((int(row[column("spring_masses")]), substeps), []).append(i)
    for (masses, substeps), members in groups.items():
        for first in range(0, len(members), lane_layout.LANES):
            chunk = members[first : first + lane_layout.LANES]
            cases = np.array([*chunk, *[chunk[0]] * (lane_layout.LANES - len(chunk))])
            block = lane_layout.new_block(masses)
            lane_layout.start_chain_lanes(rows, cases, masses, 2.0 * step / substeps, block)
            lane_loops.chain_lane_pass(excitation, step, start, masses, substeps, block)
            lane_layout.finish_chain_lanes(block, len(chunk), masses, substeps, cases, out)
    return out


@pytest.mark.parametrize("masses", [1, 2, 7, 16, 24])
def test_lane_kernel_gives_the_one_case_kernels_numbers(masses):
    rows = mixed_cases(24, masses, [masses])
    expected = one_case(rows)
    status = expected[:, layout.CO_STATUS]
    assert {valve.STATUS_OK, valve.STATUS_SUBSTEP_LIMIT, valve.STATUS_INVALID_INPUT} <= set(status)
    ok = status == valve.STATUS_OK
    assert (expected[ok, layout.CO_JUMP_DURATION] > 0).any()
    assert np.isfinite(expected[ok, layout.CO_SEATING_VELOCITY]).any()  # seat landing
    assert (expected[ok, layout.CO_BOUNCE_COUNT] > 0).any()
    assert (expected[ok, layout.CO_CLASH_COUNT] > 0).any()
    assert (expected[ok, layout.CO_SUBSTEPS] > 1).any()
    np.testing.assert_allclose(lane_blocks(rows), expected, rtol=1e-12, atol=0.0)


def test_lane_kernel_flags_the_same_unstable_runs_without_the_guard():
    # Stiff coil contact and no spring damping integrated with one sub-step: the energy check
    # or the non-finite state must flag the same runs in both kernels.
    rows = mixed_cases(16, 3, [2, 8])
    rows[:, column("clash_stiffness")] = 1e9
    rows[:, column("clash_travel")] = 3e-3
    rows[:, column("spring_damping_ratio")] = 0.0
    settings = valve.valve_settings(stability_guard=False)
    expected = one_case(rows, settings=settings)
    unstable = (valve.STATUS_UNSTABLE, valve.STATUS_NONFINITE)
    assert np.isin(expected[:, layout.CO_STATUS], unstable).any()
    np.testing.assert_allclose(lane_blocks(rows, settings), expected, rtol=1e-12, atol=0.0)


def study_like_batch():
    """A parameter study's batch: N = 1, 4, 16 at 3000-6000 rpm (full lane blocks), then the
    mixed cases (small groups, which the batch entry runs one case at a time)."""
    rows = np.tile(BASE, (3 * 40, 1))
    rows[:, column("spring_masses")] = np.repeat([1, 4, 16], 40)
    rows[:, column("camshaft_speed")] = np.tile(np.linspace(3000, 6000, 40), 3) * RPM
    return np.vstack([rows, mixed_cases(30, 9, [1, 2, 7, 16, 24])])


def test_batch_entry_gives_the_one_case_kernels_numbers():
    rows = study_like_batch()
    expected = one_case(rows)
    keys = expected[:, layout.CO_SUBSTEPS] * 100 + rows[:, column("spring_masses")]
    _, sizes = np.unique(keys[expected[:, layout.CO_STATUS] == valve.STATUS_OK], return_counts=True)
    assert sizes.max() >= lane_batch.MIN_BLOCK_CASES  # some blocks run in lanes ...
    assert sizes.min() < lane_batch.MIN_BLOCK_CASES  # ... and some one case at a time
    np.testing.assert_allclose(batch(rows), expected, rtol=1e-12, atol=0.0)


def test_results_do_not_depend_on_block_neighbours():
    # Each case keeps its own N and sub-step count whatever cases share its block: a shuffled
    # batch and cases run alone give exactly the same rows.
    rows = study_like_batch()
    together = batch(rows)
    order = np.random.default_rng(3).permutation(rows.shape[0])
    np.testing.assert_array_equal(batch(rows[order]), together[order])
    for i in (0, 45, 130):
        np.testing.assert_array_equal(batch(rows[i : i + 1])[0], together[i])


def test_batch_driver_as_plain_python_gives_the_same_rows():
    # The driver (guard, grouping, block order, prange) run as plain Python around the
    # compiled blocks: its bookkeeping checked apart from Numba's parallel lowering.
    rows = study_like_batch()[::3]
    excitation, step, start = cosine_event_table(1.0)
    python = np.empty((rows.shape[0], OUTPUTS))
    spring_chain_response_batch.py_func(excitation, step, start, rows, SETTINGS, python)
    np.testing.assert_array_equal(python, batch(rows, (excitation, step, start)))


def test_batches_without_runnable_cases():
    empty = np.empty((0, OUTPUTS))
    excitation, step, start = cosine_event_table(0.5)
    spring_chain_response_batch(excitation, step, start, np.empty((0, BASE.size)), SETTINGS, empty)
    refused = np.tile(BASE, (3, 1))
    refused[:, column("spring_masses")] = 0
    out = batch(refused)
    assert (out[:, layout.CO_STATUS] == valve.STATUS_INVALID_INPUT).all()
    assert np.isnan(out[:, layout.CO_MAX_LIFT]).all()


@hypothesis_settings(max_examples=40, deadline=None)
@given(st.lists(st.integers(min_value=0, max_value=6), max_size=150))
def test_blocks_hold_one_key_each(keys):
    # Closed form: a key held by c cases fills ceil(c / LANES) blocks; refused cases (0) none.
    keys = np.array(keys, dtype=np.int64)
    order = np.argsort(keys, kind="mergesort")
    starts = block_starts(keys, order)
    blocks = [order[a:b] for a, b in itertools.pairwise(starts)]
    assert all(0 < len(block) <= lane_layout.LANES for block in blocks)
    assert all(len(set(keys[block])) == 1 for block in blocks)
    cases = np.concatenate(blocks) if blocks else np.empty(0, dtype=np.int64)
    assert sorted(cases.tolist()) == np.flatnonzero(keys).tolist()
    expected = sum(math.ceil(np.sum(keys == k) / lane_layout.LANES) for k in range(1, 7))
    assert len(blocks) == expected


@pytest.mark.parametrize(
    ("sweep", "lane_loops_in_it", "arguments"),
    [
        ("_observe_lanes", 5, (0.0, 0.0, 0.0, 0.0, True)),
        ("_stage2_lanes", 4, (0.0, 0.0)),
        ("_stage3_lanes", 4, (0.0, 0.0)),
        ("_stage4_lanes", 4, (0.0, 0.0)),
    ],
)
def test_every_lane_loop_vectorises(sweep, lane_loops_in_it, arguments):
    # The point of the lane kernel (STYLE, "Hot integrators"): every loop over lanes must
    # compile to vector arithmetic. A call, a wraparound index or a branch out of the loop
    # stops that silently, so look at the LLVM IR of a fresh (uncached) compilation: each
    # lane loop gives one vectorised loop body. Width as in test_valve_lanes.py (the host's,
    # at least 4 doubles where the target has AVX; none required on an SSE-only target).
    function = numba.njit(fastmath=FASTMATH, error_model="numpy")(
        getattr(lane_loops, sweep).py_func
    )
    function(*lane_layout.new_block(4), 4, *arguments)
    llvm = function.inspect_llvm(function.signatures[0])
    lanes = host_lanes(np.float64) if "+avx" in target_features() else 1
    assert widest_vector(llvm, np.float64) >= min(lanes, 4)
    bodies = {line for line in llvm.splitlines() if line.startswith("vector.body")}
    assert len(bodies) >= (lane_loops_in_it if lanes > 1 else 0)
