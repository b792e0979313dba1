"""Reed (check) valve natural frequencies and resonance margins: the ``reed`` scene (physics §6).

The reed is a uniform clamped–free Euler–Bernoulli beam (no damping, no torsion). Its modes are
the roots X_n = k_n l of cos X cosh X = −1 [B1], solved as cos X + 1/cosh X = 0 so no term
overflows for high modes; the root X_n lies in ((n − 1)π, nπ) and tends to (n − ½)π.

The engine excites the reed at f_e = ω e/(2π), e openings per crank revolution (e = ½ for a
four-stroke, 1 for a two-stroke), i.e. n/120 Hz for a four-stroke at n rpm; the band is
[f_e(ω_min), f_e(ω_max)]. Harmonic k of the (non-sinusoidal) intake pulse covers
[k f_min, k f_max]; the lowest harmonic that reaches f_1 is k = ⌈f_1/f_max⌉ (when
k f_min ≤ f_1), at engine speed ω = 2π f_1/(k e).

Orders are reported as **engine orders** o = k·e, multiples of the crankshaft frequency as in
the crank scene's torque harmonics (physics §5, §6): the 3rd harmonic of a four-stroke's event
frequency is engine order 1.5, and order o meets frequency f at n = 60 f/o rpm.

Reference: Blevins, *Formulas for Dynamics, Acoustics and Vibration* (2016), Table 4.2
(clamped–free beam); physics §6.
"""

from __future__ import annotations

import math

import numpy as np

from engine_kernels._jit import batch, jit, prange

ROOT_STEPS = 100
"""Iteration cap of the safeguarded Newton solve (it converges in fewer than 10)."""
ROOT_TOLERANCE = 4.0e-16
"""Relative step size at which the root solve stops."""

# Columns of params[n, N_PARAMS] (SI units).
LENGTH = 0  # free length l [m]
WIDTH = 1  # b [m]
THICKNESS = 2  # h [m]
YOUNGS_MODULUS = 3  # E [Pa]
DENSITY = 4  # ρ [kg/m³]
SPEED_MIN = 5  # lowest engine speed ω_min [rad/s]
SPEED_MAX = 6  # highest engine speed ω_max [rad/s]
OPENINGS_PER_REVOLUTION = 7  # e [-]: 0.5 four-stroke, 1 two-stroke
N_PARAMS = 8
PARAM_NAMES = (
    "length",
    "width",
    "thickness",
    "youngs_modulus",
    "density",
    "speed_min",
    "speed_max",
    "openings_per_revolution",
)

# Columns of out[n, N_OUT].
OUT_FIRST_FREQUENCY = 0
OUT_BAND_MIN = 1
OUT_BAND_MAX = 2
OUT_FIRST_MARGIN = 3
OUT_FIRST_MARGIN_RATIO = 4
OUT_HARMONIC_ORDER = 5
OUT_RESONANCE_SPEED = 6
OUT_TIP_STIFFNESS = 7
OUT_MASS = 8
N_OUT = 9
OUTPUTS = (
    "first_frequency",
    "band_min",
    "band_max",
    "first_margin",
    "first_margin_ratio",
    "harmonic_order",
    "resonance_speed",
    "tip_stiffness",
    "mass",
)
OUTPUT_UNITS = ("Hz", "Hz", "Hz", "Hz", "-", "-", "rad/s", "N/m", "kg")
HARMONIC_SLACK = 1e-9
"""Relative slack when counting the harmonics k with k·e ≤ max_order (0.5·3 must count as 1.5)."""

# Rows of modes_out[n, N_MODE_OUT, n_modes].
MODE_FREQUENCY = 0
MODE_MARGIN = 1
MODE_MARGIN_RATIO = 2
N_MODE_OUT = 3
MODE_OUTPUTS = ("frequency", "margin", "margin_ratio")
MODE_OUTPUT_UNITS = ("Hz", "Hz", "-")

# order_crossing columns
CROSSING_ORDER = 0  # lowest engine order k·e whose band holds f [-]
CROSSING_SPEED = 1  # engine speed of that crossing [rad/s]
ORDER_MARGIN = 2  # signed margin to the nearest order band [Hz]
ORDER_CLEAR = 3  # 1: outside every order band widened by the margin
N_ORDER_OUT = 4


@jit
def frequency_equation(x):
    """Overflow-safe clamped–free frequency function cos X + 1/cosh X  [B1].

    x: float  X = k l [-]. Zero exactly where cos X cosh X = −1. Reference: physics §6.
    """
    return math.cos(x) + 1.0 / math.cosh(x)


@jit
def cantilever_root(mode):
    """Root X_n of cos X cosh X = −1 in ((n − 1)π, nπ)  [B1].

    Newton's method from (n − ½)π, kept inside a shrinking sign-change bracket (bisection when
    a Newton step leaves it). For large n, 1/cosh X underflows and X_n = (n − ½)π to machine
    precision.

    mode: int  n ≥ 1.
    Reference: physics §6; Blevins (2016) Table 4.2.
    """
    lo = (mode - 1) * math.pi
    hi = mode * math.pi
    f_lo = frequency_equation(lo)
    x = (mode - 0.5) * math.pi
    for _ in range(ROOT_STEPS):
        f = frequency_equation(x)
        if f == 0.0:
            return x
        if (f > 0.0) == (f_lo > 0.0):
            lo = x
            f_lo = f
        else:
            hi = x
        slope = -math.sin(x) - math.tanh(x) / math.cosh(x)
        step = f / slope
        candidate = x - step
        if not lo < candidate < hi:
            candidate = 0.5 * (lo + hi)
            step = x - candidate
        x = candidate
        if abs(step) <= ROOT_TOLERANCE * x:
            break
    return x


@jit
def cantilever_roots(roots_out):
    """First len(roots_out) roots X_1, X_2, … of cos X cosh X = −1  [B1].

    roots_out: float[:]  Output.
    Reference: physics §6.
    """
    for n in range(roots_out.shape[0]):
        roots_out[n] = cantilever_root(n + 1)


@jit
def reed_natural_frequency(root, length, thickness, youngs_modulus, density):
    """Natural frequency f_n = X_n²/(2π l²) √(E I/(ρ A)), I/A = h²/12  [B2].

    The width cancels (I = b h³/12, A = b h).

    root          : float  X_n [-].
    length        : float  Free length l [m].
    thickness     : float  h [m].
    youngs_modulus: float  E [Pa].
    density       : float  ρ [kg/m³].
    Returns f_n [Hz]. Reference: physics §6 [B2].
    """
    return (
        root**2
        / (2.0 * math.pi * length**2)
        * math.sqrt(youngs_modulus * thickness**2 / (12.0 * density))
    )


@jit
def cantilever_mode_shape(root, position, derivative):
    """Clamped–free mode shape or its derivative, d^j w/dξ^j at ξ = x/l  (physics §6).

    w(ξ) = cosh Xξ − cos Xξ − σ (sinh Xξ − sin Xξ), σ = (cos X + cosh X)/(sin X + sinh X)
    (unnormalised; |w(1)| = 2), evaluated as
    ½(1 − σ)e^z + ½(1 + σ)e^(−z) − cos z + σ sin z with z = Xξ and 1 − σ, σ rewritten in
    e^(−X) so nothing overflows for high modes. w(0) = w'(0) = 0, w''(1) = w'''(1) = 0.

    root      : float  X_n [-].
    position  : float  ξ = x/l, 0 ≤ ξ ≤ 1 [-].
    derivative: int    j = 0…3 (order of the derivative in ξ).
    Reference: Blevins (2016) Table 4.2.
    """
    e = math.exp(-root)
    denominator = 2.0 * math.sin(root) * e + 1.0 - e * e
    sigma = (2.0 * math.cos(root) * e + 1.0 + e * e) / denominator
    z = root * position
    # (1 − σ) e^z with e^z/sinh-type growth cancelled analytically: z ≤ X keeps e^(z − X) ≤ 1.
    growing = (math.sin(root) - math.cos(root) - e) * 2.0 * math.exp(z - root) / denominator
    sign = 1.0 - 2.0 * (derivative % 2)
    shift = 0.5 * math.pi * derivative
    value = (
        0.5 * growing
        + 0.5 * sign * (1.0 + sigma) * math.exp(-z)
        - math.cos(z + shift)
        + sigma * math.sin(z + shift)
    )
    return value * root**derivative


@jit
def band_margin(frequency, band_min, band_max):
    """Signed distance of a natural frequency from the excitation band [Hz].

    Positive outside the band (distance to the nearest edge), negative inside (depth into the
    band, to the nearest edge).

    frequency: float  f [Hz].
    band_min : float  Lowest excitation frequency [Hz].
    band_max : float  Highest excitation frequency [Hz].
    Reference: physics §6 (margin to the band).
    """
    return max(frequency - band_max, band_min - frequency)


@jit
def order_crossing(frequency, band_min, band_max, openings, max_order, margin, out):
    """Engine orders against one natural frequency (physics §6, the intake pulse's harmonics).

    Harmonic k of the event frequency is engine order o = k·e; its excitation covers
    [k f_min, k f_max] over the speed range and crosses f at the engine speed ω = 2π f/(k e).
    Writes into ``out``: the lowest engine order o ≤ ``max_order`` whose band holds f (NaN if
    none), its crossing speed [rad/s] (NaN if none), the signed margin [Hz]: outside every band
    the distance to the nearest one (> 0), else the depth into the crossing order's band to its
    nearest edge (< 0); and 1 if f lies outside every band widened by ``margin``
    (k f_min (1 − m) … k f_max (1 + m)), else 0.

    frequency: float  f [Hz].
    band_min : float  f_min = ω_min e/(2π), the first harmonic's band, lower edge [Hz].
    band_max : float  f_max [Hz].
    openings : float  Excitation events (reed openings) per crank revolution e [-].
    max_order: float  Highest engine order checked (harmonics k with k·e ≤ max_order) [-].
    margin   : float  Relative margin m of the resonance-free check [-].
    out      : float[4]
    """
    out[CROSSING_ORDER] = math.nan
    out[CROSSING_SPEED] = math.nan
    nearest = math.inf
    clear = 1.0
    harmonics = math.floor(max_order / openings * (1.0 + HARMONIC_SLACK))
    for k in range(1, harmonics + 1):
        low, high = k * band_min, k * band_max
        if math.isnan(out[CROSSING_ORDER]) and low <= frequency <= high:
            out[CROSSING_ORDER] = k * openings
            out[CROSSING_SPEED] = 2.0 * math.pi * frequency / (k * openings)
            nearest = band_margin(frequency, low, high)
        elif math.isnan(out[CROSSING_ORDER]):
            nearest = min(nearest, band_margin(frequency, low, high))
        if low * (1.0 - margin) <= frequency <= high * (1.0 + margin):
            clear = 0.0
    out[ORDER_MARGIN] = nearest
    out[ORDER_CLEAR] = clear


@batch
def order_batch(frequencies, params, max_order, margin, out):
    """:func:`order_crossing` of every case and mode.

    frequencies: float[n, q]     Natural frequencies of modes 1…q [Hz].
    params     : float[n, N_PARAMS]
    max_order  : float           Highest engine order checked [-].
    margin     : float           Relative margin of the resonance-free check [-].
    out        : float[n, q, 4]  Columns CROSSING_ORDER (engine order), CROSSING_SPEED [rad/s],
                                 ORDER_MARGIN [Hz], ORDER_CLEAR.
    Reference: physics §6.
    """
    for i in prange(frequencies.shape[0]):
        openings = params[i, OPENINGS_PER_REVOLUTION]
        band_min = params[i, SPEED_MIN] * openings / (2.0 * math.pi)
        band_max = params[i, SPEED_MAX] * openings / (2.0 * math.pi)
        for q in range(frequencies.shape[1]):
            order_crossing(
                frequencies[i, q], band_min, band_max, openings, max_order, margin, out[i, q]
            )


@batch
def reed_batch(params, out, modes_out, shapes_out):
    """Natural frequencies, band margins, resonant harmonic and mode shapes of every case.

    params    : float[n, N_PARAMS]        Case parameters (columns of this module).
    out       : float[n, N_OUT]           Scalars, columns OUT_* (names OUTPUTS); the harmonic
                                          order is the engine order k·e of the lowest harmonic
                                          reaching f_1; it and the resonance speed are NaN when
                                          no harmonic band reaches f_1 (f_1 below k f_min).
    modes_out : float[n, N_MODE_OUT, q]   Frequency, margin [Hz] and margin/frequency of modes
                                          1…q (q may be 0).
    shapes_out: float[n, s, g]            Mode shapes 1…s on ξ_j = j/(g − 1), normalised to a
                                          unit tip deflection; g = 0 skips them.
    Reference: physics §6 [B1], [B2].
    """
    n_modes = max(modes_out.shape[2], shapes_out.shape[1], 1)
    roots = np.empty(n_modes)
    cantilever_roots(roots)
    g = shapes_out.shape[2]
    for i in prange(params.shape[0]):
        length = params[i, LENGTH]
        thickness = params[i, THICKNESS]
        modulus = params[i, YOUNGS_MODULUS]
        density = params[i, DENSITY]
        openings = params[i, OPENINGS_PER_REVOLUTION]
        band_min = params[i, SPEED_MIN] * openings / (2.0 * math.pi)
        band_max = params[i, SPEED_MAX] * openings / (2.0 * math.pi)
        f1 = reed_natural_frequency(roots[0], length, thickness, modulus, density)
        order = math.ceil(f1 / band_max)
        reachable = order * band_min <= f1
        margin = band_margin(f1, band_min, band_max)
        out[i, OUT_FIRST_FREQUENCY] = f1
        out[i, OUT_BAND_MIN] = band_min
        out[i, OUT_BAND_MAX] = band_max
        out[i, OUT_FIRST_MARGIN] = margin
        out[i, OUT_FIRST_MARGIN_RATIO] = margin / f1
        out[i, OUT_HARMONIC_ORDER] = order * openings if reachable else math.nan
        out[i, OUT_RESONANCE_SPEED] = (
            2.0 * math.pi * f1 / (order * openings) if reachable else math.nan
        )
        inertia = params[i, WIDTH] * thickness**3 / 12.0
        out[i, OUT_TIP_STIFFNESS] = 3.0 * modulus * inertia / length**3
        out[i, OUT_MASS] = density * params[i, WIDTH] * thickness * length
        for q in range(modes_out.shape[2]):
            f = reed_natural_frequency(roots[q], length, thickness, modulus, density)
            margin_q = band_margin(f, band_min, band_max)
            modes_out[i, MODE_FREQUENCY, q] = f
            modes_out[i, MODE_MARGIN, q] = margin_q
            modes_out[i, MODE_MARGIN_RATIO, q] = margin_q / f
        if g > 0:
            for s in range(shapes_out.shape[1]):
                tip = cantilever_mode_shape(roots[s], 1.0, 0)
                for j in range(g):
                    position = j / (g - 1) if g > 1 else 1.0
                    shapes_out[i, s, j] = cantilever_mode_shape(roots[s], position, 0) / tip
