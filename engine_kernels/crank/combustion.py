"""Parametric single-zone cylinder-pressure cycle for the ``crank`` scene (physics §5).

A four-stroke cycle on the crank-angle grid of :mod:`engine_kernels.crank.kinematics` (α_j = 4π j/m,
gas-exchange TDC at α = 0, firing TDC at α = 2π):

* intake stroke, 0 ≤ α < π: p = intake pressure p_a;
* closed cycle, π ≤ α ≤ 3π (inlet closes and exhaust opens at BDC): polytropic compression and
  expansion with exponent k and a Wiebe heat release, dp/dα = −k p V'/V + (k − 1) Q'/V. The
  equation is linear in p and integrates exactly to
  p V^k = p_a V_bdc^k + (k − 1) ∫ V^(k−1) dQ, so only the heat-release integral is numerical
  (3-point Gauss–Legendre over the burned fraction, :func:`heat_release_integral`);
* exhaust stroke, 3π < α < 4π: p = exhaust pressure p_ex (blow-down at BDC is instantaneous).

Heat input (documented choice): HEAT_INPUT_MODE = HEAT_MODE_ENERGY takes the heat released per
cycle Q [J]; HEAT_MODE_PEAK_PRESSURE takes a target peak pressure [Pa] and finds Q exactly:
p(α) = p_mot(α) + Q g(α) is linear in Q with g ≥ 0, so the largest Q whose peak does not
exceed the target is the least (p_target − p_mot)/g over g > 0 (NaN if the motoring pressure
alone exceeds the target): found on the grid, then located between the grid points either side
of the limiting one (Brent's method to ``LOCATE_TOLERANCE``), so Q, the work and the IMEP do not
depend on the grid (a combustion shorter than a grid step had them 25-31 % off at 1°). The
peak pressure and its angle are located the same way. The Wiebe law is normalised so the burned
fraction reaches exactly 1 at the end of combustion: x_b = (1 − exp(−a τ^(m+1)))/(1 − exp(−a)), τ = (α − α_s)/Δα.

References: Heywood, *Internal Combustion Engine Fundamentals* (2nd ed., 2018), §9.2
(single-zone heat-release analysis, Wiebe function); physics §5.
"""

from __future__ import annotations

import math

from engine_kernels._jit import batch, jit, prange
from engine_kernels.crank.kinematics import CYCLE_ANGLE
from engine_kernels.crank.piston import piston_displacement_exact

HEAT_MODE_ENERGY = 0
"""Heat input given as heat released per cycle [J]."""
HEAT_MODE_PEAK_PRESSURE = 1
"""Heat input found from a target peak cylinder pressure [Pa]."""

QUADRATURE_STEP = math.radians(0.25)
"""Sub-steps of the heat-release quadrature: at least one per this much crank angle [rad]..."""
QUADRATURE_STEPS_PER_BURN = 128
"""...and at least this many over the whole burn (0 to 1 of the burned fraction)."""
GRADED_LEVELS = 20
"""Halvings of the first and last quadrature step of a burn (:func:`_graded_piece`)."""
GAUSS_NODE = math.sqrt(0.6)
GAUSS_WEIGHT_OUTER = 5.0 / 9.0
GAUSS_WEIGHT_CENTRE = 8.0 / 9.0

# Columns of params[n, N_PARAMS] (SI units).
BORE = 0  # D [m]
CRANK_RADIUS = 1  # r [m]
ROD_RATIO = 2  # λ = r/l [-]
COMPRESSION_RATIO = 3  # ε = V_bdc/V_tdc [-]
INTAKE_PRESSURE = 4  # p_a, pressure at inlet closing (BDC) [Pa]
EXHAUST_PRESSURE = 5  # p_ex, pressure during the exhaust stroke [Pa]
POLYTROPIC_EXPONENT = 6  # k [-]
COMBUSTION_START = 7  # start of heat release after firing TDC [rad] (negative = before TDC)
COMBUSTION_DURATION = 8  # Δα [rad]
WIEBE_EFFICIENCY = 9  # a [-] (6.908 burns 99.9 % in the un-normalised law)
WIEBE_FORM = 10  # m [-]
HEAT_INPUT_MODE = 11  # HEAT_MODE_ENERGY or HEAT_MODE_PEAK_PRESSURE
HEAT_RELEASED = 12  # Q [J], used with HEAT_MODE_ENERGY
PEAK_PRESSURE_TARGET = 13  # [Pa], used with HEAT_MODE_PEAK_PRESSURE
N_PARAMS = 14
PARAM_NAMES = (
    "bore",
    "crank_radius",
    "rod_ratio",
    "compression_ratio",
    "intake_pressure",
    "exhaust_pressure",
    "polytropic_exponent",
    "combustion_start",
    "combustion_duration",
    "wiebe_efficiency",
    "wiebe_form",
    "heat_input_mode",
    "heat_released",
    "peak_pressure_target",
)

# Columns of out[n, N_OUT].
OUT_PEAK_PRESSURE = 0
OUT_PEAK_PRESSURE_ANGLE = 1
OUT_HEAT_RELEASED = 2
OUT_COMPRESSION_PRESSURE = 3
OUT_EXPANSION_END_PRESSURE = 4
OUT_CYCLE_WORK = 5
OUT_IMEP = 6
N_OUT = 7
OUTPUTS = (
    "peak_pressure",
    "peak_pressure_angle",
    "heat_released",
    "compression_pressure",
    "expansion_end_pressure",
    "cycle_work",
    "imep",
)
OUTPUT_UNITS = ("Pa", "rad", "J", "Pa", "Pa", "J", "Pa")


@jit
def cylinder_volume(bore, crank_radius, rod_ratio, compression_ratio, crank_angle):
    """Cylinder volume V = V_c + (π D²/4) x(α), V_c = V_d/(ε − 1), V_d = (π D²/4)·2r.

    bore             : float  D [m].
    crank_radius     : float  r [m].
    rod_ratio        : float  λ = r/l [-].
    compression_ratio: float  ε [-].
    crank_angle      : float  α from TDC [rad].
    Reference: physics §5 [K1] (exact displacement).
    """
    area = 0.25 * math.pi * bore * bore
    clearance = 2.0 * crank_radius * area / (compression_ratio - 1.0)
    return clearance + area * piston_displacement_exact(crank_radius, rod_ratio, crank_angle)


@jit
def wiebe_burned_fraction(angle_from_start, duration, efficiency, form):
    """Normalised Wiebe burned fraction x_b = (1 − e^(−a τ^(m+1)))/(1 − e^(−a)), τ = θ/Δθ.

    angle_from_start: float  Crank angle since start of combustion θ [rad].
    duration        : float  Combustion duration Δθ [rad].
    efficiency      : float  Wiebe a [-].
    form            : float  Wiebe m [-].
    Returns 0 before the start and 1 after the end. Reference: Heywood (2018) §9.2.
    """
    if angle_from_start <= 0.0:
        return 0.0
    if angle_from_start >= duration:
        return 1.0
    tau = angle_from_start / duration
    return math.expm1(-efficiency * tau ** (form + 1.0)) / math.expm1(-efficiency)


@jit
def wiebe_angle(fraction, duration, efficiency, form):
    """Crank angle since the start of combustion at which the normalised Wiebe law has burned
    ``fraction`` (the inverse of :func:`wiebe_burned_fraction`) [rad]."""
    # τ^(m+1) = −ln(1 − x_b (1 − e^(−a)))/a, its argument written as (1 − x_b) + x_b e^(−a)
    # above one half: exact at x_b = 1 however small e^(−a) is
    if fraction < 0.5:
        power = -math.log1p(fraction * math.expm1(-efficiency)) / efficiency
    else:
        power = -math.log((1.0 - fraction) + fraction * math.exp(-efficiency)) / efficiency
    return duration * min(1.0, power) ** (1.0 / (form + 1.0))


@jit
def _gauss_piece(row, start, x0, x1):
    """3-point Gauss–Legendre of V(α(x_b))^(k−1) over the burned fractions [x0, x1]."""
    duration, a, m = row[COMBUSTION_DURATION], row[WIEBE_EFFICIENCY], row[WIEBE_FORM]
    centre, half = 0.5 * (x0 + x1), 0.5 * (x1 - x0)
    total = 0.0
    for node, weight in (
        (-GAUSS_NODE, GAUSS_WEIGHT_OUTER),
        (0.0, GAUSS_WEIGHT_CENTRE),
        (GAUSS_NODE, GAUSS_WEIGHT_OUTER),
    ):
        angle = start + wiebe_angle(centre + half * node, duration, a, m)
        volume = cylinder_volume(
            row[BORE], row[CRANK_RADIUS], row[ROD_RATIO], row[COMPRESSION_RATIO], angle
        )
        total += half * weight * volume ** (row[POLYTROPIC_EXPONENT] - 1.0)
    return total


@jit
def _graded_piece(row, start, x0, x1, toward_end):
    """:func:`_gauss_piece` over [x0, x1] in pieces halving toward x1 (``toward_end``) or x0:
    at the start and the end of the burn α(x_b) has an infinite slope (α − α_s grows as
    x_b^(1/(m+1)); the end of a steep law as −ln(1 − x_b)), which equal pieces converge on
    slowly."""
    total = 0.0
    lo, hi = x0, x1
    for _ in range(GRADED_LEVELS):
        middle = 0.5 * (lo + hi)
        if toward_end:
            total += _gauss_piece(row, start, lo, middle)
            lo = middle
        else:
            total += _gauss_piece(row, start, middle, hi)
            hi = middle
    return total + _gauss_piece(row, start, lo, hi)


@jit
def heat_release_integral(row, lower, upper):
    """∫ V^(k−1) dx_b/dα dα over [lower, upper] ∩ combustion, per joule of heat input.

    Integrated over the burned fraction, ∫ V(α(x_b))^(k−1) dx_b (3-point Gauss–Legendre on
    equal steps of x_b, at least ``QUADRATURE_STEPS_PER_BURN`` per whole burn and one per
    ``QUADRATURE_STEP`` of crank angle; the steps at the start and end of the burn graded,
    :func:`_graded_piece`): the integrand stays smooth however steep the Wiebe law is (with
    0.25° steps in crank angle, a = 66, m = 8.85 burning in a fraction of a 0.89° combustion
    left the cycle work 31 % off at a 1° grid).

    row  : float[:]  One row of ``params``.
    lower: float     Lower crank angle [rad] (cycle angle, firing TDC at 2π).
    upper: float     Upper crank angle [rad].
    Returns the integral [m^(3(k−1))]. Reference: module docstring (closed-cycle solution).
    """
    start = 2.0 * math.pi + row[COMBUSTION_START]
    duration = row[COMBUSTION_DURATION]
    lo = max(lower, start)
    hi = min(upper, start + duration)
    if hi <= lo:
        return 0.0
    a, m = row[WIEBE_EFFICIENCY], row[WIEBE_FORM]
    x_lo = wiebe_burned_fraction(lo - start, duration, a, m)
    x_hi = wiebe_burned_fraction(hi - start, duration, a, m)
    steps = max(
        math.ceil((x_hi - x_lo) * QUADRATURE_STEPS_PER_BURN),
        math.ceil((hi - lo) / QUADRATURE_STEP),
    )
    h = (x_hi - x_lo) / steps
    total = 0.0
    for s in range(steps):
        x0 = x_lo + s * h
        x1 = x_hi if s == steps - 1 else x0 + h
        if s == 0 and lo == start:
            total += _graded_piece(row, start, x0, x1, False)
        elif s == steps - 1 and hi == start + duration:
            total += _graded_piece(row, start, x0, x1, True)
        else:
            total += _gauss_piece(row, start, x0, x1)
    return total


LOCATE_ITERATIONS = 100
"""A guard: Brent's method narrows two grid intervals to ``LOCATE_TOLERANCE`` in 10-30
evaluations."""
LOCATE_TOLERANCE = 1e-9
"""Width [rad] to which a peak (or the angle limiting the heat) is located."""
GOLDEN = (math.sqrt(5.0) - 1.0) / 2.0


@jit
def _objective(row, c0, heat, target, lo, integral_lo, angle):
    """What :func:`_located` minimises at ``angle``: with ``heat`` NaN the heat per joule of
    heat input ``(target·V^k − c0)/((k − 1) I)`` at which the pressure there is ``target``
    (+inf before any heat is released); else minus the pressure ``(c0 + (k − 1)·heat·I)/V^k``.
    I is the heat-release integral, ``integral_lo`` at the angle ``lo``."""
    k = row[POLYTROPIC_EXPONENT]
    v_k = (
        cylinder_volume(row[BORE], row[CRANK_RADIUS], row[ROD_RATIO], row[COMPRESSION_RATIO], angle)
        ** k
    )
    integral = integral_lo + heat_release_integral(row, lo, angle)
    if math.isnan(heat):
        return (target * v_k - c0) / ((k - 1.0) * integral) if integral > 0.0 else math.inf
    return -(c0 + (k - 1.0) * heat * integral) / v_k


@jit
def _located(row, c0, heat, target, lo, integral_lo, hi):
    """The least value of :func:`_objective` between the angles ``lo`` and ``hi`` and its
    angle, by Brent's bounded minimisation (golden section with parabolic steps, as
    ``scipy.optimize.fminbound``) to ``LOCATE_TOLERANCE``: the heat the target allows, or
    minus the peak pressure."""
    a, b = lo, hi
    x = w = v = a + (1.0 - GOLDEN) * (b - a)
    fx = fw = fv = _objective(row, c0, heat, target, lo, integral_lo, x)
    d = e = 0.0
    for _ in range(LOCATE_ITERATIONS):
        middle = 0.5 * (a + b)
        tol1 = LOCATE_TOLERANCE + 1e-12 * abs(x)
        tol2 = 2.0 * tol1
        if abs(x - middle) <= tol2 - 0.5 * (b - a):
            break
        golden = True
        if abs(e) > tol1:  # try a parabola through x, w, v
            r = (x - w) * (fx - fv)
            q = (x - v) * (fx - fw)
            p = (x - v) * q - (x - w) * r
            q = 2.0 * (q - r)
            if q > 0.0:
                p = -p
            q = abs(q)
            if abs(p) < abs(0.5 * q * e) and q * (a - x) < p < q * (b - x):
                e, d = d, p / q
                u = x + d
                if u - a < tol2 or b - u < tol2:
                    d = tol1 if x < middle else -tol1
                golden = False
        if golden:
            e = (a if x >= middle else b) - x
            d = (1.0 - GOLDEN) * e
        u = x + (d if abs(d) >= tol1 else (tol1 if d > 0.0 else -tol1))
        fu = _objective(row, c0, heat, target, lo, integral_lo, u)
        if fu <= fx:
            if u >= x:
                a = x
            else:
                b = x
            v, fv, w, fw, x, fx = w, fw, x, fx, u, fu
        else:
            if u < x:
                a = u
            else:
                b = u
            if fu <= fw or w == x:
                v, fv, w, fw = w, fw, u, fu
            elif fu <= fv or v in (x, w):
                v, fv = u, fu
    return fx, x


@jit
def _closed_bracket(j, m, integral_before):
    """The grid angles either side of grid point ``j`` inside the closed cycle [π, 3π], and
    the heat-release integral at the first (``integral_before`` at grid point j − 1, 0 before
    π)."""
    lo = max(math.pi, CYCLE_ANGLE * (j - 1) / m)
    hi = min(3.0 * math.pi, CYCLE_ANGLE * (j + 1) / m)
    return lo, hi, integral_before if CYCLE_ANGLE * (j - 1) / m >= math.pi else 0.0


@batch
def cycle_pressure_batch(params, out, pressure_out):
    """Cylinder pressure of a single-zone polytropic cycle with Wiebe heat release.

    params      : float[n, N_PARAMS]  Case parameters (columns of this module).
    out         : float[n, N_OUT]     Scalars, columns OUT_* (names OUTPUTS): grid peak
                                      pressure and its angle after firing TDC, heat released in
                                      the closed cycle, compression pressure p_a ε^k, pressure
                                      at exhaust opening, indicated work ∮p dV (closed form
                                      W = Q − (p_eo − p_a)V_bdc/(k − 1) + (p_a − p_ex)V_d) and
                                      IMEP = W/V_d.
    pressure_out: float[n, m]         Pressure on α_j = 4π j/m [Pa] (m sets the grid).
    Reference: module docstring; physics §5.
    """
    m = pressure_out.shape[1]
    for i in prange(params.shape[0]):
        row = params[i]
        prow = pressure_out[i]
        k = row[POLYTROPIC_EXPONENT]
        p_a = row[INTAKE_PRESSURE]
        area = 0.25 * math.pi * row[BORE] ** 2
        v_d = 2.0 * row[CRANK_RADIUS] * area
        v_bdc = v_d * row[COMPRESSION_RATIO] / (row[COMPRESSION_RATIO] - 1.0)
        c0 = p_a * v_bdc**k
        target = row[PEAK_PRESSURE_TARGET]
        integral = 0.0
        previous = math.pi
        heat_for_target = math.inf
        limiting = -1  # the grid point whose pressure reaches the target first
        motoring_max = 0.0
        for j in range(m):
            alpha = CYCLE_ANGLE * j / m
            if alpha < math.pi or alpha > 3.0 * math.pi:
                continue
            integral += heat_release_integral(row, previous, alpha)
            previous = alpha
            v_k = (
                cylinder_volume(
                    row[BORE], row[CRANK_RADIUS], row[ROD_RATIO], row[COMPRESSION_RATIO], alpha
                )
                ** k
            )
            prow[j] = integral  # until the pressure replaces it
            motoring_max = max(motoring_max, c0 / v_k)
            per_joule = (k - 1.0) * integral / v_k
            if per_joule > 0.0 and (target - c0 / v_k) / per_joule < heat_for_target:
                heat_for_target = (target - c0 / v_k) / per_joule
                limiting = j
        total = integral + heat_release_integral(row, previous, 3.0 * math.pi)
        if int(row[HEAT_INPUT_MODE]) == HEAT_MODE_PEAK_PRESSURE:
            ok = motoring_max <= target and heat_for_target < math.inf
            if ok:  # the target is the peak between the grid points too, not only on them
                lo, hi, integral_lo = _closed_bracket(limiting, m, prow[limiting - 1])
                heat_for_target = min(
                    heat_for_target, _located(row, c0, math.nan, target, lo, integral_lo, hi)[0]
                )
            heat = heat_for_target if ok else math.nan
        else:
            heat = row[HEAT_RELEASED]
        peak = -math.inf
        peak_angle = math.nan
        peak_index = -1
        previous_integral = 0.0  # at grid point j − 1, before its pressure replaced it
        peak_integral = 0.0  # that of the peak's grid point − 1
        for j in range(m):
            alpha = CYCLE_ANGLE * j / m
            integral = 0.0
            if alpha < math.pi:
                prow[j] = p_a
            elif alpha > 3.0 * math.pi:
                prow[j] = row[EXHAUST_PRESSURE]
            else:
                integral = prow[j]
                volume = cylinder_volume(
                    row[BORE], row[CRANK_RADIUS], row[ROD_RATIO], row[COMPRESSION_RATIO], alpha
                )
                prow[j] = (c0 + (k - 1.0) * heat * integral) / volume**k
            if prow[j] > peak:
                peak = prow[j]
                peak_angle = alpha - 2.0 * math.pi
                peak_index = j
                peak_integral = previous_integral
            previous_integral = integral
        if math.isnan(heat):
            peak = math.nan
            peak_angle = math.nan
        elif math.pi <= CYCLE_ANGLE * peak_index / m <= 3.0 * math.pi:
            lo, hi, integral_lo = _closed_bracket(peak_index, m, peak_integral)
            value, angle = _located(row, c0, heat, target, lo, integral_lo, hi)
            if -value > peak:
                peak, peak_angle = -value, angle - 2.0 * math.pi
        start = 2.0 * math.pi + row[COMBUSTION_START]
        released = heat * (
            wiebe_burned_fraction(
                3.0 * math.pi - start,
                row[COMBUSTION_DURATION],
                row[WIEBE_EFFICIENCY],
                row[WIEBE_FORM],
            )
            - wiebe_burned_fraction(
                math.pi - start, row[COMBUSTION_DURATION], row[WIEBE_EFFICIENCY], row[WIEBE_FORM]
            )
        )
        p_eo = (c0 + (k - 1.0) * heat * total) / v_bdc**k
        work = released - (p_eo - p_a) * v_bdc / (k - 1.0) + (p_a - row[EXHAUST_PRESSURE]) * v_d
        out[i, OUT_PEAK_PRESSURE] = peak
        out[i, OUT_PEAK_PRESSURE_ANGLE] = peak_angle
        out[i, OUT_HEAT_RELEASED] = released
        out[i, OUT_COMPRESSION_PRESSURE] = p_a * row[COMPRESSION_RATIO] ** k
        out[i, OUT_EXPANSION_END_PRESSURE] = p_eo
        out[i, OUT_CYCLE_WORK] = work
        out[i, OUT_IMEP] = work / v_d
