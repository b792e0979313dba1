"""Example scene plugin: a damped, harmonically driven single-degree-of-freedom oscillator.

    m x'' + c x' + k x = F0 sin(ω t),   c = 2 ζ √(k m),   from rest at t = 0

The scene integrates the motion (classic RK4, a whole number of steps per drive period) until
the free vibration has decayed below 1e-11 of its start, then takes the steady amplitude and
phase lag from the first Fourier coefficient of the last drive period. It is what a user's own
mechanism looks like to the study engine: declarations, one stage, ``evaluate``; its package
registers it through the entry point group ``engine_studies.scenes`` (see pyproject.toml).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from studies.scenes import Parameter, Response, Scene, SceneOutput

STEPS_PER_PERIOD = 200  # RK4 steps per period of the faster of drive and natural frequency
DECAY = 25.0  # integrate until exp(-ζ ωn t) < exp(-DECAY)
NEEDS = ("response",)


class OscillatorScene(Scene):
    """A damped, harmonically driven oscillator (steady amplitude and phase lag)."""

    name = "oscillator"
    description = "damped driven oscillator: steady amplitude and phase lag (example plugin)"
    parameters = (
        Parameter("mass", "kg", 1.0, "oscillating mass m", 0.0, None, True),
        Parameter("stiffness", "N/m", 4000.0, "spring rate k", 0.0, None, True),
        Parameter("damping_ratio", "1", 0.1, "damping ratio ζ", 0.01, 2.0),
        Parameter("force_amplitude", "N", 10.0, "amplitude F0 of the driving force", 0.0),
        Parameter("drive_frequency", "Hz", 10.0, "drive frequency f", 0.0, None, True),
    )
    responses = (
        Response("amplitude", "mm", "steady amplitude of x", NEEDS),
        Response("phase_lag", "degree", "phase lag of x behind the force", NEEDS),
        Response("natural_frequency", "Hz", "undamped natural frequency √(k/m)/2π", NEEDS),
    )
    stage_order = NEEDS

    def stage_response(self, points: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
        """Integrate every design point at once (each with its own step) to steady state."""
        m, k = points["mass"], points["stiffness"]
        zeta, f0 = points["damping_ratio"], points["force_amplitude"]
        omega = 2.0 * math.pi * points["drive_frequency"]
        omega_n = np.sqrt(k / m)
        c = 2.0 * zeta * np.sqrt(k * m)
        per_period = STEPS_PER_PERIOD * np.maximum(1, np.ceil(omega_n / omega)).astype(np.int64)
        periods = np.ceil(DECAY / (zeta * omega_n) * omega / (2.0 * math.pi)).astype(np.int64) + 1
        total = per_period * periods
        dt = 2.0 * math.pi / omega / per_period
        x, v = np.zeros_like(m), np.zeros_like(m)
        sin_sum, cos_sum = np.zeros_like(m), np.zeros_like(m)

        def acceleration(t: np.ndarray, x: np.ndarray, v: np.ndarray) -> np.ndarray:
            return (f0 * np.sin(omega * t) - c * v - k * x) / m

        for step in range(int(total.max())):
            live = step < total
            t = step * dt
            last = live & (step >= total - per_period)  # the last drive period
            sin_sum += np.where(last, x * np.sin(omega * t), 0.0)
            cos_sum += np.where(last, x * np.cos(omega * t), 0.0)
            k1x, k1v = v, acceleration(t, x, v)
            k2x, k2v = (
                v + 0.5 * dt * k1v,
                acceleration(t + 0.5 * dt, x + 0.5 * dt * k1x, v + 0.5 * dt * k1v),
            )
            k3x, k3v = (
                v + 0.5 * dt * k2v,
                acceleration(t + 0.5 * dt, x + 0.5 * dt * k2x, v + 0.5 * dt * k2v),
            )
            k4x, k4v = v + dt * k3v, acceleration(t + dt, x + dt * k3x, v + dt * k3v)
            x = np.where(live, x + dt / 6.0 * (k1x + 2 * k2x + 2 * k3x + k4x), x)
            v = np.where(live, v + dt / 6.0 * (k1v + 2 * k2v + 2 * k3v + k4v), v)
        a, b = 2.0 * sin_sum / per_period, 2.0 * cos_sum / per_period  # x ≈ a sin ωt + b cos ωt
        return {
            "amplitude": np.hypot(a, b) * 1e3,
            "phase_lag": np.degrees(np.arctan2(-b, a)),
            "natural_frequency": omega_n / (2.0 * math.pi),
        }

    def evaluate(
        self,
        points: dict[str, np.ndarray],
        settings: dict[str, Any],
        responses: list[str],
        curves: list[str],
    ) -> SceneOutput:
        values = self.stages["response"](points)
        return SceneOutput(scalars={r: values[r] for r in responses})
