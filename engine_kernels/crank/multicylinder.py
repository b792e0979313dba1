"""Multi-cylinder layouts of the slider-crank engine: the ``multicylinder`` driver (physics §5).

This module holds firing angles (even, and V engines with shared crankpins), cylinder axis
angles of V layouts, the free first- and second-order reciprocating forces and moments of a
layout, the
periodic interpolation and harmonic amplitude used on the cycle grid, the output columns of the
multi-cylinder driver and :func:`crank_multicylinder_batch` (summed torque, its harmonic orders
and the free forces). Parameter columns and conventions are those of :mod:`engine_kernels.crank.kinematics`;
the single-cylinder torque comes from :mod:`engine_kernels.crank.forces`.
"""

from __future__ import annotations

import math

import numpy as np

from engine_kernels._jit import batch, jit, prange
from engine_kernels.crank.forces import crank_torque_curve
from engine_kernels.crank.kinematics import (
    ANGULAR_SPEED,
    CRANK_RADIUS,
    CYCLE_ANGLE,
    CYLINDERS,
    RECIPROCATING_MASS,
    ROD_RATIO,
)

# Columns of the multi-cylinder output out[n, N_MULTI_OUT].
MULTI_MEAN_TORQUE = 0
MULTI_MAX_TORQUE = 1
MULTI_MIN_TORQUE = 2
MULTI_TORQUE_PEAK_TO_PEAK = 3
MULTI_TORQUE_NONUNIFORMITY = 4
MULTI_MEAN_POWER = 5
MULTI_FREE_FIRST_ORDER_FORCE = 6
MULTI_FREE_SECOND_ORDER_FORCE = 7
MULTI_FREE_FIRST_ORDER_MOMENT = 8
MULTI_FREE_SECOND_ORDER_MOMENT = 9
N_MULTI_OUT = 10
MULTI_OUTPUTS = (
    "mean_torque",
    "max_torque",
    "min_torque",
    "torque_peak_to_peak",
    "torque_nonuniformity",
    "mean_power",
    "free_first_order_force",
    "free_second_order_force",
    "free_first_order_moment",
    "free_second_order_moment",
)
MULTI_OUTPUT_UNITS = ("N m", "N m", "N m", "N m", "-", "W", "N", "N", "N m", "N m")

# --- multi-cylinder layouts -----------------------------------------------------------------


@jit
def even_firing_angles(firing_order, firing_out):
    """Even firing: cylinder firing_order[k] fires at k·720°/z  (physics §5).

    firing_order: int[:]    Cylinder numbers (1-based) in firing order, length z.
    firing_out  : float[:]  Output, firing angle of cylinder c at index c − 1 [rad].
    """
    z = firing_order.shape[0]
    for k in range(z):
        firing_out[firing_order[k] - 1] = CYCLE_ANGLE * k / z


@jit
def v_crank_firing_angles(firing_order, bank_angle, firing_out):
    """Firing angles of a V engine with shared crankpins (two rods per throw).

    The firing order alternates banks; the leading-bank cylinders (even positions k = 0, 2, …)
    fire evenly every 1440°/z, and each following cylinder on the other bank shares a throw
    with the one before it, so it fires one bank angle γ later. Firing is even (720°/z) only
    when γ = 720°/z (a 6-throw V12 at 60°); a 90° V12 fires at alternating 90°/30° intervals.

    firing_order: int[:]    Cylinder numbers (1-based) in firing order, even length z.
    bank_angle  : float     γ between the banks [rad].
    firing_out  : float[:]  Output, firing angle of cylinder c at index c − 1 [rad].
    Reference: physics §5 (a 6-throw V12 fires evenly only at a 60° bank).
    """
    z = firing_order.shape[0]
    for k in range(z):
        lead = CYCLE_ANGLE * (k // 2) / (z // 2)
        firing_out[firing_order[k] - 1] = lead + bank_angle * (k % 2)


@jit
def v_axis_angles(firing_order, bank_angle, axis_out):
    """Cylinder axis angles of a V layout: −γ/2 for the leading bank, +γ/2 for the other.

    Banks alternate along the firing order (position k even → leading bank). Angles are
    measured from the vertical in the direction of rotation; a cylinder reaches TDC when its
    crank throw points along its axis.

    firing_order: int[:]    Cylinder numbers (1-based) in firing order.
    bank_angle  : float     γ [rad].
    axis_out    : float[:]  Output, axis angle of cylinder c at index c − 1 [rad].
    Reference: physics §5.
    """
    for k in range(firing_order.shape[0]):
        axis_out[firing_order[k] - 1] = bank_angle * ((k % 2) - 0.5)


@jit
def free_force_amplitude(a_x, a_y, b_x, b_y):
    """Largest magnitude of the rotating/oscillating vector F(t) = A cos t + B sin t.

    |F|² = |A|² cos²t + |B|² sin²t + 2 A·B sin t cos t, maximised in closed form:
    (|A|² + |B|²)/2 + √(((|A|² − |B|²)/2)² + (A·B)²).

    a_x, a_y: float  Components of A [N].
    b_x, b_y: float  Components of B [N].
    Reference: physics §5 (free forces of a layout).
    """
    aa = a_x * a_x + a_y * a_y
    bb = b_x * b_x + b_y * b_y
    ab = a_x * b_x + a_y * b_y
    half_diff = 0.5 * (aa - bb)
    return math.sqrt(max(0.5 * (aa + bb) + math.sqrt(half_diff * half_diff + ab * ab), 0.0))


@jit
def layout_resultant(firing, axis, weights, cylinders, order):
    """Amplitude of Σ w_i cos(order·(α − ψ_i)) e_i over a crank revolution (unit force).

    The reciprocating force of order 1 or 2 of cylinder i is ∝ cos(order·(α − ψ_i)) along its
    axis e_i = (sin θ_i, cos θ_i), ψ_i its TDC crank angle (its firing angle; the 720°
    ambiguity drops out of the first and second orders). With weights 1 the sum is the free
    force; with weights z_i − z̄ (axial position from the middle) its magnitude is that of the
    free moment, whose vector is the force sum turned by 90° about the crank axis. The vector
    sum is A cos(order·α) + B sin(order·α) (:func:`free_force_amplitude`).

    firing   : float[:]  Firing angles ψ_i [rad].
    axis     : float[:]  Cylinder axis angles θ_i [rad].
    weights  : float[:]  w_i [-] or [m].
    cylinders: int       Number of cylinders used (leading entries of the arrays).
    order    : int       1 or 2.
    """
    a_x = 0.0
    a_y = 0.0
    b_x = 0.0
    b_y = 0.0
    for c in range(cylinders):
        cp = weights[c] * math.cos(order * firing[c])
        sp = weights[c] * math.sin(order * firing[c])
        ex = math.sin(axis[c])
        ey = math.cos(axis[c])
        a_x += cp * ex
        a_y += cp * ey
        b_x += sp * ex
        b_y += sp * ey
    return free_force_amplitude(a_x, a_y, b_x, b_y)


@jit
def free_reciprocating_force(
    reciprocating_mass, crank_radius, rod_ratio, angular_speed, firing, axis, cylinders, order
):
    """Free first- or second-order reciprocating force of a layout (amplitude of the resultant).

    Cylinder i contributes −mj r ω² λ^(order−1) cos(order·(α − ψ_i)) along its axis
    (:func:`layout_resultant`).

    reciprocating_mass: float     mj [kg].
    crank_radius      : float     r [m].
    rod_ratio         : float     λ [-].
    angular_speed     : float     ω [rad/s].
    firing            : float[:]  Firing angles ψ_i [rad].
    axis              : float[:]  Cylinder axis angles θ_i [rad].
    cylinders         : int       Number of cylinders used (leading entries of the arrays).
    order             : int       1 or 2.
    Returns the largest magnitude of the resultant [N]. Reference: physics §5 [F2].
    """
    scale = reciprocating_mass * crank_radius * angular_speed**2 * rod_ratio ** (order - 1)
    return scale * layout_resultant(firing, axis, np.ones(cylinders), cylinders, order)


@jit
def free_reciprocating_moment(
    reciprocating_mass,
    crank_radius,
    rod_ratio,
    angular_speed,
    firing,
    axis,
    positions,
    cylinders,
    order,
):
    """Free first- or second-order reciprocating moment of a layout about its middle.

    The moments of the cylinders' reciprocating forces (:func:`free_reciprocating_force`)
    about the point midway along the crankshaft; where the free force of that order is zero
    the moment is the same about any point.

    positions: float[:]  Axial position z_i of each cylinder's axis along the crankshaft [m];
                         NaN where it is not modelled (then the result is NaN).
    Other arguments as in :func:`free_reciprocating_force`. Returns the largest magnitude
    [N m]. Reference: physics §5 [F2]; e.g. Taylor, *The Internal-Combustion Engine in Theory
    and Practice*, vol. 2, ch. 8 (couples of multi-cylinder engines).
    """
    middle = positions[:cylinders].sum() / cylinders
    arms = positions[:cylinders] - middle
    scale = reciprocating_mass * crank_radius * angular_speed**2 * rod_ratio ** (order - 1)
    return scale * layout_resultant(firing, axis, arms, cylinders, order)


@jit
def periodic_interpolate(values, position):
    """Linear interpolation of a periodic grid sequence at a fractional index.

    values  : float[:]  Samples on a uniform periodic grid.
    position: float     Fractional index (any real; wrapped modulo the length).
    Reference: standard periodic linear interpolation.
    """
    m = values.shape[0]
    wrapped = position % m
    k = math.floor(wrapped)
    frac = wrapped - k
    k = k % m
    return (1.0 - frac) * values[k] + frac * values[(k + 1) % m]


@jit
def harmonic_amplitude(values, harmonic):
    """Amplitude of harmonic q of a periodic grid sequence, 2|Σ v_j e^{−2πiqj/m}|/m.

    On the four-stroke cycle grid harmonic q is engine order q/2.

    values  : float[:]  Samples on a uniform periodic grid.
    harmonic: int       q ≥ 1.
    Reference: discrete Fourier transform.
    """
    m = values.shape[0]
    re = 0.0
    im = 0.0
    for j in range(m):
        phase = 2.0 * math.pi * harmonic * j / m
        re += values[j] * math.cos(phase)
        im -= values[j] * math.sin(phase)
    return 2.0 * math.sqrt(re * re + im * im) / m


# --- batch driver ---------------------------------------------------------------------------


@batch
def crank_multicylinder_batch(
    params, pressure, firing_angles, axis_angles, positions, out, harmonics_out, curves_out
):
    """Summed crankshaft torque, its harmonic orders, free forces and moments  [F1]–[F2].

    Every cylinder has the same pressure curve; cylinder c's torque is the single-cylinder
    torque shifted by its firing angle less cylinder 1's, so the summed curve is on cylinder
    1's crank angle like the single-cylinder curves (periodic linear interpolation, exact when
    the firing angles fall on the grid).

    params       : float[n, N_PARAMS]  Case parameters; CYLINDERS = z cylinders used.
    pressure     : float[n_p, m]       Cylinder pressure [Pa] on the cycle grid; n_p = n or 1.
    firing_angles: float[n_f, z_max]   Firing angle of each cylinder [rad] (see
                                       :func:`even_firing_angles`, :func:`v_crank_firing_angles`);
                                       n_f = n or 1.
    axis_angles  : float[n_f, z_max]   Cylinder axis angle from vertical [rad]: 0 inline,
                                       ±γ/2 for a V (:func:`v_axis_angles`).
    positions    : float[n_f, z_max]   Axial position of each cylinder along the crankshaft [m]
                                       (NaN: not modelled, free moments NaN).
    out          : float[n, N_MULTI_OUT]  Scalars, columns MULTI_* (names MULTI_OUTPUTS).
    harmonics_out: float[n, q_max]     Amplitude of engine orders 0.5, 1, 1.5, …, q_max/2 [N m]
                                       (q_max may be 0).
    curves_out   : float[n, 1, m], or last dimension 0 to skip. Summed torque [N m].
    Reference: physics §5.
    """
    m = pressure.shape[1]
    shared_p = pressure.shape[0] == 1
    shared_f = firing_angles.shape[0] == 1
    store = curves_out.shape[2] > 0
    step = CYCLE_ANGLE / m
    for i in prange(params.shape[0]):
        row = params[i]
        prow = pressure[0] if shared_p else pressure[i]
        firing = firing_angles[0] if shared_f else firing_angles[i]
        axis = axis_angles[0] if shared_f else axis_angles[i]
        position = positions[0] if shared_f else positions[i]
        z = int(row[CYLINDERS])
        single = np.empty(m)
        crank_torque_curve(row, prow, single)
        total = np.zeros(m)
        for c in range(z):
            shift = (firing[c] - firing[0]) / step  # on cylinder 1's crank angle
            for j in range(m):
                total[j] += periodic_interpolate(single, j - shift)
        mean = total.sum() / m
        t_max = total.max()
        t_min = total.min()
        out[i, MULTI_MEAN_TORQUE] = mean
        out[i, MULTI_MAX_TORQUE] = t_max
        out[i, MULTI_MIN_TORQUE] = t_min
        out[i, MULTI_TORQUE_PEAK_TO_PEAK] = t_max - t_min
        out[i, MULTI_TORQUE_NONUNIFORMITY] = (t_max - t_min) / mean if mean != 0.0 else np.nan
        out[i, MULTI_MEAN_POWER] = mean * row[ANGULAR_SPEED]
        mass, radius = row[RECIPROCATING_MASS], row[CRANK_RADIUS]
        lam, omega = row[ROD_RATIO], row[ANGULAR_SPEED]
        for order in (1, 2):
            out[i, MULTI_FREE_FIRST_ORDER_FORCE + order - 1] = free_reciprocating_force(
                mass, radius, lam, omega, firing, axis, z, order
            )
            out[i, MULTI_FREE_FIRST_ORDER_MOMENT + order - 1] = free_reciprocating_moment(
                mass, radius, lam, omega, firing, axis, position, z, order
            )
        for q in range(harmonics_out.shape[1]):
            harmonics_out[i, q] = harmonic_amplitude(total, q + 1)
        if store:
            for j in range(m):
                curves_out[i, 0, j] = total[j]
