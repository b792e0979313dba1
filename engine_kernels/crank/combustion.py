"""Parametric single-zone cylinder-pressure cycle for the ``crank`` scene (physics §5).

A four-stroke cycle on the crank-angle grid of :mod:`engine_kernels.crank.kinematics` (α_j = 4π j/m,
gas-exchange TDC at α = 0, firing TDC at α = 2π):

* intake stroke, 0 ≤ α < π: p = intake pressure p_a;
* closed cycle, π ≤ α ≤ 3π (inlet closes and exhaust opens at BDC): polytropic compression and
  expansion with exponent k and a Wiebe heat release, dp/dα = −k p V'/V + (k − 1) Q'/V. The
  equation is linear in p and integrates exactly to
  p V^k = p_a V_bdc^k + (k − 1) ∫ V^(k−1) dQ, so only the heat-release integral is numerical
  (3-point Gauss–Legendre on sub-steps of at most QUADRATURE_STEP, split at the start and end
  of combustion);
* exhaust stroke, 3π < α < 4π: p = exhaust pressure p_ex (blow-down at BDC is instantaneous).

Heat input (documented choice): HEAT_INPUT_MODE = HEAT_MODE_ENERGY takes the heat released per
cycle Q [J]; HEAT_MODE_PEAK_PRESSURE takes a target peak pressure [Pa] and finds Q exactly:
p_j = p_mot,j + Q g_j is linear in Q with g_j ≥ 0, so the largest Q whose grid peak does not
exceed the target is min over g_j > 0 of (p_target − p_mot,j)/g_j (NaN if the motoring pressure
alone exceeds the target). The Wiebe law is normalised so the burned fraction reaches exactly 1
at the end of combustion: x_b = (1 − exp(−a τ^(m+1)))/(1 − exp(−a)), τ = (α − α_s)/Δα.

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
"""Largest sub-step of the heat-release quadrature [rad]."""
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
def wiebe_burn_rate(angle_from_start, duration, efficiency, form):
    """Normalised Wiebe burn rate dx_b/dθ [1/rad].

    angle_from_start: float  Crank angle since start of combustion θ [rad].
    duration        : float  Combustion duration Δθ [rad].
    efficiency      : float  Wiebe a [-].
    form            : float  Wiebe m [-].
    Reference: Heywood (2018) §9.2, derivative of :func:`wiebe_burned_fraction`.
    """
    if angle_from_start <= 0.0 or angle_from_start >= duration:
        return 0.0
    tau = angle_from_start / duration
    return (
        efficiency
        * (form + 1.0)
        / duration
        * tau**form
        * math.exp(-efficiency * tau ** (form + 1.0))
        / -math.expm1(-efficiency)
    )


@jit
def heat_release_integral(row, lower, upper):
    """∫ V^(k−1) dx_b/dα dα over [lower, upper] ∩ combustion, per joule of heat input.

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
    steps = math.ceil((hi - lo) / QUADRATURE_STEP)
    h = (hi - lo) / steps
    total = 0.0
    for s in range(steps):
        centre = lo + (s + 0.5) * h
        for node, weight in (
            (-GAUSS_NODE, GAUSS_WEIGHT_OUTER),
            (0.0, GAUSS_WEIGHT_CENTRE),
            (GAUSS_NODE, GAUSS_WEIGHT_OUTER),
        ):
            angle = centre + 0.5 * h * node
            volume = cylinder_volume(
                row[BORE], row[CRANK_RADIUS], row[ROD_RATIO], row[COMPRESSION_RATIO], angle
            )
            rate = wiebe_burn_rate(angle - start, duration, row[WIEBE_EFFICIENCY], row[WIEBE_FORM])
            total += 0.5 * h * weight * volume ** (row[POLYTROPIC_EXPONENT] - 1.0) * rate
    return total


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
            prow[j] = integral
            motoring_max = max(motoring_max, c0 / v_k)
            per_joule = (k - 1.0) * integral / v_k
            if per_joule > 0.0:
                heat_for_target = min(heat_for_target, (target - c0 / v_k) / per_joule)
        total = integral + heat_release_integral(row, previous, 3.0 * math.pi)
        if int(row[HEAT_INPUT_MODE]) == HEAT_MODE_PEAK_PRESSURE:
            ok = motoring_max <= target and heat_for_target < math.inf
            heat = heat_for_target if ok else math.nan
        else:
            heat = row[HEAT_RELEASED]
        peak = -math.inf
        peak_angle = math.nan
        for j in range(m):
            alpha = CYCLE_ANGLE * j / m
            if alpha < math.pi:
                prow[j] = p_a
            elif alpha > 3.0 * math.pi:
                prow[j] = row[EXHAUST_PRESSURE]
            else:
                volume = cylinder_volume(
                    row[BORE], row[CRANK_RADIUS], row[ROD_RATIO], row[COMPRESSION_RATIO], alpha
                )
                prow[j] = (c0 + (k - 1.0) * heat * prow[j]) / volume**k
            if prow[j] > peak:
                peak = prow[j]
                peak_angle = alpha - 2.0 * math.pi
        if math.isnan(heat):
            peak = math.nan
            peak_angle = math.nan
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
