"""Normalised rise laws of a cam follower with exact derivatives up to jerk (physics §2).

A rise law is f(x) on x ∈ [0, 1] with f(0) = 0, f(1) = 1. A rise over the cam angle β [rad]
of height H [m] gives h = H f, h' = H f1/β, h'' = H f2/β², h''' = H f3/β³ (derivatives per rad
of cam angle), so the acceleration factor of a law is Ca = max|f2| (physics.md: a = Ca·H ω²/β²).

The piecewise laws (modified sine, modified trapezoid) follow Norton, *Cam Design and
Manufacturing Handbook*, 2nd ed. (double-dwell functions); their peak factors come out in
closed form, Ca = 4π²/(π + 4) ≈ 5.528 and Ca = 8π/(π + 2) ≈ 4.888. Both laws are
point-symmetric about x = 1/2, f(1 - x) = 1 - f(x), so only the first half is written out.

The polydyne law is a user polynomial f = Σ c_k x^k, k < NCOEF. For a usable rise it needs
c0 = 0 and Σ c_k = 1 (end lifts), c1 = 0 and Σ k c_k = 0 (zero end velocities), and for a
smooth rise-return cam also c2 = 0, Σ k(k-1) c_k = 0 (zero end accelerations) and, for a
finite jerk at the nose, Σ k(k-1)(k-2) c_k = 0. The kernels evaluate whatever is given;
checking these conditions belongs to the study definition.
"""

from __future__ import annotations

import math

import numpy as np

from engine_kernels._jit import jit

LAW_CYCLOIDAL = 0
LAW_HARMONIC = 1
LAW_MODIFIED_SINE = 2
LAW_MODIFIED_TRAPEZOID = 3
LAW_POLY345 = 4
LAW_POLY4567 = 5
LAW_POLYDYNE = 6
LAW_SIX_SEGMENT = 7
"""Not a rise law: the multi-segment acceleration profile of ``multi_segment`` (physics §2)."""

N_RISE_LAWS = 7
"""Rise-law codes are 0 … N_RISE_LAWS - 1."""

NCOEF = 16
"""Number of polydyne coefficients c0 … c15."""

MODIFIED_SINE_PEAK = 4.0 * math.pi**2 / (math.pi + 4.0)
MODIFIED_TRAPEZOID_PEAK = 8.0 * math.pi / (math.pi + 2.0)

_PI = math.pi
_QUARTER_OMEGA = 4.0 * math.pi
"""Angular frequency of the quarter-sine flanks, which span x ∈ [0, 1/8]."""


@jit
def _modified_sine_half(x):
    """Modified sine (Norton) on x ∈ [0, 1/2]: quarter sine to the peak at 1/8, then a
    sine of three times the period down to zero acceleration at 1/2."""
    c = MODIFIED_SINE_PEAK
    k0 = _QUARTER_OMEGA
    if x <= 0.125:
        s, co = math.sin(k0 * x), math.cos(k0 * x)
        return c / k0 * (x - s / k0), c / k0 * (1.0 - co), c * s, c * k0 * co
    k = k0 / 3.0
    u = x - 0.125
    v1 = c / k0
    s1 = v1 * (0.125 - 1.0 / k0)
    s, co = math.sin(k * u), math.cos(k * u)
    return s1 + v1 * u + c / (k * k) * (1.0 - co), v1 + c / k * s, c * co, -c * k * s


@jit
def _modified_trapezoid_half(x):
    """Modified trapezoid (Norton) on x ∈ [0, 1/2]: quarter sine up to 1/8, constant
    acceleration to 3/8, quarter cosine down to zero at 1/2."""
    c = MODIFIED_TRAPEZOID_PEAK
    k0 = _QUARTER_OMEGA
    v1 = c / k0
    s1 = v1 * (0.125 - 1.0 / k0)
    if x <= 0.125:
        s, co = math.sin(k0 * x), math.cos(k0 * x)
        return c / k0 * (x - s / k0), c / k0 * (1.0 - co), c * s, c * k0 * co
    if x <= 0.375:
        u = x - 0.125
        return s1 + v1 * u + 0.5 * c * u * u, v1 + c * u, c, 0.0
    u = x - 0.375
    v2 = v1 + 0.25 * c
    s2 = s1 + 0.25 * v1 + c / 32.0
    s, co = math.sin(k0 * u), math.cos(k0 * u)
    return s2 + v2 * u + c / (k0 * k0) * (1.0 - co), v2 + c / k0 * s, c * co, -c * k0 * s


@jit
def _point_symmetric(half, x):
    """Extend a law given on x <= 1/2 to [0, 1] by f(1 - x) = 1 - f(x) (``half`` evaluated at
    min(x, 1 - x))."""
    f, f1, f2, f3 = half
    if x > 0.5:
        return 1.0 - f, f1, -f2, f3
    return f, f1, f2, f3


@jit
def _polynomial(x, coeffs):
    """Σ c_k x^k and its first three derivatives by Horner's scheme."""
    f = 0.0
    f1 = 0.0
    f2 = 0.0
    f3 = 0.0
    for k in range(coeffs.shape[0] - 1, -1, -1):
        f3 = f3 * x + 3.0 * f2
        f2 = f2 * x + 2.0 * f1
        f1 = f1 * x + f
        f = f * x + coeffs[k]
    return f, f1, f2, f3


@jit
def rise_law(law, x, coeffs):
    """Normalised rise f(x) and its exact derivatives f1, f2, f3 with respect to x (physics §2).

    law   : int    Law code, LAW_CYCLOIDAL … LAW_POLYDYNE.
    x     : float  Normalised cam angle, 0 at the start and 1 at the end of the rise [-].
    coeffs: array  Polydyne coefficients c0 … c_{NCOEF-1} of f = Σ c_k x^k [-]; read only by
                   LAW_POLYDYNE.

    Returns (f, f1, f2, f3) [-]; all NaN for a code that is not a rise law. Defined for
    x ∈ [0, 1]; outside it the closed forms are simply continued.
    Reference: Norton, *Cam Design and Manufacturing Handbook*, 2nd ed. (double-dwell
    functions).
    """
    if law == LAW_CYCLOIDAL:
        w = 2.0 * _PI
        s, c = math.sin(w * x), math.cos(w * x)
        return x - s / w, 1.0 - c, w * s, w * w * c
    if law == LAW_HARMONIC:
        s, c = math.sin(_PI * x), math.cos(_PI * x)
        return 0.5 * (1.0 - c), 0.5 * _PI * s, 0.5 * _PI**2 * c, -0.5 * _PI**3 * s
    if law == LAW_MODIFIED_SINE:
        return _point_symmetric(_modified_sine_half(min(x, 1.0 - x)), x)
    if law == LAW_MODIFIED_TRAPEZOID:
        return _point_symmetric(_modified_trapezoid_half(min(x, 1.0 - x)), x)
    if law == LAW_POLY345:
        x2 = x * x
        return (
            x2 * x * (10.0 - 15.0 * x + 6.0 * x2),
            30.0 * x2 * (1.0 - 2.0 * x + x2),
            60.0 * x * (1.0 - 3.0 * x + 2.0 * x2),
            60.0 - 360.0 * x + 360.0 * x2,
        )
    if law == LAW_POLY4567:
        x2 = x * x
        x3 = x2 * x
        return (
            x2 * x2 * (35.0 - 84.0 * x + 70.0 * x2 - 20.0 * x3),
            x3 * (140.0 - 420.0 * x + 420.0 * x2 - 140.0 * x3),
            x2 * (420.0 - 1680.0 * x + 2100.0 * x2 - 840.0 * x3),
            x * (840.0 - 5040.0 * x + 8400.0 * x2 - 4200.0 * x3),
        )
    if law == LAW_POLYDYNE:
        return _polynomial(x, coeffs)
    return np.nan, np.nan, np.nan, np.nan


@jit
def rise_return_lift(law, theta, lift, rise_angle, coeffs):
    """Lift h and derivatives h', h'', h''' of a symmetric rise-return cam at one angle.

    The rise spans θ ∈ [-β, 0] with x = (θ + β)/β, the nose is at θ = 0 and the fall is the
    mirror image (h even, h' odd, h'' even, h''' odd); base circle (all zero) for |θ| > β.

    law       : int    Rise-law code, LAW_CYCLOIDAL … LAW_POLYDYNE.
    theta     : float  Cam angle from the nose [rad].
    lift      : float  Rise H [m].
    rise_angle: float  Rise duration β > 0 [rad].
    coeffs    : array  Polydyne coefficients [-] (see ``rise_law``).

    Returns (h [m], h' [m/rad], h'' [m/rad²], h''' [m/rad³]).
    """
    t = -abs(theta)
    if t < -rise_angle:
        return 0.0, 0.0, 0.0, 0.0
    f, f1, f2, f3 = rise_law(law, (t + rise_angle) / rise_angle, coeffs)
    sign = 1.0 if theta <= 0.0 else -1.0
    b = rise_angle
    return lift * f, sign * lift * f1 / b, lift * f2 / (b * b), sign * lift * f3 / (b * b * b)


@jit
def rise_return_cam(law, lift, rise_angle, coeffs, theta, out):
    """Fill ``out[4, m]`` with h, h', h'', h''' of a rise-return cam on the grid ``theta``.

    law       : int    Rise-law code, LAW_CYCLOIDAL … LAW_POLYDYNE.
    lift      : float  Rise H [m].
    rise_angle: float  Rise duration β > 0 [rad] (half the event).
    coeffs    : array  Polydyne coefficients [-] (see ``rise_law``).
    theta     : array  Cam angles from the nose, shape (m,) [rad].
    out       : array  Output, shape (4, m): h [m], h' [m/rad], h'' [m/rad²], h''' [m/rad³].
    """
    for j in range(theta.shape[0]):
        h, h1, h2, h3 = rise_return_lift(law, theta[j], lift, rise_angle, coeffs)
        out[0, j] = h
        out[1, j] = h1
        out[2, j] = h2
        out[3, j] = h3
