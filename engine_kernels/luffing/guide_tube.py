"""Guide tube of the luffing rig: a simply supported beam loaded at mid-span [L2] (physics §7).

Second moment of the tube section, mid-span deflection and end slope under the trolley load
and the tube's own weight. SI units throughout.
"""

from __future__ import annotations

import math

from engine_kernels._jit import jit


@jit
def tube_second_moment(outer_diameter, inner_diameter):
    """Second moment of area of a tube I = π(D⁴ − d⁴)/64 [m⁴].

    outer_diameter: float  D [m].
    inner_diameter: float  d [m].
    Reference: physics §7.
    """
    return math.pi * (outer_diameter**4 - inner_diameter**4) / 64.0


@jit
def tube_midspan_deflection(load, weight, span, modulus, second_moment):
    """Mid-span deflection of a simply supported tube, y = (F + G) l³/(48 E I)  [L2].

    load         : float  F [N].
    weight       : float  G [N] (treated as acting at mid-span, as in docs/physics.md).
    span         : float  l [m].
    modulus      : float  E [Pa].
    second_moment: float  I [m⁴].
    Reference: physics §7 [L2].
    """
    return (load + weight) * span**3 / (48.0 * modulus * second_moment)


@jit
def tube_end_slope(load, weight, span, modulus, second_moment):
    """End slope of a simply supported tube loaded at mid-span, θ = (F + G) l²/(16 E I)  [L2].

    load         : float  F [N].
    weight       : float  G [N].
    span         : float  l [m].
    modulus      : float  E [Pa].
    second_moment: float  I [m⁴].
    Reference: physics §7 [L2].
    """
    return (load + weight) * span**2 / (16.0 * modulus * second_moment)
