"""Benchmark figures of the multi-mass valve spring kernel [V4] beside the lumped one [V2].

The chain rows are the lumped rows of the valve benchmark (same camshaft speeds, preloads,
drive, seat, same excitation table and step) with the spring taken out of the equivalent mass
and modelled as N coil masses: valve-side mass ``M − m_s/3`` with the 15 g spring of the
scene's default equivalent mass, its first mode damped at 3 % (as the kernel tests), no coil
clash. For each N the batch entry (``spring_chain_response_batch``: SIMD lanes) is timed in
turns with the lumped lane kernel on the same rows, and the one-case chain kernel on every
``stride``-th row (at most ``ONE_CASE_CASES``: it is tens of times slower), so the figures
say what the multi-mass model costs against the lumped one and what the lanes gain.
"""

from __future__ import annotations

from functools import partial
from typing import Any

import numpy as np

from engine_kernels import valvetrain as valve
from engine_kernels.valvetrain.spring_chain.layout import (
    CHAIN_OUTPUT_NAMES,
    CHAIN_PARAM_NAMES,
    SC_CLASH_TRAVEL,
    SC_SPRING_DAMPING_RATIO,
    SC_SPRING_MASS,
    SC_SPRING_MASSES,
    SC_VALVE_MASS,
)
from engine_kernels.valvetrain.spring_chain.one_case import (
    spring_chain_one_case_batch,
    spring_chain_response_batch,
)
from engine_kernels.valvetrain.valve import lane_batch as valve_lanes
from studies.common.timing import best_times

CHAIN_MASSES = (1, 2, 4, 8, 16, 24)
SPRING_MASS = 0.015  # kg: the spring behind the valve scene's default equivalent mass [V1]
SPRING_DAMPING_RATIO = 0.03
ONE_CASE_CASES = 1000


def chain_rows(rows: np.ndarray, masses: int) -> np.ndarray:
    """``SC_*`` rows of the lumped ``P_*`` rows: the spring's third off the equivalent mass,
    the spring as ``masses`` coil masses (clash travel 1 m with no stop rate: no clash)."""
    chain = np.zeros((rows.shape[0], len(CHAIN_PARAM_NAMES)))
    chain[:, : rows.shape[1]] = rows
    chain[:, SC_VALVE_MASS] -= SPRING_MASS / 3.0
    chain[:, SC_SPRING_MASS] = SPRING_MASS
    chain[:, SC_SPRING_MASSES] = masses
    chain[:, SC_SPRING_DAMPING_RATIO] = SPRING_DAMPING_RATIO
    chain[:, SC_CLASH_TRAVEL] = 1.0
    return chain


def _timing(cases: int, seconds: float) -> dict[str, float]:
    return {"cases": cases, "seconds": seconds, "cases_per_s": cases / seconds}


def chain_figures(
    excitation: tuple[np.ndarray, float, float], rows: np.ndarray, flags: np.ndarray, repeat: int
) -> dict[str, Any]:
    """Cases/s of the chain kernel for each N in ``CHAIN_MASSES`` and its ratios to the lumped
    lane kernel and to the one-case chain kernel (module docstring).

    excitation : (table, table_step, start) of the valve benchmark; rows : its ``P_*`` rows;
    flags : its ``S_*`` settings; repeat : timed repetitions (best kept).
    """
    table, table_step, start = excitation
    n = rows.shape[0]
    subset = slice(None, None, max(1, -(-n // ONE_CASE_CASES)))
    lumped_out = np.empty((n, len(valve.VALVE_OUTPUT_NAMES)))
    chain_out = np.empty((n, len(CHAIN_OUTPUT_NAMES)))
    lanes = {
        "lumped_lanes": partial(
            valve_lanes.valve_response_lanes, *excitation, rows, flags, lumped_out
        )
    }
    one_case = {}
    for masses in CHAIN_MASSES:
        chain = chain_rows(rows, masses)
        lanes[f"n{masses}_lanes"] = partial(
            spring_chain_response_batch, table, table_step, start, chain, flags, chain_out
        )
        one_case[f"n{masses}_one_case"] = partial(
            spring_chain_one_case_batch,
            table,
            table_step,
            start,
            chain[subset],
            flags,
            chain_out[subset],
        )
    figures: dict[str, Any] = {"spring_mass_kg": SPRING_MASS}
    for name, seconds in zip(lanes, best_times(list(lanes.values()), repeat), strict=True):
        figures[name] = _timing(n, seconds)
    few = len(range(n)[subset])
    for name, seconds in zip(one_case, best_times(list(one_case.values()), repeat), strict=True):
        figures[name] = _timing(few, seconds)
    lumped = figures["lumped_lanes"]["cases_per_s"]
    for masses in CHAIN_MASSES:
        rate = figures[f"n{masses}_lanes"]["cases_per_s"]
        figures[f"n{masses}_lanes_over_lumped_lanes"] = rate / lumped
        figures[f"n{masses}_lanes_over_one_case"] = (
            rate / figures[f"n{masses}_one_case"]["cases_per_s"]
        )
    return figures
