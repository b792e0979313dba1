"""Multi-segment symmetric acceleration profile of a flat-faced tappet cam (physics §2, §9).

The working half-event (ramp end → nose) is split into six segments of widths w_k [rad]. Each
segment's acceleration a(x) [m/rad²] over x ∈ [0, 1] runs from the previous segment's end value
a0 (0 for segment 1) to its own end value a1, with L(x) = a0 + (a1 - a0)·x and shape

* SHAPE_LIN       a = L
* SHAPE_SIN_FULL  a = L + A·sin(πx)
* SHAPE_SIN_LEFT  a = L + A·(sin(πx/2) - x)
* SHAPE_FILLET    cubic Hermite matching the neighbours' values and slopes (at a joint of two
                  fillets both take the right one's chord slope; the ramp end and the nose count
                  as slope-zero neighbours, so the profile is C¹ there too).

Amplitudes A ≥ 0 are signed to bulge away from zero (+ for segments 1-3, - for 4-6). Every
shape is a cubic polynomial plus multiples of sin(πx) and sin(πx/2), so velocity and lift are
integrated in closed form. The acceleration is linear in the end values and amplitudes, so the
profile is the superposition sp·a_pos + sn·a_neg of its positive part (segments 1-3, with
segment 4's start value) and negative part. Closure (zero velocity at the nose) fixes sn for
sp = 1; a target working lift fixes both by a 2x2 linear system (a uniform scale when the ramp
velocity is zero).

The working lift is the lift gained over the working part: the nose lift minus the lift at the
ramp end (so it includes the v_ramp·W carried over from the ramp velocity).
"""

from __future__ import annotations

import math

import numpy as np

from engine_kernels._jit import batch, jit, prange

SHAPE_LIN = 0
SHAPE_SIN_FULL = 1
SHAPE_SIN_LEFT = 2
SHAPE_FILLET = 3
N_SHAPES = 4

N_SEGMENTS = 6
N_POSITIVE_SEGMENTS = 3
"""Segments 1-3 (indices 0-2) form the positive-acceleration part, 4-6 the negative part."""

D_CLOSURE_RESIDUAL = 0
D_RAW_NOSE_VELOCITY = 1
D_UNSCALED_WORKING_LIFT = 2
D_POSITIVE_SCALE = 3
D_NEGATIVE_SCALE = 4
D_FILLET_MONOTONE = 5
D_RAMP_FEASIBLE = 6
D_EVENT_HALF_WIDTH = 7
D_INPUT_VALID = 8
N_DIAG = 9
DIAG_NAMES = (
    "closure_residual",
    "raw_nose_velocity",
    "unscaled_working_lift",
    "positive_scale",
    "negative_scale",
    "fillet_monotone",
    "ramp_feasible",
    "event_half_width",
    "input_valid",
)
DIAG_UNITS = ("m/rad", "m/rad", "m", "1", "1", "1", "1", "rad", "1")
"""Diagnostic columns: nose velocity of the final profile [m/rad] (0 after closure); nose
velocity before the closure fix, sp = sn = 1 [m/rad]; working lift after closure with sp = 1
[m]; positive and negative scale factors sp, sn [-]; fillet monotone flag; ramp feasible flag;
event half-width including the ramp [rad]; input valid flag (flags are 1.0 or 0.0)."""

_N_COLUMNS = 6
"""Per-segment table: cubic coefficients q0…q3 of a(x), then the sin(πx) and sin(πx/2)
multipliers."""
_S_FULL = 4
_S_QUARTER = 5
_HALF_PI = 0.5 * math.pi
_TINY = 1e-300
_REL_TOL = 1e-12


@jit
def segment_widths(widths, shapes, half_event, out):
    """Segment widths after keeping the working half-event fixed (physics §2 width rule).

    The excess Δ = Σw - half_event is absorbed -Δ/2 by the first fillet segment and -Δ/2 by
    the last segment, or all by the last segment when there is no fillet before it (physics §9:
    segment 2 going 11 → 9 turns fillet 22 → 23 and segment 6 23 → 24).

    widths    : array  Nominal widths w_k, shape (6,) [rad].
    shapes    : array  Shape codes, shape (6,) [-].
    half_event: float  Working half-event [rad]; ≤ 0 keeps the nominal widths.
    out       : array  Adjusted widths, shape (6,) [rad] (written).

    Returns True when every adjusted width is ≥ 0 and their sum is > 0.
    """
    total = 0.0
    for k in range(N_SEGMENTS):
        out[k] = widths[k]
        total += widths[k]
    if half_event > 0.0:
        excess = total - half_event
        last = N_SEGMENTS - 1
        fillet = -1
        for k in range(last):
            if shapes[k] == SHAPE_FILLET:
                fillet = k
                break
        if fillet >= 0:
            out[fillet] -= 0.5 * excess
            out[last] -= 0.5 * excess
        else:
            out[last] -= excess
    valid = True
    total = 0.0
    for k in range(N_SEGMENTS):
        valid = valid and out[k] >= 0.0
        total += out[k]
    return valid and total > 0.0


@batch
def segment_widths_batch(widths, shapes, half_event, out, valid):
    """:func:`segment_widths` for many profiles (one per prange row): nominal ``widths``
    (n, 6) [rad], ``shapes`` (n, 6) int64 codes, working ``half_event`` (n,) [rad]; writes the
    adjusted widths ``out`` (n, 6) [rad] and ``valid`` (n,) bool (every width ≥ 0)."""
    for i in prange(widths.shape[0]):
        valid[i] = segment_widths(widths[i], shapes[i], half_event[i], out[i])


@jit
def ramp_layout(height, width, velocity):
    """Lash-take-up ramp: constant acceleration over width w1, then constant velocity (physics §2).

    Height Hr = v (Wr - w1/2), so w1 = 2 (Wr - Hr/v), feasible iff Hr/v ≤ Wr ≤ 2 Hr/v. An
    infeasible ramp is clamped to the nearest feasible w1 (its height then differs from Hr) and
    reported, never raised; a ramp with Hr = v = 0 is a plain dwell, and negative inputs give
    a motionless (infeasible) ramp. At the edge Wr = Hr/v, w1 = 0: the ramp starts with a
    velocity step.

    height  : float  Ramp height Hr [m].
    width   : float  Ramp width Wr [rad].
    velocity: float  Ramp end velocity v [m/rad].

    Returns (w1 [rad], actual height [m], velocity used [m/rad], feasible).
    """
    if width < 0.0 or height < 0.0 or velocity < 0.0:
        return 0.0, 0.0, 0.0, False
    if velocity == 0.0:
        return 0.0, 0.0, 0.0, height == 0.0
    w1 = 2.0 * (width - height / velocity)
    tol = _REL_TOL * max(width, height / velocity)
    feasible = -tol <= w1 <= width + tol
    w1 = min(max(w1, 0.0), width)
    return w1, velocity * (width - 0.5 * w1), velocity, feasible


@jit
def _end_slope(row):
    """da/dx of a table row at x = 1."""
    return row[1] + 2.0 * row[2] + 3.0 * row[3] - math.pi * row[_S_FULL]


@jit
def _start_slope(row):
    """da/dx of a table row at x = 0."""
    return row[1] + math.pi * row[_S_FULL] + _HALF_PI * row[_S_QUARTER]


@jit
def _segment_table(widths, shapes, end_accels, amplitudes, sp, sn, table):
    """Fill ``table[6, 6]`` for the profile scaled by sp (segments 1-3) and sn (4-6).

    Returns True when every fillet stays monotone between its end values (no overshoot)."""
    a0 = 0.0
    for k in range(N_SEGMENTS):
        scale = sp if k < N_POSITIVE_SEGMENTS else sn
        sign = 1.0 if k < N_POSITIVE_SEGMENTS else -1.0
        a1 = scale * end_accels[k]
        amp = sign * scale * amplitudes[k]
        for c in range(_N_COLUMNS):
            table[k, c] = 0.0
        table[k, 0] = a0
        table[k, 1] = a1 - a0
        if shapes[k] == SHAPE_SIN_FULL:
            table[k, _S_FULL] = amp
        elif shapes[k] == SHAPE_SIN_LEFT:
            table[k, 1] -= amp
            table[k, _S_QUARTER] = amp
        a0 = a1
    monotone = True
    for k in range(N_SEGMENTS):
        if shapes[k] != SHAPE_FILLET or widths[k] <= 0.0:
            continue
        slope0 = 0.0
        if k > 0 and widths[k - 1] > 0.0:
            slope0 = _end_slope(table[k - 1]) / widths[k - 1]
        slope1 = 0.0
        if k < N_SEGMENTS - 1 and widths[k + 1] > 0.0:
            slope1 = _start_slope(table[k + 1]) / widths[k + 1]
        m0 = slope0 * widths[k]
        m1 = slope1 * widths[k]
        y0 = table[k, 0]
        y1 = y0 + table[k, 1]
        table[k, 1] = m0
        table[k, 2] = -3.0 * y0 - 2.0 * m0 + 3.0 * y1 - m1
        table[k, 3] = 2.0 * y0 + m0 - 2.0 * y1 + m1
        monotone = monotone and _cubic_monotone(table[k], y1 - y0)
    return monotone


@jit
def _cubic_monotone(row, rise):
    """True when q1 + 2 q2 x + 3 q3 x² never takes the sign opposite to ``rise`` on [0, 1]."""
    q1, q2, q3 = row[1], row[2], row[3]
    tol = _REL_TOL * (abs(row[0]) + abs(q1) + abs(q2) + abs(q3))
    direction = 1.0 if rise >= 0.0 else -1.0
    lowest = min(direction * q1, direction * (q1 + 2.0 * q2 + 3.0 * q3))
    if q3 != 0.0:
        xv = -q2 / (3.0 * q3)
        if 0.0 < xv < 1.0:
            lowest = min(lowest, direction * (q1 + xv * (2.0 * q2 + 3.0 * q3 * xv)))
    if abs(rise) <= tol:
        highest = max(abs(q1), abs(q1 + 2.0 * q2 + 3.0 * q3))
        return highest <= tol
    return lowest >= -tol


@jit
def _segment_state(row, x):
    """(∫∫a, ∫a, a, da/dx) of one table row at x, integrals taken from 0 in units of x."""
    q0, q1, q2, q3 = row[0], row[1], row[2], row[3]
    s_full, s_quarter = row[_S_FULL], row[_S_QUARTER]
    sf, cf = math.sin(math.pi * x), math.cos(math.pi * x)
    sq, cq = math.sin(_HALF_PI * x), math.cos(_HALF_PI * x)
    a = q0 + x * (q1 + x * (q2 + x * q3)) + s_full * sf + s_quarter * sq
    ax = q1 + x * (2.0 * q2 + 3.0 * q3 * x) + s_full * math.pi * cf + s_quarter * _HALF_PI * cq
    i1 = (
        x * (q0 + x * (q1 / 2.0 + x * (q2 / 3.0 + x * q3 / 4.0)))
        + s_full * (1.0 - cf) / math.pi
        + s_quarter * (1.0 - cq) / _HALF_PI
    )
    i2 = (
        x * x * (q0 / 2.0 + x * (q1 / 6.0 + x * (q2 / 12.0 + x * q3 / 20.0)))
        + s_full * (x / math.pi - sf / math.pi**2)
        + s_quarter * (x / _HALF_PI - sq / _HALF_PI**2)
    )
    return i2, i1, a, ax


@jit
def _working_increments(widths, table):
    """Velocity [m/rad] and lift [m] gained over the working part from rest."""
    v = 0.0
    h = 0.0
    for k in range(N_SEGMENTS):
        w = widths[k]
        i2, i1, _, _ = _segment_state(table[k], 1.0)
        h += v * w + w * w * i2
        v += w * i1
    return v, h


@jit
def _fill_invalid(out, diag):
    out[:, :] = np.nan
    diag[:] = np.nan
    diag[D_INPUT_VALID] = 0.0


@jit
def multi_segment_cam(
    theta,
    half_event,
    widths,
    shapes,
    end_accels,
    amplitudes,
    ramp_height,
    ramp_width,
    ramp_velocity,
    target_lift,
    out,
    diag,
):
    """Lift h and derivatives of the symmetric multi-segment cam on a grid (physics §2, §9).

    Nose at θ = 0; for θ < 0 the ramp starts at -(Wr + W) and the working part spans [-W, 0];
    the fall (θ > 0) is the mirror image; base circle outside the event.

    theta        : array  Cam angles from the nose, shape (m,) [rad] (any order).
    half_event   : float  Working half-event W [rad]; ≤ 0 uses the sum of the widths.
    widths       : array  Nominal segment widths, shape (6,) [rad] (see ``segment_widths``).
    shapes       : array  Segment shape codes SHAPE_*, shape (6,) int.
    end_accels   : array  Segment end accelerations a_k, shape (6,) [m/rad²].
    amplitudes   : array  Segment amplitudes A_k ≥ 0, shape (6,) [m/rad²].
    ramp_height  : float  Ramp height Hr [m].
    ramp_width   : float  Ramp width Wr [rad].
    ramp_velocity: float  Ramp end velocity [m/rad].
    target_lift  : float  Working lift to scale to [m]; ≤ 0 keeps sp = 1 (closure only).
    out          : array  Output (4, m): h [m], h' [m/rad], h'' [m/rad²], h''' [m/rad³].
    diag         : array  Output (N_DIAG,): see DIAG_NAMES.

    h''' is the exact jerk inside each piece; it is 0 on the ramp, whose acceleration steps
    (at the ramp start and where the constant velocity begins) carry infinite jerk that a
    grid cannot hold.
    Invalid input (unknown shape, a negative width after absorption, a profile whose
    closure or lift system is singular) gives NaN curves with diag[D_INPUT_VALID] = 0.
    Reference: physics §2 (12V150 exhaust-cam design method).
    """
    w = np.empty(N_SEGMENTS)
    valid = segment_widths(widths, shapes, half_event, w)
    for k in range(N_SEGMENTS):
        valid = valid and 0 <= shapes[k] < N_SHAPES
    if not valid:
        _fill_invalid(out, diag)
        return
    working = 0.0
    for k in range(N_SEGMENTS):
        working += w[k]
    ramp_w = max(ramp_width, 0.0)
    w1, hr, vr, feasible = ramp_layout(ramp_height, ramp_width, ramp_velocity)

    table = np.empty((N_SEGMENTS, _N_COLUMNS))
    _segment_table(w, shapes, end_accels, amplitudes, 1.0, 0.0, table)
    v_pos, h_pos = _working_increments(w, table)
    _segment_table(w, shapes, end_accels, amplitudes, 0.0, 1.0, table)
    v_neg, h_neg = _working_increments(w, table)
    scale_v = abs(v_pos) + abs(v_neg) + vr
    if abs(v_neg) <= _REL_TOL * scale_v or scale_v <= _TINY:
        _fill_invalid(out, diag)
        return
    sn = -(vr + v_pos) / v_neg
    sp = 1.0
    unscaled_lift = vr * working + h_pos + sn * h_neg
    if target_lift > 0.0:
        det = v_pos * h_neg - v_neg * h_pos
        if abs(det) <= _REL_TOL * (abs(v_pos * h_neg) + abs(v_neg * h_pos)):
            _fill_invalid(out, diag)
            return
        rhs = target_lift - vr * working
        sp = (-vr * h_neg - v_neg * rhs) / det
        sn = (v_pos * rhs + vr * h_pos) / det
    monotone = _segment_table(w, shapes, end_accels, amplitudes, sp, sn, table)

    starts = np.empty(N_SEGMENTS + 1)
    v_start = np.empty(N_SEGMENTS + 1)
    h_start = np.empty(N_SEGMENTS + 1)
    starts[0] = 0.0
    v_start[0] = vr
    h_start[0] = hr
    for k in range(N_SEGMENTS):
        i2, i1, _, _ = _segment_state(table[k], 1.0)
        starts[k + 1] = starts[k] + w[k]
        h_start[k + 1] = h_start[k] + v_start[k] * w[k] + w[k] * w[k] * i2
        v_start[k + 1] = v_start[k] + w[k] * i1

    event = ramp_w + working
    ramp_accel = vr / w1 if w1 > 0.0 else 0.0
    for j in range(theta.shape[0]):
        t = -abs(theta[j])
        sign = 1.0 if theta[j] <= 0.0 else -1.0
        s = t + event
        if s < 0.0:
            h, h1, h2, h3 = 0.0, 0.0, 0.0, 0.0
        elif s < ramp_w:
            if s < w1:
                h, h1, h2, h3 = 0.5 * ramp_accel * s * s, ramp_accel * s, ramp_accel, 0.0
            else:
                h, h1, h2, h3 = 0.5 * vr * w1 + vr * (s - w1), vr, 0.0, 0.0
        else:
            s -= ramp_w
            k = 0
            while k < N_SEGMENTS - 1 and (s >= starts[k + 1] or w[k] <= 0.0):
                k += 1
            while w[k] <= 0.0:
                k -= 1
            x = min(max((s - starts[k]) / w[k], 0.0), 1.0)
            i2, i1, a, ax = _segment_state(table[k], x)
            h = h_start[k] + w[k] * x * v_start[k] + w[k] * w[k] * i2
            h1 = v_start[k] + w[k] * i1
            h2 = a
            h3 = ax / w[k]
        out[0, j] = h
        out[1, j] = sign * h1
        out[2, j] = h2
        out[3, j] = sign * h3

    diag[D_CLOSURE_RESIDUAL] = v_start[N_SEGMENTS]
    diag[D_RAW_NOSE_VELOCITY] = vr + v_pos + v_neg
    diag[D_UNSCALED_WORKING_LIFT] = unscaled_lift
    diag[D_POSITIVE_SCALE] = sp
    diag[D_NEGATIVE_SCALE] = sn
    diag[D_FILLET_MONOTONE] = 1.0 if monotone else 0.0
    diag[D_RAMP_FEASIBLE] = 1.0 if feasible else 0.0
    diag[D_EVENT_HALF_WIDTH] = event
    diag[D_INPUT_VALID] = 1.0
