"""Cam geometry and load batch drivers of the `cam` scene: curvature, lubrication, contact (physics §2).

Drivers 3 and 4 of :mod:`engine_kernels.cam.kinematics` (which holds the parameter columns
P_*), one design case per ``prange`` iteration, from the kinematic curves it computed:

3. ``cam_geometry_batch``  curvature, lubrication coefficient, entrainment (columns G_*, GC_*);
4. ``cam_loads_batch``     contact force, Hertz stress, spring margin, EHL film (L_*, LC_*).

Design criteria come out as margins and 1.0/0.0 flags: a concave or cusped cam gives a negative
minimum radius, infinite stress and flags 0 — numbers, never an exception.
"""

from __future__ import annotations

import math

import numpy as np

from engine_kernels._jit import batch, prange
from engine_kernels.cam.contact import (
    contact_force,
    effective_modulus,
    entrainment_velocity,
    film_thickness_dowson_higginson,
    hertz_line_contact_stress,
    lubrication_coefficient,
    radius_of_curvature,
    relative_film_thickness,
    spring_margin,
)
from engine_kernels.cam.kinematics import (
    P_BASE_RADIUS,
    P_CAM_SPEED,
    P_CAM_WIDTH,
    P_E1,
    P_E2,
    P_EQUIVALENT_MASS,
    P_MIN_RADIUS_LIMIT,
    P_NOSE_WINDOW,
    P_NU1,
    P_NU2,
    P_PRESSURE_VISCOSITY,
    P_SPRING_MARGIN_LIMIT,
    P_SPRING_PRELOAD,
    P_SPRING_RATE,
    P_STRESS_LIMIT,
    P_VISCOSITY,
    invalid_case,
    nose_index,
)

G_MIN_RADIUS = 0
G_RADIUS_MARGIN = 1
G_RADIUS_OK = 2
G_MAX_LUBRICATION = 3
G_MIN_LUBRICATION = 4
G_MIN_FILM_RATIO = 5
G_MAX_ENTRAINMENT = 6
N_GEO = 7
GEOMETRY_NAMES = (
    "min_radius",
    "radius_margin",
    "radius_ok",
    "max_lubrication_coefficient",
    "min_lubrication_coefficient",
    "min_relative_film_thickness",
    "max_entrainment_velocity",
)
GEOMETRY_UNITS = ("m", "m", "1", "1", "1", "1", "m/s")
"""radius_margin = min rho - limit, radius_ok = margin > 0; the lubrication coefficient and
relative film thickness are taken within ±nose_window of the nose."""
GC_RADIUS = 0
GC_LUBRICATION = 1
GC_ENTRAINMENT = 2
GC_FILM_RATIO = 3
N_GEO_CURVES = 4
GEOMETRY_CURVE_NAMES = (
    "radius_of_curvature",
    "lubrication_coefficient",
    "entrainment_velocity",
    "relative_film_thickness",
)
GEOMETRY_CURVE_UNITS = ("m", "1", "m/s", "1")

L_MAX_FORCE = 0
L_MIN_FORCE = 1
L_MAX_STRESS = 2
L_STRESS_MARGIN = 3
L_STRESS_OK = 4
L_SPRING_MARGIN = 5
L_SPRING_OK = 6
L_MIN_FILM = 7
N_LOAD = 8
LOAD_NAMES = (
    "max_contact_force",
    "min_contact_force",
    "max_contact_stress",
    "stress_margin",
    "stress_ok",
    "spring_margin",
    "spring_ok",
    "min_film_thickness",
)
LOAD_UNITS = ("N", "N", "Pa", "Pa", "1", "1", "1", "m")
"""stress_margin = limit - max stress, stress_ok = margin ≥ 0; spring_ok = margin > limit;
min_film_thickness (Dowson-Higginson) within ±nose_window of the nose."""
LC_FORCE = 0
LC_STRESS = 1
LC_FILM = 2
N_LOAD_CURVES = 3
LOAD_CURVE_NAMES = ("contact_force", "contact_stress", "film_thickness")
LOAD_CURVE_UNITS = ("N", "Pa", "m")


@batch
def cam_geometry_batch(params, theta, curves, out, curves_out):
    """Curvature and lubrication responses per case ([C1]-[C4]).

    params    : array  (n, N_PARAMS) case parameters, SI.
    theta     : array  (m,) cam angles from the nose [rad].
    curves    : array  (n, 4, m) lift curves from ``cam_kinematics_batch``.
    out       : array  (n, N_GEO) output, columns GEOMETRY_NAMES (units GEOMETRY_UNITS).
    curves_out: array  (n, 4, m) output radius of curvature [m], lubrication coefficient [-],
                       entrainment velocity [m/s], relative film thickness [-]; last
                       dimension 0 to skip.

    The nose window is |θ| ≤ P_NOSE_WINDOW, or the grid point nearest the nose if it holds
    none.
    """
    nose = nose_index(theta)
    store = curves_out.shape[2] > 0
    for i in prange(params.shape[0]):
        if invalid_case(curves, i):
            out[i, :] = np.nan
            if store:
                curves_out[i, :, :] = np.nan
            continue
        speed = params[i, P_CAM_SPEED]
        r0 = params[i, P_BASE_RADIUS]
        window = params[i, P_NOSE_WINDOW]
        min_radius = math.inf
        max_lub = -math.inf
        min_lub = math.inf
        min_film = math.inf
        max_entrain = 0.0
        for j in range(theta.shape[0]):
            h = curves[i, 0, j]
            h2 = curves[i, 2, j]
            rho = radius_of_curvature(r0, h, h2)
            lub = lubrication_coefficient(r0, h, h2)
            entrain = entrainment_velocity(speed, r0, h, h2)
            film = relative_film_thickness(lub)
            min_radius = min(min_radius, rho)
            max_entrain = max(max_entrain, abs(entrain))
            if abs(theta[j]) <= window or j == nose:
                max_lub = max(max_lub, lub)
                min_lub = min(min_lub, lub)
                min_film = min(min_film, film)
            if store:
                curves_out[i, GC_RADIUS, j] = rho
                curves_out[i, GC_LUBRICATION, j] = lub
                curves_out[i, GC_ENTRAINMENT, j] = entrain
                curves_out[i, GC_FILM_RATIO, j] = film
        margin = min_radius - params[i, P_MIN_RADIUS_LIMIT]
        out[i, G_MIN_RADIUS] = min_radius
        out[i, G_RADIUS_MARGIN] = margin
        out[i, G_RADIUS_OK] = 1.0 if margin > 0.0 else 0.0
        out[i, G_MAX_LUBRICATION] = max_lub
        out[i, G_MIN_LUBRICATION] = min_lub
        out[i, G_MIN_FILM_RATIO] = min_film
        out[i, G_MAX_ENTRAINMENT] = max_entrain


@batch
def cam_loads_batch(params, theta, curves, out, curves_out):
    """Contact-load responses per case (physics §2, [C5]).

    params    : array  (n, N_PARAMS) case parameters, SI.
    theta     : array  (m,) cam angles from the nose [rad].
    curves    : array  (n, 4, m) lift curves from ``cam_kinematics_batch``.
    out       : array  (n, N_LOAD) output, columns LOAD_NAMES (units LOAD_UNITS).
    curves_out: array  (n, 3, m) output contact force [N], Hertz stress [Pa], minimum film
                       thickness [m]; last dimension 0 to skip.

    A cam that is not convex (radius of curvature ≤ 0 anywhere, loaded or not: a flat tappet
    cannot follow it, [C1]) gives max stress +inf, stress margin -inf and stress_ok 0; where
    it is loaded its film thickness is 0 (see ``film_thickness_dowson_higginson``). The stress
    curve stays pointwise (0 where the tappet lifts off).
    """
    nose = nose_index(theta)
    store = curves_out.shape[2] > 0
    for i in prange(params.shape[0]):
        if invalid_case(curves, i):
            out[i, :] = np.nan
            if store:
                curves_out[i, :, :] = np.nan
            continue
        speed = params[i, P_CAM_SPEED]
        r0 = params[i, P_BASE_RADIUS]
        width = params[i, P_CAM_WIDTH]
        preload = params[i, P_SPRING_PRELOAD]
        rate = params[i, P_SPRING_RATE]
        mass = params[i, P_EQUIVALENT_MASS]
        window = params[i, P_NOSE_WINDOW]
        modulus = effective_modulus(
            params[i, P_E1], params[i, P_NU1], params[i, P_E2], params[i, P_NU2]
        )
        max_force = -math.inf
        min_force = math.inf
        max_stress = 0.0
        min_film = math.inf
        convex = True
        for j in range(theta.shape[0]):
            h = curves[i, 0, j]
            h2 = curves[i, 2, j]
            rho = radius_of_curvature(r0, h, h2)
            convex = convex and rho > 0.0
            force = contact_force(preload, rate, mass, speed, h, h2)
            stress = hertz_line_contact_stress(force, modulus, width, rho)
            max_force = max(max_force, force)
            min_force = min(min_force, force)
            max_stress = max(max_stress, stress)
            in_window = abs(theta[j]) <= window or j == nose
            if in_window or store:
                film = film_thickness_dowson_higginson(
                    rho,
                    entrainment_velocity(speed, r0, h, h2),
                    force / width,
                    params[i, P_VISCOSITY],
                    params[i, P_PRESSURE_VISCOSITY],
                    modulus,
                )
                if in_window:
                    min_film = min(min_film, film)
                if store:
                    curves_out[i, LC_FORCE, j] = force
                    curves_out[i, LC_STRESS, j] = stress
                    curves_out[i, LC_FILM, j] = film
        margin = spring_margin(curves[i, 0], curves[i, 2], preload, rate, mass, speed)
        if not convex:
            max_stress = math.inf
        stress_margin = params[i, P_STRESS_LIMIT] - max_stress
        out[i, L_MAX_FORCE] = max_force
        out[i, L_MIN_FORCE] = min_force
        out[i, L_MAX_STRESS] = max_stress
        out[i, L_STRESS_MARGIN] = stress_margin
        out[i, L_STRESS_OK] = 1.0 if stress_margin >= 0.0 else 0.0
        out[i, L_SPRING_MARGIN] = margin
        out[i, L_SPRING_OK] = 1.0 if margin > params[i, P_SPRING_MARGIN_LIMIT] else 0.0
        out[i, L_MIN_FILM] = min_film
