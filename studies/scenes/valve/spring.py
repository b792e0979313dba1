"""The valve scene's multi-mass spring rung [V4]: kernel rows, runs, and what they answer.

:mod:`studies.scenes.valve.spring_parameters` says which responses need the chain and how the
two rungs share their inputs. Here: the chain kernel's ``SC_*`` rows from the design points,
one run of :func:`~engine_kernels.valvetrain.spring_chain.one_case.spring_chain_response_batch`
per chain group (or one case at a time when curves are stored), the outputs that replace the
lumped rung's under ``spring_model = "multi_mass"``, and the checks of a request.
"""

from __future__ import annotations

from typing import Any, Protocol

import numpy as np

from engine_kernels import valvetrain as valve
from engine_kernels.valvetrain.spring_chain import layout as sc
from engine_kernels.valvetrain.spring_chain.model import chain_natural_frequency
from engine_kernels.valvetrain.spring_chain.one_case import (
    spring_chain_response,
    spring_chain_response_batch,
)
from studies.scenes.checks import PointProblems
from studies.scenes.linkage.scene import HALF_TURN_DEG, step_deg
from studies.scenes.valve.batches import N_OUT, kernel_settings
from studies.scenes.valve.parameters import STATUS_NOT_RUN
from studies.scenes.valve.spring_parameters import CHAIN_UNOBSERVED, SURGE_CURVES
from studies.scenes.valve.state import ValveState


class SurgeHost(Protocol):
    """What the ``surge`` stage asks of the scene that runs it (the valve scene): the curve
    axis, which cam–rocker chains are valid, the chain kernel's rows and the excitation."""

    def curve_coordinate(self, settings: dict[str, Any]) -> np.ndarray: ...

    def linkage_valid(self, state: ValveState, key: tuple) -> bool: ...

    def spring_rows(self, state: ValveState, idx: np.ndarray) -> np.ndarray: ...

    def window(self, state: ValveState, key: tuple) -> tuple[float, float]: ...

    def excitation(
        self,
        state: ValveState,
        key: tuple,
        step: float,
        span: tuple[float, float] | None = None,
    ) -> tuple[np.ndarray, float, float]: ...


MM = 1e3
TWO_PI = 2.0 * np.pi
N_CHAIN_OUT = len(sc.CHAIN_OUTPUT_NAMES)
N_CHAIN_CURVES = len(sc.CHAIN_CURVE_NAMES)
SPRING_MASS_SHARE = 1.0 / 3.0
MASS_NAMES = ("equivalent_mass", "spring_mass")  # what spring_point_problems reads
"""Share of the spring's mass in the [V1] equivalent mass (the lumped rung's m_s/3 rule)."""

# lumped output column <- chain output column, for the responses both rungs observe
LUMPED_FROM_CHAIN = {
    valve.O_MAX_LIFT: sc.CO_MAX_LIFT,
    valve.O_MAX_VELOCITY: sc.CO_MAX_VELOCITY,
    valve.O_MIN_VELOCITY: sc.CO_MIN_VELOCITY,
    valve.O_JUMP_START: sc.CO_JUMP_START,
    valve.O_JUMP_DURATION: sc.CO_JUMP_DURATION,
    valve.O_JUMP_GAP: sc.CO_JUMP_GAP,
    valve.O_BOUNCE_COUNT: sc.CO_BOUNCE_COUNT,
    valve.O_BOUNCE_HEIGHT: sc.CO_BOUNCE_HEIGHT,
    valve.O_SEATING_VELOCITY: sc.CO_SEATING_VELOCITY,
    valve.O_MAX_CONTACT_FORCE: sc.CO_MAX_CONTACT_FORCE,
    valve.O_SUBSTEPS: sc.CO_SUBSTEPS,
    valve.O_STEP_RATIO: sc.CO_STEP_RATIO,
    valve.O_STATUS: sc.CO_STATUS,
}
STEADY_COLUMNS = [
    sc.CO_SURGE_AMPLITUDE,
    sc.CO_MIN_RETAINER_RATIO,
    sc.CO_MAX_RETAINER_DEVIATION,
    sc.CO_CLASH_COUNT,
    sc.CO_STATUS,
]
"""Chain outputs a run over several revolutions gives for the spring responses: all of
``SURGE_OUTPUT``'s columns, so the single-event run is needed only for the dynamics or curves."""
# response -> (chain output column, factor from SI to the response's units)
SURGE_OUTPUT = {
    "surge_amplitude": (sc.CO_SURGE_AMPLITUDE, MM),
    "min_retainer_force_ratio": (sc.CO_MIN_RETAINER_RATIO, 1.0),
    "max_retainer_force_deviation": (sc.CO_MAX_RETAINER_DEVIATION, 1.0),
    "coil_clash_count": (sc.CO_CLASH_COUNT, 1.0),
    "surge_status": (sc.CO_STATUS, 1.0),
}
# curve -> (chain curve row, factor from SI)
CHAIN_CURVE_ROW = {
    "actual_lift": (sc.CC_LIFT, MM),
    "actual_velocity": (sc.CC_VELOCITY, 1.0),
    "drive_force": (sc.CC_DRIVE_FORCE, 1.0),
    "retainer_force": (sc.CC_RETAINER_FORCE, 1.0),
    "spring_surge": (sc.CC_SURGE, MM),
}
SURGE_CURVE_NAMES = frozenset(c.name for c in SURGE_CURVES)
_SPRING_COLUMN = {
    "spring_mass": sc.SC_SPRING_MASS,
    "spring_damping_ratio": sc.SC_SPRING_DAMPING_RATIO,
    "clash_travel": sc.SC_CLASH_TRAVEL,
    "clash_stiffness": sc.SC_CLASH_STIFFNESS,
    "clash_damping": sc.SC_CLASH_DAMPING,
}


def surge_frequency(points: dict[str, np.ndarray], masses: int) -> np.ndarray:
    """First fixed–fixed frequency [Hz] of the N-mass spring of each point [V4], computed
    once per distinct (spring rate, spring mass) pair."""
    pairs, where = np.unique(
        np.stack([points["spring_rate"], points["spring_mass"]], axis=1),
        axis=0,
        return_inverse=True,
    )
    frequency = [chain_natural_frequency(k, m, masses, 1) / TWO_PI for k, m in pairs]
    return np.asarray(frequency)[where.ravel()]


def uses_chain(settings: dict[str, Any]) -> bool:
    """True when the dynamic responses come from the multi-mass rung."""
    return settings.get("spring_model", "lumped") == "multi_mass"


def chain_rows(
    lumped: np.ndarray, points: dict[str, np.ndarray], idx: Any, masses: int
) -> np.ndarray:
    """``SC_*`` rows (SI) from the lumped ``P_*`` rows of the points ``idx``: the valve-side
    mass is the equivalent mass less the spring's third [V1], N = ``masses``."""
    rows = np.zeros((lumped.shape[0], len(sc.CHAIN_PARAM_NAMES)))
    rows[:, : lumped.shape[1]] = lumped
    for name, column in _SPRING_COLUMN.items():
        rows[:, column] = points[name][idx]
    rows[:, sc.SC_VALVE_MASS] -= SPRING_MASS_SHARE * rows[:, sc.SC_SPRING_MASS]
    rows[:, sc.SC_SPRING_MASSES] = masses
    return rows


def run_chain(
    excitation: tuple[np.ndarray, float, float], rows: np.ndarray, flags: np.ndarray, curves: bool
) -> tuple[np.ndarray, np.ndarray | None]:
    """Chain outputs (n, CO_*) on one excitation, and its curves (n, CC_*, grid) if asked."""
    table, table_step, start = excitation
    out = np.empty((rows.shape[0], N_CHAIN_OUT))
    if not curves:
        spring_chain_response_batch(table, table_step, start, rows, flags, out)
        return out, None
    trace = np.empty((rows.shape[0], N_CHAIN_CURVES, (table.shape[1] - 1) // 2 + 1))
    for j in range(rows.shape[0]):
        spring_chain_response(table, table_step, start, rows[j], flags, out[j], trace[j])
    return out, trace


def steady_surge(
    revolution: tuple[np.ndarray, float, float], rows: np.ndarray, flags: np.ndarray, turns: int
) -> np.ndarray:
    """Chain outputs over ``turns`` camshaft revolutions of a periodic cam, with the surge
    amplitude and the retainer force ratio and deviation taken over the last one.

    revolution : (table, step [rad], start [rad]) over one whole revolution (its last node is
    its first one again). One case at a time, its curves reduced as soon as it finishes.
    """
    table, table_step, start = revolution
    tiled = np.concatenate([np.tile(table[:, :-1], turns), table[:, :1]], axis=1)
    per_turn = (table.shape[1] - 1) // 2
    out = np.empty((rows.shape[0], N_CHAIN_OUT))
    trace = np.empty((N_CHAIN_CURVES, per_turn * turns + 1))
    for j in range(rows.shape[0]):
        spring_chain_response(tiled, table_step, start, rows[j], flags, out[j], trace)
        last = trace[:, -(per_turn + 1) :]
        static = rows[j, sc.SC_PRELOAD] + rows[j, sc.SC_SPRING_RATE] * last[sc.CC_LIFT]
        retainer = last[sc.CC_RETAINER_FORCE]
        out[j, sc.CO_SURGE_AMPLITUDE] = last[sc.CC_SURGE].max()
        out[j, sc.CO_MIN_RETAINER_RATIO] = (retainer / static).min()
        out[j, sc.CO_MAX_RETAINER_DEVIATION] = np.abs(retainer - static).max()
    return out


def request_problems(
    settings: dict[str, Any], responses: list[str], curves: list[str]
) -> list[str]:
    """Requests the chosen spring model cannot answer."""
    if not uses_chain(settings):
        return []
    problems = [
        f"{kind} {name!r} is not observed by spring_model = 'multi_mass' (the multi-mass "
        "kernel records lift, velocities, jump, bounce, seating and forces); ask for it with "
        "spring_model = 'lumped'"
        for kind, names in (("response", responses), ("curve", curves))
        for name in names
        if name in CHAIN_UNOBSERVED
    ]
    if settings.get("tolerance", 0.0) > 0.0:
        problems.append(
            f"setting tolerance = {settings['tolerance'] * MM:g} mm: the step is picked by a "
            "tolerance only for spring_model = 'lumped'; with 'multi_mass' set angle_step"
        )
    return problems


def spring_point_problems(points: dict[str, np.ndarray]) -> list[str]:
    """Design points whose spring mass leaves no valve-side mass (equivalent mass ≤ m_s/3)."""
    found = PointProblems()
    valve_mass = points["equivalent_mass"] - SPRING_MASS_SHARE * points["spring_mass"]
    for i in np.flatnonzero(~(valve_mass > 0.0)):
        found.add(
            int(i),
            f"spring_mass = {points['spring_mass'][i]:g} kg with equivalent_mass = "
            f"{points['equivalent_mass'][i]:g} kg: the equivalent mass must exceed a third of "
            "the spring mass (it is valve + spring/3 + rocker inertia/lb² [V1])",
        )
    return found.messages()


def surge_stage(scene: SurgeHost, state: ValveState) -> None:
    """The ``surge`` stage: the multi-mass spring (once per study chunk) at ``angle_step``, and
    over ``revolutions`` turns when asked; under ``spring_model = "multi_mass"`` its outputs
    also answer the dynamic responses (it then runs in place of ``dynamics``)."""
    n, settings = state.n, state.settings
    chain_curves = set(CHAIN_CURVE_ROW) if uses_chain(settings) else set()
    want = not (chain_curves | SURGE_CURVE_NAMES).isdisjoint(state.curves)
    axis = scene.curve_coordinate(settings) if want else np.empty(0)
    state.chain_out = np.full((n, N_CHAIN_OUT), np.nan)
    state.chain_traces = np.full((n, N_CHAIN_CURVES, axis.size), np.nan)
    step = step_deg(settings["angle_step"])
    flags = kernel_settings(settings, "rk4", False)
    for key, idx in state.groups.items():
        if not scene.linkage_valid(state, key):
            state.chain_out[idx, sc.CO_STATUS] = STATUS_NOT_RUN
            continue
        rows = scene.spring_rows(state, idx)
        turns = int(settings["revolutions"])
        if turns == 1 or want or uses_chain(settings):  # else every answer is the steady run's
            out, trace = run_chain(scene.excitation(state, key, step), rows, flags, want)
            state.chain_out[idx] = out
            if trace is not None:
                first = round((scene.window(state, key)[0] + HALF_TURN_DEG) / step)
                state.chain_traces[idx, :, first : first + trace.shape[2]] = trace
        if turns > 1:
            turn = scene.excitation(state, key, step, (-HALF_TURN_DEG, HALF_TURN_DEG))
            steady = steady_surge(turn, rows, flags, turns)
            state.chain_out[np.ix_(idx, np.asarray(STEADY_COLUMNS))] = steady[:, STEADY_COLUMNS]
    if uses_chain(settings):
        state.out = np.full((n, N_OUT), np.nan)
        for column, chain_column in LUMPED_FROM_CHAIN.items():
            state.out[:, column] = state.chain_out[:, chain_column]
        state.step_used = np.full(n, step)
