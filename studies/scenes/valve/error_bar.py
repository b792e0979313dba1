"""Error bars of the valve dynamics and the tolerance ladder (physics §4, issues #15, #26).

A run at angle step h takes n RK4 sub-steps per grid step on an excitation table of spacing
h/2. Its **companion** halves every length: step h/2, table h/4 and the same n sub-steps per
(half as long) grid step, so each sub-step is exactly half as long. The count is forced with
the kernels' ``substeps`` setting: on a stiff seat the stability guard alone would halve the
number of sub-steps instead of their length, and the error of a seat contact would never
shrink. The companion never takes a longer step than the run, so it never breaks the RK4
stability bound and the bar is never NaN for a finished point.

The **error bar** of the run (``error_estimate``) is ``BAR_FACTOR`` times the step-halving
difference ``max |y_h − y_h/2|`` over the run's grid. Two errors shrink when every length
halves: the integration error (fourth order with located switches, about 1.6 for plain RK4,
not monotone) and the excitation error (the cubic Hermite interpolation of the chain's table
between nodes, where the cam law's acceleration jumps: about second order). The factor
1/(1 − 2⁻¹) = 2 turns the difference into an error for any order ≥ 1, and a safety factor
1.5 covers the non-monotone convergence of plain RK4. Plain RK4's runs come from the lane
kernel as ``lanes`` and ``lanes_f32`` run without a tolerance (double precision: the one-case
kernel's numbers to round-off; single precision for ``lanes_f32``, whose round-off is then in
the bar); switch-aware RK4's come from the one-case kernel. On sample A's 48 points tiled 5×
(one linkage) the first rung's runs took 50-53 µs per point instead of 127-234 one case at a
time; where every point has a linkage of its own (sample B) 0.9-1.3 ms instead of 0.2-0.5 (a
block integrates 32 lanes however few cases fill it), a third of the 2.9-3.4 ms such a point
costs under a 1e-3 mm tolerance.

**Derived outputs** (max lift, jump start, seating velocity, bounce height) are located
between the grid points by the kernels (:mod:`engine_kernels.valvetrain.valve.located`), but their
step-halving difference still missed their error: the kinks of the excitation (lash take-up,
the cam law's segment ends) make plain RK4's error in them jump from one step to the next (on
the random samples the jump-start bar held in 89–92 %). Their bars (``DERIVED_BARS``) for the
points a fixed-step rung reports therefore come from a ``dopri`` companion that is far more
accurate and independent of the run (:func:`companion_bars`: ``COMPANION_TOLERANCE`` per step
on an unclipped table every ``COMPANION_TABLE_DEG``, its steps at most the grid step), times
``COMPANION_BAR_FACTOR``; computed only when a study asks for one of those bars.

The **budget** splits the bar: a third run at step h with the table of h/2 and 2n sub-steps
differs from the run only by the integration (``integration_error``) and from the companion
only by the excitation table and the grid (``excitation_error``).

**Tolerance**: starting at ``angle_step``, each level halves every length as above; a point
stops at the first level whose bar is within the tolerance (that level's results are reported
with that bar, ``tolerance_met`` = 1), or at ``MAX_HALVINGS`` with the last bar and 0.

**dopri** (adaptive Dormand–Prince 5(4), :mod:`engine_kernels.valvetrain.dopri.integrate`) has no step
to halve: its companion runs at a tenth of the lift tolerance per step on a table of half the
spacing (``dopri_table_deg``) with its steps capped at the grid step, so the difference sees
the integration and the table error and shares neither the run's long steps over a resting
valve nor a switch found in one of them; the bar is ``DOPRI_BAR_FACTOR`` times the largest
lift difference over the grid, and the same factor on each derived output's difference (both
runs locate them on their dense output). Under a tolerance, points the first rung leaves
above it run ``dopri`` at tolerance/``DOPRI_SAFETY`` per step; the points its bar still leaves
above run it once more at a per-step tolerance ``DOPRI_RETRY`` times tighter (same table), and
only those that still miss go down the switch-aware ladder. The budget is not split for ``dopri``
(``integration_error`` is its bar, ``excitation_error`` NaN).

Measured against the scipy reference on two samples of 200 random points
(``tests/studies/test_valve_error_bar.py``: the six-segment cam with speed, seat, preload and
drive varied; every lift law with lash, damping, mass, spring and drive varied too): the lift
bar bounds the true error in 98.5/99.5 % (``lanes`` at 0.5°), 99.5/100 % (switch-aware),
99.5/100 % (``dopri``), 99/100 % (tolerance 1e-3 mm) and 99.5/100 % (1e-4 mm) of the points;
every derived bar in at least 95.7 % (1e-4 mm's jump start on the first sample), and every bar
is within 10× of the true error in at least 91.5 %. No point reports ``tolerance_met`` = 1
above its tolerance.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from engine_kernels import valvetrain as valve
from engine_kernels.valvetrain.valve import lane_batch as valve_lanes
from studies.scenes.valve.batches import dopri_lifts
from studies.scenes.valve.parameters import (
    DOPRI,
    LANE_PRECISION,
    MAX_HALVINGS,
    dopri_table_deg,
    dopri_tolerance,
)

Excitation = tuple[np.ndarray, float, float]
ExcitationAt = Callable[[float, bool], Excitation]
"""(angle step [deg], unclipped) -> the excitation table at half that step (the scene's
``excitation``: clipped for RK4, unclipped for ``dopri``)."""
SWITCH_AWARE = "rk4_switch_aware"
BAR_FACTOR = 3.0
"""Error bar per unit of step-halving difference: 1/(1 − 2⁻¹) for first order × 1.5 [-]."""
DERIVED_BARS = {
    "jump_start_error": valve.O_JUMP_START,
    "seating_velocity_error": valve.O_SEATING_VELOCITY,
    "bounce_height_error": valve.O_BOUNCE_HEIGHT,
    "max_lift_error": valve.O_MAX_LIFT,
}
"""Bars of derived outputs: response name -> output column whose two runs are compared."""
DOPRI_BAR_FACTOR = 3.0
"""Error bar of ``dopri`` per unit of its companion difference [-] (see the module docstring)."""
DOPRI_TIGHTENING = 10.0
"""The ``dopri`` companion runs at the tolerance per step / DOPRI_TIGHTENING [-]."""
DOPRI_RETRY = 100.0
"""The second ``dopri`` rung runs at the first one's per-step tolerance / DOPRI_RETRY [-]. The points
the first rung leaves above the tolerance are slow valves (440-870 rpm on the random
samples) whose landing on a stiff seat hides a bounce shorter than a step: at 1e-7 and 1e-8
m per step the error stayed at 1.4 µm, at 1e-9 m it was 0.008 µm. On both 200-point samples
the second rung's bar met 1e-3 and 1e-4 mm at every point its first left above (8 + 12 and
9 + 16 points), where the switch-aware ladder cost 50-400 times a ``dopri`` run per point.
Used from ``DOPRI_RETRY_FROM`` up, where its bars were checked."""
DOPRI_RETRY_FROM = 1e-7
"""Smallest study tolerance [m] (1e-4 mm) with the second ``dopri`` rung: the tolerances where
its bars were checked against the scipy reference on both random samples. At 1e-4 mm it was
kept off until ``dopri`` dated a jump where the drive force reaches zero: before, its
converged jump start lay band/|dF/dθ| (~1e-5°) behind the reference, above its own bars
(~1e-7°). Below 1e-4 mm the points the first rung leaves above go down the switch-aware
ladder."""
COMPANION_TOLERANCE = 1e-10
"""Lift tolerance per step [m] of the ``dopri`` companion of fixed-step derived outputs."""
COMPANION_TABLE_DEG = 1.0 / 256.0
"""Excitation table spacing [deg] of that companion."""
COMPANION_BAR_FACTOR = 2.0
"""Bar of a fixed-step derived output per unit of its difference from the companion:
1/(1 − 1/2), the companion's own error allowed up to half the run's [-]."""


@dataclass
class Ladder:
    """Outcome of the halving ladder for a set of points (SI units, angles in degrees)."""

    out: np.ndarray
    level: np.ndarray
    bar: np.ndarray
    met: np.ndarray
    substeps: np.ndarray
    derived: dict[str, np.ndarray] = field(default_factory=dict)
    budget: dict[str, np.ndarray] = field(default_factory=dict)
    per_step: float = 0.0
    """``dopri``: the lift tolerance per step [m] of its run (0: fixed-step RK4)."""


def lift_runs(
    excitation: Excitation,
    rows: np.ndarray,
    flags: np.ndarray,
    forced: np.ndarray,
    precision: type = np.float64,
) -> tuple[np.ndarray, np.ndarray]:
    """Outputs (n, O_*) and lift at every grid point [m] of plain RK4 (the lane kernel in
    ``precision``, as ``lanes`` and ``lanes_f32`` run without a tolerance: the same numbers
    whatever the chunk), or of switch-aware RK4 (the one-case kernel) under
    ``flags[S_SWITCH_AWARE]``.

    forced    : sub-steps per grid step of each row (0: the guard's count), rows with the
                same count run as one batch.
    precision : arithmetic of plain RK4's lanes (``np.float32``: ``lanes_f32``).
    """
    table, table_step, start = excitation
    lanes = not flags[valve.S_SWITCH_AWARE]
    if lanes:
        table = table.astype(precision, copy=False)
    out = np.full((rows.shape[0], len(valve.VALVE_OUTPUT_NAMES)), np.nan)
    lifts = np.full((rows.shape[0], (table.shape[1] - 1) // 2 + 1), np.nan)
    for count in np.unique(forced):
        members = np.flatnonzero(forced == count)
        local = flags.copy()
        local[valve.S_SUBSTEPS] = int(count)
        part_out = np.empty((members.size, out.shape[1]))
        part_lifts = np.empty((members.size, lifts.shape[1]))
        (valve_lanes.valve_lift_lanes if lanes else valve.valve_lift_batch)(
            table,
            table_step,
            start,
            np.ascontiguousarray(rows[members]),
            local,
            part_out,
            part_lifts,
        )
        out[members], lifts[members] = part_out, part_lifts
    return out, lifts


def halving_difference(coarse: np.ndarray, fine: np.ndarray) -> np.ndarray:
    """max |coarse − fine| [m] per row over the coarse grid (fine holds twice the intervals)."""
    return np.max(np.abs(coarse - fine[:, ::2]), axis=1)


def output_difference(coarse: np.ndarray, fine: np.ndarray) -> np.ndarray:
    """|coarse − fine| of one output column; 0 where both are NaN (no such event), inf where
    only one run has it (the runs disagree on whether it happens)."""
    both = np.isnan(coarse) & np.isnan(fine)
    one = np.isnan(coarse) ^ np.isnan(fine)
    difference = np.abs(coarse - fine)
    return np.where(both, 0.0, np.where(one, np.inf, difference))


def halving_ladder(
    excitation_at: ExcitationAt,
    rows: np.ndarray,
    flags: np.ndarray,
    coarse_deg: float,
    tolerance: float,
    max_halvings: int,
    budget: bool,
    precision: type = np.float64,
) -> Ladder:
    """Run the points ``rows`` down the ladder (see the module docstring).

    excitation_at : (angle step [deg], unclipped) -> its excitation table (``ExcitationAt``).
    flags         : kernel settings row (``S_*``) of the integrator.
    tolerance     : [m]; 0 stops every point at the first level (the error bar only).
    budget        : also estimate the integration and excitation parts of the bar.
    precision     : arithmetic of plain RK4 (``lift_runs``).
    """
    n = rows.shape[0]
    out, lifts = lift_runs(
        excitation_at(coarse_deg, False), rows, flags, np.zeros(n, dtype=np.int64), precision
    )
    finished = out[:, valve.O_STATUS] == valve.STATUS_OK
    forced = np.where(np.isfinite(out[:, valve.O_SUBSTEPS]), out[:, valve.O_SUBSTEPS], 0)
    forced = forced.astype(np.int64)
    ladder = Ladder(
        out=out,
        level=np.zeros(n, dtype=np.int64),
        bar=np.full(n, np.nan),
        met=np.zeros(n),
        substeps=forced,
        derived={name: np.full(n, np.nan) for name in DERIVED_BARS},
        budget={"integration_error": np.full(n, np.nan), "excitation_error": np.full(n, np.nan)},
    )
    pending = np.flatnonzero(finished)
    out, lifts = out[pending], lifts[pending]
    for level in range(max_halvings + 1):
        if pending.size == 0:
            break
        step = coarse_deg / 2**level
        fine = excitation_at(step / 2.0, False)
        fine_out, fine_lifts = lift_runs(fine, rows[pending], flags, forced[pending], precision)
        bar = BAR_FACTOR * halving_difference(lifts, fine_lifts)
        done = (bar <= tolerance) | (level == max_halvings) | (tolerance <= 0.0)
        take = pending[done]
        ladder.out[take], ladder.level[take], ladder.bar[take] = out[done], level, bar[done]
        ladder.met[take] = (bar[done] <= tolerance).astype(float)
        if budget and take.size:
            middle = lift_runs(
                excitation_at(step, False), rows[take], flags, 2 * forced[take], precision
            )[1]
            ladder.budget["integration_error"][take] = BAR_FACTOR * np.max(
                np.abs(lifts[done] - middle), axis=1
            )
            ladder.budget["excitation_error"][take] = BAR_FACTOR * halving_difference(
                middle, fine_lifts[done]
            )
        pending, out, lifts = pending[~done], fine_out[~done], fine_lifts[~done]
    return ladder


def dopri_ladder(
    excitation_at: ExcitationAt,
    rows: np.ndarray,
    coarse_deg: float,
    tolerance: float,
    tightening: float = 1.0,
) -> Ladder:
    """The ``dopri`` rung: its run at the per-step tolerance of ``tolerance`` [m] (0: none,
    :func:`~studies.scenes.valve.parameters.dopri_tolerance`) divided by ``tightening`` on the
    ``coarse_deg`` grid, and its bar from the companion (see the module docstring). Level 0,
    no forced sub-steps."""
    atol = dopri_tolerance(tolerance) / tightening
    spacing = dopri_table_deg(tolerance)
    out, lifts = dopri_lifts(excitation_at(2.0 * spacing, True), rows, coarse_deg, atol, 0.0)
    fine_out, fine_lifts = dopri_lifts(
        excitation_at(spacing, True), rows, coarse_deg, atol / DOPRI_TIGHTENING, coarse_deg
    )
    finished = (out[:, valve.O_STATUS] == valve.STATUS_OK) & (
        fine_out[:, valve.O_STATUS] == valve.STATUS_OK
    )
    n = rows.shape[0]
    bar = np.full(n, np.nan)
    bar[finished] = DOPRI_BAR_FACTOR * np.max(
        np.abs(lifts[finished] - fine_lifts[finished]), axis=1
    )
    met = ((bar <= tolerance) & finished).astype(float)
    derived = derived_bars(out, fine_out, DOPRI_BAR_FACTOR, finished)
    return Ladder(
        out=out,
        level=np.zeros(n, dtype=np.int64),
        bar=bar,
        met=met,
        substeps=np.zeros(n, dtype=np.int64),
        derived=derived,
        budget={"integration_error": bar.copy(), "excitation_error": np.full(n, np.nan)},
        per_step=atol,
    )


def companion_bars(
    excitation_at: ExcitationAt,
    rows: np.ndarray,
    out: np.ndarray,
    coarse_deg: float,
    tolerance: float,
) -> dict[str, np.ndarray]:
    """Bars of the derived outputs of fixed-step runs (``out``, (n, O_*)) of ``rows``: the
    factor ``COMPANION_BAR_FACTOR`` times their difference from a ``dopri`` companion at
    ``COMPANION_TOLERANCE`` per step (or the tolerance mode's companion, if tighter) on an
    unclipped table every ``COMPANION_TABLE_DEG`` (or finer), its steps at most the grid step
    (see the module docstring). NaN where either run did not finish."""
    atol = COMPANION_TOLERANCE
    spacing = COMPANION_TABLE_DEG
    if tolerance > 0.0:
        atol = min(atol, dopri_tolerance(tolerance) / DOPRI_TIGHTENING)
        spacing = min(spacing, dopri_table_deg(tolerance) / 2.0)
    companion = dopri_lifts(excitation_at(2.0 * spacing, True), rows, coarse_deg, atol, coarse_deg)[
        0
    ]
    finished = (out[:, valve.O_STATUS] == valve.STATUS_OK) & (
        companion[:, valve.O_STATUS] == valve.STATUS_OK
    )
    return derived_bars(out, companion, COMPANION_BAR_FACTOR, finished)


def derived_bars(
    out: np.ndarray, other: np.ndarray, factor: float, finished: np.ndarray
) -> dict[str, np.ndarray]:
    """``factor`` × the difference of each derived output of ``out`` from ``other`` (both
    (n, O_*)); NaN where a run did not finish, and for a bounce height the run left unknown
    (NaN: the valve had not settled, a value missing rather than no bounce)."""
    bars = {
        name: np.where(finished, factor * output_difference(out[:, c], other[:, c]), np.nan)
        for name, c in DERIVED_BARS.items()
    }
    bars["bounce_height_error"][np.isnan(out[:, valve.O_BOUNCE_HEIGHT])] = np.nan
    return bars


def tolerance_rungs(
    excitation_at: ExcitationAt,
    rows: np.ndarray,
    flags_of: Callable[[str], np.ndarray],
    integrator: str,
    coarse_deg: float,
    tolerance: float,
    budget: bool,
    derived: bool,
) -> list[tuple[np.ndarray, str, Ladder]]:
    """The rungs a study's points go down: (row positions, method, its ladder) each.

    Without a tolerance one rung: the integrator at ``coarse_deg`` with its error bar. Under
    a tolerance [m] a plain-RK4 integrator gets one rung at ``coarse_deg`` (its cheap run and
    bar); the finished points it leaves above the tolerance get the ``dopri`` rung
    (:func:`dopri_ladder`: it met 1e-3 mm on a random sample at about 1/80 of the ladder's
    cost), those still above a second one ``DOPRI_RETRY`` times tighter per step (from
    ``DOPRI_RETRY_FROM`` up), and those still
    above go down the ladder of switch-aware RK4 (plain RK4 left 12 % of a random sample
    above 1e-3 mm after six halvings). ``flags_of``: kernel settings of a
    method; ``derived``: bars of the derived outputs (``DERIVED_BARS``) are wanted, which for
    the points a fixed-step rung reports come from :func:`companion_bars`.
    """
    retry = [(DOPRI, 0, DOPRI_RETRY)] if tolerance >= DOPRI_RETRY_FROM else []
    adaptive = [(DOPRI, 0, 1.0), *retry, (SWITCH_AWARE, MAX_HALVINGS, 1.0)]
    rungs = [(integrator, MAX_HALVINGS if tolerance > 0.0 else 0, 1.0)]
    if tolerance > 0.0 and integrator == DOPRI:
        rungs = adaptive
    elif tolerance > 0.0 and integrator != SWITCH_AWARE:
        rungs = [(integrator, 0, 1.0), *adaptive]
    pending = np.arange(rows.shape[0])
    taken = []
    for method, halvings, tightening in rungs:
        if pending.size == 0:
            break
        if method == DOPRI:
            ladder = dopri_ladder(excitation_at, rows[pending], coarse_deg, tolerance, tightening)
        else:
            ladder = halving_ladder(
                excitation_at,
                rows[pending],
                flags_of(method),
                coarse_deg,
                tolerance,
                halvings,
                budget,
                LANE_PRECISION.get(method, np.float64),
            )
        finished = ladder.out[:, valve.O_STATUS] == valve.STATUS_OK
        passed_on = finished & (ladder.met == 0.0) & ((method, halvings, tightening) != rungs[-1])
        if derived and method != DOPRI and (~passed_on).any():
            kept = np.flatnonzero(~passed_on)
            bars = companion_bars(
                excitation_at, rows[pending[kept]], ladder.out[kept], coarse_deg, tolerance
            )
            for name, values in bars.items():
                ladder.derived[name][kept] = values
        taken.append((pending, method, ladder))
        pending = pending[passed_on]
    return taken
