"""Accuracy and cost of the valve integrators: reference solution, trajectory error, timing.

The error of a fixed-step run is measured against scipy's event-restarted ``solve_ivp``
(:mod:`studies.scenes.valve.reference.valve_ivp`, DOP853 or Radau at rtol ~1e-10) on the same model and
the same excitation: the chain's valve lift before the lash take-up sampled every
``REFERENCE_TABLE_DEG``, interpolated and clipped as the kernels do. The error is the largest ``|y − y_ref|`` over the run's grid
points (the whole integration window). The reference is evaluated on one grid holding the
nodes of every step of a chunk and of the ``REFERENCE_TABLE_DEG`` grid, so for the usual steps
(2°/2^k) it is solved once per design point whatever the chunking. The lane kernel integrates exactly the plain RK4 scheme
of the one-case kernel (in SIMD lanes), so the trajectory of a ``lanes`` run is taken from the
one-case kernel at the same step; only its cost differs. ``lanes_f32`` (single precision)
differs by round-off, so its trajectory comes from the lane kernel itself.

Cost per case is a wall-clock timing: the integrator (or the tolerance ladder) runs copies of
the design point, at least ``COST_CASES`` (two lane blocks so both cores work) and enough that
the fixed cost of a call (measured as a call with one case: dispatch, thread start, tables)
is at most ``MAX_OVERHEAD`` of a run; the median of ``COST_REPEATS`` runs at that size is
divided by the number of cases, and their interquartile range (IQR) is stored beside it
(``cost_per_case_iqr``): a difference smaller than the spreads is noise. On a loaded machine
that fixed cost was 10–24 ms, 100× the kernel's time for 64 lane cases. It varies from run to
run and machine to machine; compare within one run.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Iterable
from fractions import Fraction

import numpy as np

from engine_kernels import valvetrain as valve
from engine_kernels.valvetrain.valve import lane_batch as valve_lanes
from studies.scenes.valve.parameters import LANE_PRECISION
from studies.scenes.valve.reference.valve_ivp import table_excitation, valve_reference

REFERENCE_TABLE_DEG = 1.0 / 512.0
"""Spacing of the reference's excitation table [deg]: finer than any table the tolerance ladder
uses (1/256° after six halvings of 0.5°). At 1/64° the reference's own table error reached
0.1–0.3 µm in violent separation (measured against 1/512°), the size of the errors measured."""
COST_CASES = 64
MAX_COST_CASES = 1 << 16
MAX_OVERHEAD = 0.05
COST_REPEATS = 5
MAX_DENOMINATOR = 1_000_000

Excitation = tuple[np.ndarray, float, float]


def common_spacing(steps_deg: Iterable[float]) -> float:
    """Largest spacing [deg] whose grid holds the nodes of every step (their common divisor)."""
    fractions = [Fraction(s).limit_denominator(MAX_DENOMINATOR) for s in steps_deg]
    denominator = math.lcm(*(f.denominator for f in fractions))
    numerator = math.gcd(*(int(f * denominator) for f in fractions))
    return numerator / denominator


def reference_lift(
    fine: Excitation, row: np.ndarray, theta: np.ndarray, method: str, rtol: float
) -> np.ndarray:
    """Reference valve lift [m] at the cam angles ``theta`` [rad] (scipy, event restarts).

    fine   : (table, table_step [rad], start [rad]) of Y, Y', Y'' at a fine spacing.
    row    : valve parameter row (``engine_kernels.valvetrain.P_*``, SI).
    method : ``"DOP853"`` or ``"Radau"``; rtol: relative tolerance of the solver.
    """
    excitation = table_excitation(*fine)
    return valve_reference(excitation, row, theta, method=method, rtol=rtol).lift


def trajectory_lift(
    excitation: Excitation, row: np.ndarray, flags: np.ndarray, integrator: str
) -> np.ndarray:
    """Valve lift [m] at every grid point of one fixed-step run.

    ``lanes_f32`` runs the lane kernel in single precision; every other integrator's
    trajectory is the one-case kernel's (``lanes`` computes exactly the same numbers).
    """
    table, table_step, start = excitation
    if integrator == "lanes_f32":
        lift = np.empty((table.shape[1] - 1) // 2 + 1)
        single = table.astype(LANE_PRECISION[integrator])
        valve_lanes.lift_trace_lanes(single, table_step, start, row, flags, lift)
        return lift
    out = np.empty(len(valve.VALVE_OUTPUT_NAMES))
    curves = np.empty((len(valve.VALVE_CURVE_NAMES), (table.shape[1] - 1) // 2 + 1))
    valve.valve_response(table, table_step, start, row, flags, out, curves)
    return curves[valve.C_LIFT]


def max_error(lift: np.ndarray, reference: np.ndarray, stride: int) -> float:
    """Largest |lift − reference| [m], the reference on a grid ``stride`` times finer."""
    return float(np.max(np.abs(lift - reference[::stride])))


def seconds_per_case(
    run: Callable[[np.ndarray], object],
    row: np.ndarray,
    max_overhead: float = MAX_OVERHEAD,
    repeats: int = COST_REPEATS,
) -> float:
    """Median wall-clock seconds per case of ``run`` on copies of ``row`` (see
    :func:`timing_per_case`)."""
    return timing_per_case(run, row, max_overhead, repeats)[0]


def timing_per_case(
    run: Callable[[np.ndarray], object],
    row: np.ndarray,
    max_overhead: float = MAX_OVERHEAD,
    repeats: int = COST_REPEATS,
) -> tuple[float, float]:
    """Median and interquartile range of the wall-clock seconds per case of ``run`` on copies
    of ``row``.

    The fixed cost of a call is the median time of ``repeats`` calls with one case; the copies
    start at ``COST_CASES`` and double until it is at most ``max_overhead`` of one run (at
    most ``MAX_COST_CASES`` copies); that run and ``repeats`` − 1 more are the timings.
    """
    single = np.ascontiguousarray(row[None, :])
    fixed = float(np.median([_seconds(run, single) for _ in range(repeats)]))
    cases = COST_CASES
    while True:
        rows = np.ascontiguousarray(np.tile(row, (cases, 1)))
        elapsed = _seconds(run, rows)
        if fixed <= max_overhead * elapsed or cases >= MAX_COST_CASES:
            break
        cases *= 2
    times = np.array([elapsed] + [_seconds(run, rows) for _ in range(repeats - 1)]) / cases
    low, high = np.percentile(times, [25.0, 75.0])
    return float(np.median(times)), float(high - low)


def _seconds(run: Callable[[np.ndarray], object], rows: np.ndarray) -> float:
    t0 = time.perf_counter()
    run(rows)
    return time.perf_counter() - t0
