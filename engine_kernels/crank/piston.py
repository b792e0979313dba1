"""Piston motion of the slider crank: exact [K1] and two-term [K2]–[K4] relations (physics §5).

Displacement x from TDC, velocity ẋ and acceleration ẍ at crank angle α, constant crank speed
ω. Conventions in :mod:`engine_kernels.crank.kinematics`.
"""

from __future__ import annotations

import math

from engine_kernels._jit import jit


@jit
def piston_displacement_exact(crank_radius, rod_ratio, crank_angle):
    """Exact piston displacement from TDC x = r(1 − cos α) + l(1 − cos β)  [K1].

    Written as x = r[(1 − cos α) + λ sin²α/(1 + cos β)], which needs no division by λ and keeps
    full precision as λ → 0.

    crank_radius: float  r [m].
    rod_ratio   : float  λ = r/l [-].
    crank_angle : float  α from TDC [rad].
    Reference: physics §5 [K1].
    """
    s = math.sin(crank_angle)
    cos_beta = math.sqrt(1.0 - (rod_ratio * s) ** 2)
    return crank_radius * ((1.0 - math.cos(crank_angle)) + rod_ratio * s * s / (1.0 + cos_beta))


@jit
def piston_velocity_exact(crank_radius, rod_ratio, angular_speed, crank_angle):
    """Exact piston velocity ẋ = rω[sin α + (λ/2) sin 2α / cos β] = rω sin(α + β)/cos β  [K1].

    crank_radius : float  r [m].
    rod_ratio    : float  λ = r/l [-].
    angular_speed: float  Crank speed ω [rad/s].
    crank_angle  : float  α from TDC [rad].
    Reference: physics §5 [K1], differentiated once in time at constant ω.
    """
    s = math.sin(crank_angle)
    cos_beta = math.sqrt(1.0 - (rod_ratio * s) ** 2)
    return (
        crank_radius
        * angular_speed
        * (s + 0.5 * rod_ratio * math.sin(2.0 * crank_angle) / cos_beta)
    )


@jit
def piston_acceleration_exact(crank_radius, rod_ratio, angular_speed, crank_angle):
    """Exact piston acceleration ẍ = rω²[cos α + λ cos 2α / cos β + λ³ sin²2α/(4 cos³β)]  [K1].

    crank_radius : float  r [m].
    rod_ratio    : float  λ = r/l [-].
    angular_speed: float  Crank speed ω [rad/s].
    crank_angle  : float  α from TDC [rad].
    Reference: physics §5 [K1], differentiated twice in time at constant ω.
    """
    s = math.sin(crank_angle)
    cos_beta = math.sqrt(1.0 - (rod_ratio * s) ** 2)
    s2 = math.sin(2.0 * crank_angle)
    return (
        crank_radius
        * angular_speed**2
        * (
            math.cos(crank_angle)
            + rod_ratio * math.cos(2.0 * crank_angle) / cos_beta
            + rod_ratio**3 * s2 * s2 / (4.0 * cos_beta**3)
        )
    )


@jit
def piston_displacement_two_term(crank_radius, rod_ratio, crank_angle):
    """Two-term piston displacement x = r[(1 − cos α) + (λ/4)(1 − cos 2α)]  [K2].

    crank_radius: float  r [m].
    rod_ratio   : float  λ = r/l [-].
    crank_angle : float  α from TDC [rad].
    Reference: physics §5 [K2].
    """
    return crank_radius * (
        (1.0 - math.cos(crank_angle)) + 0.25 * rod_ratio * (1.0 - math.cos(2.0 * crank_angle))
    )


@jit
def piston_velocity_two_term(crank_radius, rod_ratio, angular_speed, crank_angle):
    """Two-term piston velocity v = rω(sin α + (λ/2) sin 2α)  [K3].

    crank_radius : float  r [m].
    rod_ratio    : float  λ = r/l [-].
    angular_speed: float  Crank speed ω [rad/s].
    crank_angle  : float  α from TDC [rad].
    Reference: physics §5 [K3].
    """
    return (
        crank_radius
        * angular_speed
        * (math.sin(crank_angle) + 0.5 * rod_ratio * math.sin(2.0 * crank_angle))
    )


@jit
def piston_acceleration_two_term(crank_radius, rod_ratio, angular_speed, crank_angle):
    """Two-term piston acceleration a = rω²(cos α + λ cos 2α)  [K4].

    crank_radius : float  r [m].
    rod_ratio    : float  λ = r/l [-].
    angular_speed: float  Crank speed ω [rad/s].
    crank_angle  : float  α from TDC [rad].
    Reference: physics §5 [K4].
    """
    return (
        crank_radius
        * angular_speed**2
        * (math.cos(crank_angle) + rod_ratio * math.cos(2.0 * crank_angle))
    )
