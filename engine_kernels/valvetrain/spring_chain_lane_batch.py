"""Valve dynamics with the multi-mass spring [V4] for many cases: the batch entry (SPEC §4).

:func:`spring_chain_response_batch` gives the results of the one-case kernel
(:func:`engine_kernels.valvetrain.spring_chain_response.spring_chain_response`, no curves)
bit for bit, ``LANES`` cases per block stepped together by
:mod:`engine_kernels.valvetrain.spring_chain_lanes`. A block's lanes share the number of coil
masses N (the length of their node sweeps) and the RK4 sub-step count the stability guard
gives each case, so each case keeps exactly its own: its results do not depend on which other
cases share its block. Cases the guard refuses (invalid input, sub-step limit) get their
outputs from it and join no block. As for the lumped lanes
(:mod:`engine_kernels.valvetrain.lane_batch`), blocks run in a ``prange`` in an order that
spreads the costly ones over the threads, each writing only its own cases' output rows.

A block costs all its ``LANES`` lanes however few cases fill it, so a block of fewer than
``MIN_BLOCK_CASES`` runs its cases one at a time instead (same numbers). Measured on one core
(256 cases at 0.5°, one sub-step): full blocks run 39, 20, 8 and 6 times as many cases per
second as one case at a time for N = 1, 4, 16, 24, so a block of 8 still gains, while one of
one or two cases can lose up to 5 times.
"""

from __future__ import annotations

import numpy as np

from engine_kernels._jit import batch, jit, prange
from engine_kernels.valvetrain.lane_batch import spread_order
from engine_kernels.valvetrain.spring_chain_guard import prepare_chain_case
from engine_kernels.valvetrain.spring_chain_lane_layout import (
    LANES,
    finish_chain_lanes,
    new_block,
    start_chain_lanes,
)
from engine_kernels.valvetrain.spring_chain_lanes import chain_lane_pass
from engine_kernels.valvetrain.spring_chain_layout import (
    CHAIN_CURVE_NAMES,
    MAX_SPRING_MASSES,
    SC_SPRING_MASSES,
)
from engine_kernels.valvetrain.spring_chain_response import spring_chain_response

# Blocks with fewer cases run them one at a time (module docstring).
MIN_BLOCK_CASES = 8
# Block key of a case: sub-steps · _KEY_BASE + N (0: refused), so sorting by key sorts by cost.
_KEY_BASE = MAX_SPRING_MASSES + 1


@jit
def chain_block_starts(keys, order):
    """Split cases sorted by key into blocks of ≤ ``LANES`` with one key (N, sub-steps) each.

    keys  : 1-D int64  Block key per case (0: not integrated);  order : cases sorted by key.
    Returns the block boundaries as positions in ``order`` (block b is
    ``order[starts[b]:starts[b + 1]]``); cases with key 0 are left out.
    """
    n = order.shape[0]
    starts = np.empty(n + 1, dtype=np.int64)
    blocks = 0
    i = 0
    while i < n and keys[order[i]] == 0:
        i += 1
    while i < n:
        starts[blocks] = i
        blocks += 1
        key = keys[order[i]]
        end = min(i + LANES, n)
        i += 1
        while i < end and keys[order[i]] == key:
            i += 1
    starts[blocks] = n
    return starts[: blocks + 1]


@jit
def _chain_block(excitation, table_step, table_start, params, settings, block, key, out):
    """Integrate and report one block: up to ``LANES`` cases with the same key.

    block : 1-D int64  Row indices of the block's cases in ``params`` and ``out``.
    Lanes past the block's cases repeat its first case; their results are not written. Fewer
    than ``MIN_BLOCK_CASES`` cases run one at a time.
    """
    count = block.shape[0]
    if count < MIN_BLOCK_CASES:
        for i in block:
            spring_chain_response(
                excitation,
                table_step,
                table_start,
                params[i],
                settings,
                out[i],
                np.empty((len(CHAIN_CURVE_NAMES), 0)),
            )
        return
    masses = key % _KEY_BASE
    substeps = key // _KEY_BASE
    cases = np.empty(LANES, dtype=np.int64)
    for l in range(LANES):
        cases[l] = block[l if l < count else 0]
    block_arrays = new_block(masses)
    start_chain_lanes(params, cases, masses, 2.0 * table_step / substeps, block_arrays)
    chain_lane_pass(excitation, table_step, table_start, masses, substeps, block_arrays)
    finish_chain_lanes(block_arrays, count, masses, substeps, cases, out)


@batch
def spring_chain_response_batch(excitation, table_step, table_start, params, settings, out):
    """Valve dynamics with the N-mass spring for many cases, ``LANES`` per SIMD block.

    params : 2-D array  (n_cases, len(CHAIN_PARAM_NAMES)) ``SC_*`` rows (N may differ per row).
    out    : 2-D array  (n_cases, len(CHAIN_OUTPUT_NAMES)) outputs ``CO_*``.
    Other arguments as in :func:`~engine_kernels.valvetrain.spring_chain_response.spring_chain_response`;
    the outputs are those of
    :func:`~engine_kernels.valvetrain.spring_chain_response.spring_chain_one_case_batch`.
    Reference: SPEC §4 [V4]; STYLE "Hot integrators".
    """
    n_cases = params.shape[0]
    keys = np.empty(n_cases, dtype=np.int64)
    for i in prange(n_cases):
        substeps = prepare_chain_case(excitation, table_step, params[i], settings, out[i])
        keys[i] = substeps * _KEY_BASE + int(params[i, SC_SPRING_MASSES]) if substeps > 0 else 0
    order = np.argsort(keys, kind="mergesort")
    starts = chain_block_starts(keys, order)
    schedule = spread_order(starts.shape[0] - 1)
    for i in prange(schedule.shape[0]):
        b = schedule[i]
        block = order[starts[b] : starts[b + 1]]
        _chain_block(
            excitation, table_step, table_start, params, settings, block, keys[block[0]], out
        )
