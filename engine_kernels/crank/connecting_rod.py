"""Connecting-rod motion of the slider crank: angle, angular velocity, acceleration (physics §5).

Rod angle β from sin β = λ sin α [K1], its rates at constant crank speed ω and their extremes
over a revolution. Conventions in :mod:`engine_kernels.crank.kinematics`.
"""

from __future__ import annotations

import math

from engine_kernels._jit import jit


@jit
def rod_angle(rod_ratio, crank_angle):
    """Connecting-rod angle β from sin β = λ sin α  [K1].

    rod_ratio  : float  λ = r/l [-].
    crank_angle: float  Crank angle α from TDC [rad].
    Reference: physics §5 [K1].
    """
    return math.asin(rod_ratio * math.sin(crank_angle))


@jit
def rod_angular_velocity(rod_ratio, angular_speed, crank_angle):
    """Rod angular velocity β̇ = λω cos α / cos β  [K1].

    rod_ratio    : float  λ = r/l [-].
    angular_speed: float  Crank speed ω [rad/s].
    crank_angle  : float  α from TDC [rad].
    Reference: physics §5.
    """
    s = math.sin(crank_angle)
    return rod_ratio * angular_speed * math.cos(crank_angle) / math.sqrt(1.0 - (rod_ratio * s) ** 2)


@jit
def rod_angular_acceleration(rod_ratio, angular_speed, crank_angle):
    """Rod angular acceleration β̈ = −λ(1 − λ²) ω² sin α / cos³β  [K1].

    rod_ratio    : float  λ = r/l [-].
    angular_speed: float  Crank speed ω [rad/s].
    crank_angle  : float  α from TDC [rad].
    Reference: physics §5 (exact, constant ω).
    """
    s = math.sin(crank_angle)
    cos_beta = math.sqrt(1.0 - (rod_ratio * s) ** 2)
    return -rod_ratio * (1.0 - rod_ratio**2) * angular_speed**2 * s / cos_beta**3


@jit
def rod_angle_max(rod_ratio):
    """Largest rod angle β_max = asin λ, at α = 90° (and −β_max at 270°).

    rod_ratio: float  λ = r/l [-]. Reference: physics §5.
    """
    return math.asin(rod_ratio)


@jit
def rod_angular_velocity_max(rod_ratio, angular_speed):
    """Largest rod angular velocity λω, at α = 0° (and −λω at 180°).

    rod_ratio    : float  λ = r/l [-].
    angular_speed: float  Crank speed ω [rad/s].
    Reference: physics §5.
    """
    return rod_ratio * angular_speed


@jit
def rod_angular_acceleration_max(rod_ratio, angular_speed):
    """Largest rod angular acceleration magnitude λω²/√(1 − λ²), at α = 90° and 270°.

    |β̈| = λ(1 − λ²)ω² sin α/(1 − λ² sin²α)^{3/2} grows with sin α, so it peaks at sin α = ±1.

    rod_ratio    : float  λ = r/l [-].
    angular_speed: float  Crank speed ω [rad/s].
    Reference: physics §5.
    """
    return rod_ratio * angular_speed**2 / math.sqrt(1.0 - rod_ratio**2)
