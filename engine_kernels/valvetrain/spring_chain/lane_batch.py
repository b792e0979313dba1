"""Blocks of the multi-mass spring lane kernel [V4]: grouping keys, boundaries, one block.

The batch entry
:func:`engine_kernels.valvetrain.spring_chain.one_case.spring_chain_response_batch` gives the
results of the one-case kernel bit for bit, ``LANES`` cases per block stepped together by
:mod:`engine_kernels.valvetrain.spring_chain.lanes`. A block's lanes share the number of coil
masses N (the length of their node sweeps) and the RK4 sub-step count the stability guard
gives each case (:func:`block_key`), so each case keeps exactly its own: its results do not
depend on which other cases share its block. Cases the guard refuses (invalid input, sub-step
limit) get their outputs from it and join no block. As for the lumped lanes
(:mod:`engine_kernels.valvetrain.valve.lane_batch`), blocks run in a ``prange`` in an order that
spreads the costly ones over the threads, each writing only its own cases' output rows.

A block costs all its ``LANES`` lanes however few cases fill it, so a block of fewer than
``MIN_BLOCK_CASES`` runs its cases one at a time instead (same numbers). Measured on one core
(256 cases at 0.5°, one sub-step): full blocks run 39, 20, 8 and 6 times as many cases per
second as one case at a time for N = 1, 4, 16, 24, so a block of 8 still gains, while one of
one or two cases can lose up to 5 times.
"""

from __future__ import annotations

import numpy as np

from engine_kernels._jit import jit
from engine_kernels.valvetrain.spring_chain.lane_layout import (
    LANES,
    finish_chain_lanes,
    new_block,
    start_chain_lanes,
)
from engine_kernels.valvetrain.spring_chain.lanes import chain_lane_pass
from engine_kernels.valvetrain.spring_chain.layout import MAX_SPRING_MASSES, SC_SPRING_MASSES

# Blocks with fewer cases run them one at a time (module docstring).
MIN_BLOCK_CASES = 8
_KEY_BASE = MAX_SPRING_MASSES + 1


@jit
def block_key(substeps, params):
    """Block key of a case: sub-steps · (MAX_SPRING_MASSES + 1) + N, or 0 if the guard refused
    it (``substeps`` 0). Sorting by key groups the lanes of a block and sorts blocks by cost.

    substeps : int  From :func:`~engine_kernels.valvetrain.spring_chain.guard.prepare_chain_case`;
    params   : 1-D array  The case's ``SC_*`` row.
    """
    return substeps * _KEY_BASE + int(params[SC_SPRING_MASSES]) if substeps > 0 else 0


@jit
def lane_block(excitation, table_step, table_start, params, block, key, out):
    """Integrate one block of up to ``LANES`` cases with one key in the lane kernel.

    block : 1-D int64  Row indices of the block's cases in ``params`` and ``out``.
    key   : int        Their :func:`block_key`. Other arguments as in
                       :func:`~engine_kernels.valvetrain.spring_chain.one_case.spring_chain_response_batch`.
    Lanes past the block's cases repeat its first case; their results are not written.
    """
    count = block.shape[0]
    masses = key % _KEY_BASE
    substeps = key // _KEY_BASE
    cases = np.empty(LANES, dtype=np.int64)
    for l in range(LANES):
        cases[l] = block[l if l < count else 0]
    arrays = new_block(masses)
    start_chain_lanes(params, cases, masses, 2.0 * table_step / substeps, arrays)
    chain_lane_pass(excitation, table_step, table_start, masses, substeps, arrays)
    finish_chain_lanes(arrays, count, masses, substeps, cases, out)
