"""The run state of the ``valve`` scenes: what their stages leave beside the linkage's.

Arrays are per design point of the chunk (first axis ``n``); columns and rows are the kernels'
(``O_*`` of :mod:`engine_kernels.valvetrain`, ``CO_*``/``CC_*`` of the spring chain), SI.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from studies.scenes.linkage.scene import LinkageState


@dataclass(slots=True)
class ValveState(LinkageState):
    """Run state of a ``valve`` chunk."""

    out: np.ndarray = field(init=False)  # stage dynamics (or surge): outputs (n, N_OUT), O_*
    step_used: np.ndarray = field(init=False)  # RK4 step each point ran at [deg]
    method: np.ndarray = field(init=False)  # index in INTEGRATORS of what each point ran
    per_step: np.ndarray = field(init=False)  # dopri: lift tolerance per step of the run [m]
    traces: np.ndarray = field(init=False)  # valve curves (n, N_CURVES, curve axis or 0), C_*
    bars: dict[str, np.ndarray] = field(init=False)  # error bars, budgets [m]; tolerance_met
    chain_out: np.ndarray = field(init=False)  # stage surge: spring-chain outputs (n, CO_*)
    chain_traces: np.ndarray = field(init=False)  # spring-chain curves (n, CC_*, axis or 0)
    jump: np.ndarray = field(init=False)  # stage jump_speed: speed [rad/s], status (n, 2)


@dataclass(slots=True)
class CostState(ValveState):
    """Run state of the ``valve_accuracy`` and ``valve_spring_ladder`` chunks."""

    reference_error: np.ndarray = field(init=False)  # stage reference: max |lift error| [m]
    cost: np.ndarray = field(init=False)  # stage cost: median seconds per case [s]
    cost_iqr: np.ndarray = field(init=False)  # interquartile range of those timings [s]
