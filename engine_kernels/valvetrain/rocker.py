"""Overhead cam with a variable-ratio rocker: valve lift from the flat-tappet lift law (physics §3).

The cam is given by its flat-tappet lift law ``h(φ)`` (with ``h'`` and ``h''``) on a grid of
tappet angles φ, in lift-table order (φ increases with time, nose at φ = 0). A rocker pivoting
at O carries a pad of radius rs (centre A, ``|OA| = la``) on the cam (centre Oc,
``|OOc| = lc``) and, on its other arm, a ball of radius ρb at ``lb`` from O on the flat tip of
the valve stem. The chain [R1]–[R6] maps each tappet point to the cam rotation ``φr`` that
puts it in contact and to the rocker angle W and valve lift Y; the non-uniform ``φr`` are then
resampled onto the caller's cam-angle grid with cubic Hermite pieces whose slopes are the exact
chain derivatives.

Sign convention (physics §3): φ, ψ and φr are measured in the direction of rotation. With the pad
centre A *ahead* of the line OcO (``PAD_AHEAD``) ``φr = φ + ψ + (K − K_d)``; *behind*
(``PAD_BEHIND``) ``φr = φ + ψ − (K − K_d)``. Because ``K`` falls as the pad rises, a symmetric
cam with the pad ahead opens over a shorter cam angle than it closes (steeper opening flank,
larger opening than closing velocity); with the pad behind it is the mirror image.

Geometry is passed as a 1-D array indexed by the ``G_*`` constants (all lengths in m).
Reference: physics §3 (125 cc motorcycle OHC valve train).
"""

from __future__ import annotations

import math

import numpy as np

from engine_kernels._jit import jit, jit_inline
from engine_kernels.valvetrain.rk4 import hermite_slope, hermite_value

PAD_AHEAD = 1
PAD_BEHIND = -1

G_BASE_RADIUS = 0
G_PAD_RADIUS = 1
G_PAD_ARM = 2
G_CENTRE_DISTANCE = 3
G_VALVE_ARM = 4
G_BALL_RADIUS = 5
G_STEM_HEIGHT = 6
G_LASH = 7
ROCKER_GEOMETRY_NAMES = (
    "base_radius",
    "pad_radius",
    "pad_arm",
    "centre_distance",
    "valve_arm",
    "ball_radius",
    "stem_height",
    "lash",
)

ROW_VALVE_LIFT = 0
ROW_VALVE_VELOCITY = 1
ROW_VALVE_ACCELERATION = 2
ROW_FORCE_RATIO = 3
ROW_ROCKER_ANGLE = 4
ROW_TAPPET_ANGLE = 5
ROCKER_CURVE_NAMES = (
    "valve_lift",
    "valve_velocity",
    "valve_acceleration",
    "force_ratio",
    "rocker_angle",
    "tappet_angle",
)
ROCKER_CURVE_UNITS = ("m", "m/rad", "m/rad^2", "1", "rad", "rad")

# Rows of a rocker walk (the linkage at every tappet point, :func:`rocker_walk`).
W_ROTATION = 0  # cam rotation φr [rad]
W_VALVE = 1  # valve lift before clipping [m]
W_VALVE_SLOPE = 2  # dY/dφr [m/rad]
W_ANGLE = 3  # rocker angle W [rad]
W_ANGLE_SLOPE = 4  # dW/dφr [-]
W_TAPPET_SLOPE = 5  # dφ/dφr [-]
W_RATIO = 6  # force ratio [-]
N_WALK = 7

ROCKER_OK = 0
ROCKER_CONCAVE_CAM = 1
ROCKER_NOT_MONOTONE = 2
ROCKER_OUT_OF_REACH = 4
ROCKER_STATUS_FLAGS = (
    (ROCKER_CONCAVE_CAM, "cam not convex: r0 + h + h'' <= 0 somewhere, the chain is invalid"),
    (ROCKER_NOT_MONOTONE, "cam rotation phi_r not increasing along the table"),
    (ROCKER_OUT_OF_REACH, "pad cannot reach the cam: rocker triangle does not close"),
)


@jit
def pad_centre_distance(base_radius, pad_radius, lift, lift_velocity):
    """Distance ``R = |Oc A|`` from cam centre to pad centre [R1].

    ``R = sqrt((r0 + rs + h)² + h'²)``: A lies on the cam normal at rs from the contact.

    base_radius   : float  Cam base-circle radius r0 [m].
    pad_radius    : float  Rocker pad radius rs [m].
    lift          : float  Flat-tappet lift h [m].
    lift_velocity : float  Tappet velocity h' = dh/dφ [m/rad].
    """
    return math.hypot(base_radius + pad_radius + lift, lift_velocity)


@jit
def pad_offset_angle(base_radius, pad_radius, lift, lift_velocity):
    """Angle ψ between the tappet direction and Oc A, signed like h' [R2].

    ``ψ = atan(h'/(r0 + rs + h))``.

    base_radius   : float  Cam base-circle radius r0 [m].
    pad_radius    : float  Rocker pad radius rs [m].
    lift          : float  Flat-tappet lift h [m].
    lift_velocity : float  Tappet velocity h' [m/rad].
    """
    return math.atan2(lift_velocity, base_radius + pad_radius + lift)


@jit
def rocker_angle(pad_arm, centre_distance, centre_to_pad):
    """Rocker angle W between OA and OOc, from the triangle O–Oc–A [R3].

    ``W = acos((la² + lc² − R²)/(2 la lc))``; NaN if the triangle cannot close.

    pad_arm         : float  Pivot to pad-centre distance la [m].
    centre_distance : float  Pivot to cam-centre distance lc [m].
    centre_to_pad   : float  Cam centre to pad centre R [m].
    """
    cosine = (pad_arm**2 + centre_distance**2 - centre_to_pad**2) / (
        2.0 * pad_arm * centre_distance
    )
    return math.acos(cosine) if abs(cosine) <= 1.0 else math.nan


@jit
def cam_centre_angle(pad_arm, centre_distance, centre_to_pad):
    """Angle K at the cam centre between Oc O and Oc A [R4].

    ``K = acos((lc² + R² − la²)/(2 lc R))``; NaN if the triangle cannot close.

    pad_arm         : float  Pivot to pad-centre distance la [m].
    centre_distance : float  Pivot to cam-centre distance lc [m].
    centre_to_pad   : float  Cam centre to pad centre R [m].
    """
    cosine = (centre_distance**2 + centre_to_pad**2 - pad_arm**2) / (
        2.0 * centre_distance * centre_to_pad
    )
    return math.acos(cosine) if abs(cosine) <= 1.0 else math.nan


@jit
def base_circle_rocker_angle(base_radius, pad_radius, pad_arm, centre_distance):
    """Rocker angle W0 with the pad on the base circle [R5].

    ``W0 = acos((la² + lc² − (r0 + rs)²)/(2 la lc))``; 73.543° for the physics §3 geometry.

    base_radius     : float  Cam base-circle radius r0 [m].
    pad_radius      : float  Rocker pad radius rs [m].
    pad_arm         : float  Pivot to pad-centre distance la [m].
    centre_distance : float  Pivot to cam-centre distance lc [m].
    """
    return rocker_angle(pad_arm, centre_distance, base_radius + pad_radius)


@jit
def valve_arm_base_angle(valve_arm, ball_radius, stem_height, lash):
    """Valve-arm angle β0 on the base circle, from the plane through O normal to the valve [R6].

    ``β0 = asin((Δ + ρb + z)/lb)``; 20.583° for the physics §3 geometry.

    valve_arm   : float  Pivot to ball-centre distance lb [m].
    ball_radius : float  Adjusting-screw ball radius ρb [m].
    stem_height : float  Height z of the valve-stem tip above the pivot [m].
    lash        : float  Valve lash Δ [m].
    """
    return math.asin((lash + ball_radius + stem_height) / valve_arm)


@jit
def valve_lift_from_rocker_angle(angle, base_angle, arm_base_angle, valve_arm, lash):
    """Valve lift from the rocker angle, before clipping at zero [R6].

    ``β = β0 − (W − W0)``, ``Y = lb (sin β0 − sin β) − Δ`` (negative while the lash is open).

    angle          : float  Rocker angle W [rad].
    base_angle     : float  Base-circle rocker angle W0 [rad].
    arm_base_angle : float  Base-circle valve-arm angle β0 [rad].
    valve_arm      : float  Pivot to ball-centre distance lb [m].
    lash           : float  Valve lash Δ [m].
    """
    arm = arm_base_angle - (angle - base_angle)
    return valve_arm * (math.sin(arm_base_angle) - math.sin(arm)) - lash


@jit
def tappet_lift_for_valve_lift(valve_lift, geometry):
    """Tappet lift at the nose (h' = 0) that gives a theoretical valve lift Y [R3], [R6].

    Closed-form inverse of the chain at the nose, used to scale a lift law to a target valve
    lift (physics §3: 7.815 mm of valve lift is about 6.30 mm of tappet lift).

    valve_lift : float     Theoretical valve lift Y [m].
    geometry   : 1-D array Rocker geometry indexed by the ``G_*`` constants [m].
    """
    r0 = geometry[G_BASE_RADIUS]
    rs = geometry[G_PAD_RADIUS]
    la = geometry[G_PAD_ARM]
    lc = geometry[G_CENTRE_DISTANCE]
    lb = geometry[G_VALVE_ARM]
    beta0 = valve_arm_base_angle(
        lb, geometry[G_BALL_RADIUS], geometry[G_STEM_HEIGHT], geometry[G_LASH]
    )
    beta = math.asin(math.sin(beta0) - (valve_lift + geometry[G_LASH]) / lb)
    angle = base_circle_rocker_angle(r0, rs, la, lc) + beta0 - beta
    return math.sqrt(la * la + lc * lc - 2.0 * la * lc * math.cos(angle)) - r0 - rs


@jit
def force_ratio(
    centre_distance, cam_angle_signed, offset_angle, centre_to_pad, valve_arm, arm_angle
):
    """Force ratio i = valve force / cam force from virtual work (physics §3).

    ``i`` = normal velocity of the pad at the contact / valve velocity = ``d/(lb cos β)``,
    where ``d = lc sin(κ + ψ) − R sin ψ`` is the moment arm of the contact normal about O
    (κ = ±K on the pad side).

    centre_distance  : float  Pivot to cam-centre distance lc [m].
    cam_angle_signed : float  Polar angle κ = side·K of A from the line Oc O [rad].
    offset_angle     : float  Pad offset angle ψ [rad].
    centre_to_pad    : float  Cam centre to pad centre R [m].
    valve_arm        : float  Pivot to ball-centre distance lb [m].
    arm_angle        : float  Valve-arm angle β [rad].
    """
    arm = centre_distance * math.sin(cam_angle_signed + offset_angle) - centre_to_pad * math.sin(
        offset_angle
    )
    return arm / (valve_arm * math.cos(arm_angle))


@jit
def _nose_lift(phi, lift, lift_velocity):
    """Tappet lift at φ = 0 by cubic Hermite interpolation of the table [m]."""
    n = phi.shape[0]
    if phi[0] >= 0.0:
        return lift[0]
    for j in range(n - 1):
        if phi[j + 1] >= 0.0:
            width = phi[j + 1] - phi[j]
            return hermite_value(
                lift[j],
                lift_velocity[j],
                lift[j + 1],
                lift_velocity[j + 1],
                width,
                (0.0 - phi[j]) / width,
            )
    return lift[n - 1]


@jit
def rocker_valve_lift(phi, lift, lift_velocity, lift_acceleration, geometry, side, theta, out):
    """Theoretical valve lift, its derivatives, force ratio and rocker angle [R1]–[R6].

    Walks the tappet table, computes ``R, ψ, W, K, φr`` and the exact derivatives
    ``dY/dφr``, ``dW/dφr``, ``dφ/dφr`` at every tappet point (:func:`rocker_walk`), then
    resamples onto ``theta`` with cubic Hermite pieces (:func:`rocker_resample`: values exact at
    the tappet points, error O(Δφ⁴)). The valve acceleration is the central difference of the
    resampled velocity of the unclipped lift, zero while the lash is open (the take-up is a step
    in velocity, not an acceleration that grows as the grid is refined). Outside the mapped range the end values are held (the table should
    start and end on the base circle).

    phi               : 1-D array  Tappet angles φ, increasing, nose at 0 [rad].
    lift              : 1-D array  Flat-tappet lift h(φ) [m].
    lift_velocity     : 1-D array  h' = dh/dφ [m/rad].
    lift_acceleration : 1-D array  h'' [m/rad²].
    geometry          : 1-D array  Rocker geometry indexed by the ``G_*`` constants [m].
    side              : int        ``PAD_AHEAD`` (+1) or ``PAD_BEHIND`` (−1).
    theta             : 1-D array  Output cam rotation angles, increasing, nose at 0 [rad].
    out               : 2-D array  (6, len(theta)) filled with the ``ROW_*`` curves
                                   (units in ``ROCKER_CURVE_UNITS``).

    Returns an int status: ``ROCKER_OK`` or a sum of ``ROCKER_*`` flags (see
    ``ROCKER_STATUS_FLAGS``); the curves are still filled so the caller can report them.
    Reference: physics §3.
    """
    walk = np.empty((N_WALK, phi.shape[0]))
    status = rocker_walk(phi, lift, lift_velocity, lift_acceleration, geometry, side, walk)
    rocker_resample(phi, walk, theta, out)
    return status


@jit
def rocker_walk(phi, lift, lift_velocity, lift_acceleration, geometry, side, walk):
    """The linkage at every tappet point: rows ``W_*`` of ``walk`` (``N_WALK``, len(phi));
    arguments as :func:`rocker_valve_lift`, which it serves. The costly part of a linkage (about
    110 ns a tappet point): made once, it is resampled onto any grid by
    :func:`rocker_resample`. Returns the ``ROCKER_*`` status."""
    r0 = geometry[G_BASE_RADIUS]
    rs = geometry[G_PAD_RADIUS]
    la = geometry[G_PAD_ARM]
    lc = geometry[G_CENTRE_DISTANCE]
    lb = geometry[G_VALVE_ARM]
    lash = geometry[G_LASH]
    n = phi.shape[0]
    status = ROCKER_OK

    base_angle = base_circle_rocker_angle(r0, rs, la, lc)
    arm0 = valve_arm_base_angle(lb, geometry[G_BALL_RADIUS], geometry[G_STEM_HEIGHT], lash)
    nose_angle = cam_centre_angle(la, lc, r0 + rs + _nose_lift(phi, lift, lift_velocity))

    rotation, valve, valve_slope, angle, angle_slope, tappet_slope, ratio = _walk_rows(walk)
    for j in range(n):
        h = lift[j]
        dh = lift_velocity[j]
        ddh = lift_acceleration[j]
        if r0 + h + ddh <= 0.0:
            status |= ROCKER_CONCAVE_CAM
        radial = r0 + rs + h
        big_r = pad_centre_distance(r0, rs, h, dh)
        psi = pad_offset_angle(r0, rs, h, dh)
        w = rocker_angle(la, lc, big_r)
        k = cam_centre_angle(la, lc, big_r)
        if math.isnan(w) or math.isnan(k):
            status |= ROCKER_OUT_OF_REACH
        rotation[j] = phi[j] + psi + side * (k - nose_angle)
        arm = arm0 - (w - base_angle)
        valve[j] = valve_lift_from_rocker_angle(w, base_angle, arm0, lb, lash)
        angle[j] = w
        # pad behind: d with κ = −K is the moment arm of the mirror image's normal with its
        # sign reversed; both forces push either way (i > 0)
        ratio[j] = side * force_ratio(lc, side * k, psi, big_r, lb, arm)

        r_slope = dh * (radial + ddh) / big_r
        psi_slope = (ddh * radial - dh * dh) / (big_r * big_r)
        k_slope = (
            -(big_r * big_r - lc * lc + la * la)
            / (2.0 * lc * big_r * big_r * math.sin(k))
            * r_slope
        )
        w_slope = big_r * r_slope / (la * lc * math.sin(w))
        rotation_slope = 1.0 + psi_slope + side * k_slope
        if not rotation_slope > 0.0:
            status |= ROCKER_NOT_MONOTONE
        tappet_slope[j] = 1.0 / rotation_slope
        angle_slope[j] = w_slope / rotation_slope
        valve_slope[j] = lb * math.cos(arm) * w_slope / rotation_slope
    for j in range(n - 1):
        if not rotation[j + 1] > rotation[j]:
            status |= ROCKER_NOT_MONOTONE
    return status


@jit_inline
def _walk_rows(walk):
    """The rows ``W_ROTATION`` … ``W_RATIO`` of a walk, in that order (views)."""
    return (
        walk[W_ROTATION],
        walk[W_VALVE],
        walk[W_VALVE_SLOPE],
        walk[W_ANGLE],
        walk[W_ANGLE_SLOPE],
        walk[W_TAPPET_SLOPE],
        walk[W_RATIO],
    )


@jit
def rocker_resample(phi, walk, theta, out):
    """The ``ROW_*`` curves of :func:`rocker_valve_lift` on ``theta`` from a :func:`rocker_walk`
    of the tappet points ``phi``."""
    n = phi.shape[0]
    rotation, valve, valve_slope, angle, angle_slope, tappet_slope, ratio = _walk_rows(walk)
    m = theta.shape[0]
    slope = np.empty(m)  # of the unclipped lift
    shut = np.empty(m, dtype=np.bool_)  # the unclipped lift below zero: the lash is open
    j = 0
    for q in range(m):
        t = theta[q]
        while j < n - 2 and rotation[j + 1] <= t:
            j += 1
        if t <= rotation[0] or t >= rotation[n - 1]:
            e = 0 if t <= rotation[0] else n - 1
            y_raw = valve[e]
            y_slope = 0.0
            out[ROW_ROCKER_ANGLE, q] = angle[e]
            out[ROW_FORCE_RATIO, q] = ratio[e]
            out[ROW_TAPPET_ANGLE, q] = phi[e] + (t - rotation[e])
        else:
            width = rotation[j + 1] - rotation[j]
            s = (t - rotation[j]) / width
            y_raw = hermite_value(
                valve[j], valve_slope[j], valve[j + 1], valve_slope[j + 1], width, s
            )
            y_slope = hermite_slope(
                valve[j], valve_slope[j], valve[j + 1], valve_slope[j + 1], width, s
            )
            out[ROW_ROCKER_ANGLE, q] = hermite_value(
                angle[j], angle_slope[j], angle[j + 1], angle_slope[j + 1], width, s
            )
            out[ROW_FORCE_RATIO, q] = ratio[j] + s * (ratio[j + 1] - ratio[j])
            out[ROW_TAPPET_ANGLE, q] = hermite_value(
                phi[j], tappet_slope[j], phi[j + 1], tappet_slope[j + 1], width, s
            )
        out[ROW_VALVE_LIFT, q] = max(0.0, y_raw)
        out[ROW_VALVE_VELOCITY, q] = y_slope if y_raw > 0.0 else 0.0
        slope[q] = y_slope
        shut[q] = y_raw < 0.0
    # The acceleration is that of the unclipped lift, zero while the lash is open: differenced
    # across the lash take-up, the clipped velocity's step (the take-up velocity) made a spike
    # that grew as 1/step.
    _central_difference(theta, slope, out[ROW_VALVE_ACCELERATION])
    for q in range(m):
        if shut[q]:
            out[ROW_VALVE_ACCELERATION, q] = 0.0


@jit
def _central_difference(x, y, dydx):
    """Three-point derivative on a (possibly non-uniform) grid, one-sided at the ends."""
    m = x.shape[0]
    if m < 2:
        dydx[:] = 0.0
        return
    dydx[0] = (y[1] - y[0]) / (x[1] - x[0])
    dydx[m - 1] = (y[m - 1] - y[m - 2]) / (x[m - 1] - x[m - 2])
    for q in range(1, m - 1):
        left = x[q] - x[q - 1]
        right = x[q + 1] - x[q]
        dydx[q] = ((y[q + 1] - y[q]) * left / right + (y[q] - y[q - 1]) * right / left) / (
            left + right
        )
