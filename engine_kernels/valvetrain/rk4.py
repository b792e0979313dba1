"""Fixed-step classic Runge–Kutta helpers: stability bound, sub-step count, dense output.

The valve kernels step a piecewise-linear oscillator with classic RK4 (physics §4). Explicit RK4
is stable while ``|h λ|`` stays inside its stability region for every eigenvalue ``λ`` of the
active linear system. The region reaches 2√2 = 2.828 on the imaginary axis (undamped modes)
and 2.785 on the negative real axis (heavily over-damped modes), but between the two it dips:
its smallest radius over all left-half-plane directions is 2.6198, at about 123° (damping
ratio ≈ 0.54). ``RK4_STABILITY_BOUND = 2.6`` is therefore safe whatever the damping.

The cubic Hermite helpers are the dense output used to interpolate excitation tables and
switching functions between grid points.
"""

from __future__ import annotations

import math

from engine_kernels._jit import jit

RK4_STABILITY_BOUND = 2.6
RK4_IMAGINARY_AXIS_LIMIT = 2.0 * math.sqrt(2.0)
RK4_REAL_AXIS_LIMIT = 2.785293563405282
MAX_SUBSTEPS = 2**62  # the count stable_substeps returns when no integer would do (int64)


@jit
def rk4_amplification(z_real, z_imag):
    """Modulus of the RK4 amplification factor ``|1 + z + z²/2 + z³/6 + z⁴/24|``.

    z_real : float  Real part of ``h λ`` [-].
    z_imag : float  Imaginary part of ``h λ`` [-].

    Reference: Hairer & Wanner, *Solving ODEs II*, §IV.2 (stability function of RK4).
    """
    z = complex(z_real, z_imag)
    return abs(1.0 + z * (1.0 + z * (0.5 + z * (1.0 / 6.0 + z / 24.0))))


@jit
def oscillator_spectral_radius(mass, damping, stiffness):
    """Largest eigenvalue modulus ``max |λ|`` of ``M λ² + c λ + K = 0``.

    Under-damped modes have ``|λ| = sqrt(K/M)``; over-damped ones a fast real eigenvalue
    ``(c + sqrt(c² − 4MK))/(2M)``, larger than the natural frequency (physics §4, stability).

    mass      : float  Mass M [kg], > 0.
    damping   : float  Viscous damping c [N s/m], ≥ 0.
    stiffness : float  Stiffness K [N/m], ≥ 0.
    """
    discriminant = damping * damping - 4.0 * mass * stiffness
    if discriminant < 0.0:
        return math.sqrt(stiffness / mass)
    return (damping + math.sqrt(discriminant)) / (2.0 * mass)


@jit
def stable_substeps(step, spectral_radius, bound):
    """Smallest number of equal sub-steps that keeps ``step/n · spectral_radius ≤ bound``.

    step            : float  Full step h [s].
    spectral_radius : float  Largest eigenvalue modulus of the active linear systems [1/s].
    bound           : float  Allowed ``|h λ|`` [-], e.g. ``RK4_STABILITY_BOUND``.
    """
    ratio = step * spectral_radius / bound
    if ratio <= 1.0:
        return 1
    if not ratio < MAX_SUBSTEPS:  # a near-zero speed or a NaN: more than any limit allows
        return MAX_SUBSTEPS
    return math.ceil(ratio)


@jit
def hermite_value(y0, slope0, y1, slope1, width, s):
    """Cubic Hermite interpolant between two points, evaluated at fraction ``s`` of the span.

    y0, y1         : float  End values [any unit u].
    slope0, slope1 : float  End slopes dy/dx [u per unit of x].
    width          : float  Span x1 − x0 [unit of x].
    s              : float  Position (x − x0)/width, normally in [0, 1] [-].

    Reference: de Boor, *A Practical Guide to Splines*, ch. IV (cubic Hermite basis).
    """
    s2 = s * s
    s3 = s2 * s
    h00 = 2.0 * s3 - 3.0 * s2 + 1.0
    h10 = s3 - 2.0 * s2 + s
    h01 = -2.0 * s3 + 3.0 * s2
    h11 = s3 - s2
    return h00 * y0 + h10 * width * slope0 + h01 * y1 + h11 * width * slope1


@jit
def hermite_slope(y0, slope0, y1, slope1, width, s):
    """Derivative dy/dx of the cubic Hermite interpolant of :func:`hermite_value`.

    Same arguments as :func:`hermite_value`; returns [u per unit of x].
    """
    s2 = s * s
    d00 = 6.0 * s2 - 6.0 * s
    d10 = 3.0 * s2 - 4.0 * s + 1.0
    d11 = 3.0 * s2 - 2.0 * s
    return (d00 * (y0 - y1)) / width + d10 * slope0 + d11 * slope1
