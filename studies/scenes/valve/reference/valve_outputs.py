"""The derived outputs of the valve model [V2] read off the scipy reference (physics §4).

The kernels report max lift, jump start, seating velocity and bounce height from their
observations (:mod:`engine_kernels.valvetrain.valve.observations`); these are the same quantities
of the continuous reference solution (:func:`~studies.scenes.valve.reference.valve_ivp.valve_reference`),
with the kernels' definitions: the seat phase is seated until the valve first rises above the
seat plane δ0 = Ps0/kz, open until it returns onto it with the cam at or past its nose
(first closure: the seating velocity is its speed there), and bouncing whenever it leaves the
seat after that (bounce height: the largest y − δ0 then); the jump starts where the valve is
off its seat with the drive force ≤ 0 before the first closure; max lift is the largest y.
Every mode switch of the reference is a located event (the phase and the separation change
only there), and maxima are located on the solver's dense output by a bounded scalar search
from the best of ``SAMPLES_PER_RAD`` samples per radian. Used by the tests that check the
error bars of those outputs; slow, never used in studies.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import minimize_scalar

from engine_kernels import valvetrain as valve
from studies.scenes.valve.reference.valve_ivp import ReferenceSolution, Segment

SAMPLES_PER_RAD = 4096.0
"""Dense-output samples per radian of cam that seed the search for a maximum (1/72°)."""
MIN_SAMPLES = 8
SEATED, OPEN, CLOSED, BOUNCING = 0, 1, 2, 3
"""Seat phases, as ``engine_kernels.valvetrain.valve.layout.PHASE_*``."""
MAX_ANGLE_TOLERANCE = 1e-12
"""Bracket width [rad] of the search for a maximum: the lift there is off by ~y''·1e-24 m."""


@dataclass(frozen=True)
class ReferenceOutputs:
    """Outputs of one reference run in SI units (angles [rad] absolute cam angles; NaN where
    the event does not happen, bounce height 0 without a bounce, as the kernels report)."""

    max_lift: float
    jump_start: float
    seating_velocity: float
    bounce_height: float


def _segment_maximum(segment: Segment) -> float:
    """Largest lift [m] of one segment on its dense output."""
    count = max(MIN_SAMPLES, math.ceil((segment.stop - segment.start) * SAMPLES_PER_RAD))
    theta = np.linspace(segment.start, segment.stop, count + 1)
    lift = segment.dense(theta)[0]
    best = int(np.argmax(lift))
    low, high = theta[max(best - 1, 0)], theta[min(best + 1, count)]
    found = minimize_scalar(
        lambda t: -float(segment.dense(t)[0]),
        bounds=(low, high),
        method="bounded",
        options={"xatol": MAX_ANGLE_TOLERANCE},
    )
    return max(float(lift[best]), -float(found.fun))


def reference_outputs(
    solution: ReferenceSolution, params: np.ndarray, nose: float
) -> ReferenceOutputs:
    """Max lift, jump start, seating velocity and bounce height of a reference solution.

    solution : the reference over the whole integration window (``valve_reference``).
    params   : parameter row (``engine_kernels.valvetrain.P_*``, SI units).
    nose     : cam angle [rad] of the nose, the first maximum of the excitation Y (the kernels
               take it from their table: :func:`engine_kernels.valvetrain.valve.observations.nose_position`).
    """
    depth = params[valve.P_PRELOAD] / params[valve.P_SEAT_STIFFNESS]
    phase = SEATED
    max_lift, bounce = -math.inf, 0.0
    jump_start, seating_velocity = math.nan, math.nan
    for segment in solution.segments:
        middle = 0.5 * (segment.start + segment.stop)
        # Every crossing of the seat plane is a located event, so y − δ0 keeps its sign
        # inside a segment.
        if float(segment.dense(middle)[0]) > depth:
            phase = BOUNCING if phase >= CLOSED else OPEN
            if phase == BOUNCING:
                bounce = max(bounce, _segment_maximum(segment) - depth)
            elif not segment.contact and math.isnan(jump_start):
                jump_start = segment.start
        elif phase >= CLOSED or (phase == OPEN and segment.start >= nose):
            if phase == OPEN:
                seating_velocity = abs(float(segment.dense(segment.start)[1]))
            phase = CLOSED
        else:
            phase = SEATED
        max_lift = max(max_lift, _segment_maximum(segment))
    return ReferenceOutputs(max_lift, jump_start, seating_velocity, bounce)
