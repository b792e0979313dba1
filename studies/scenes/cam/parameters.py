"""Declarations of the ``cam`` scene: parameters, settings, responses and curves.

Defaults are the 12V150 exhaust cam of physics §9 (initial design) with the stated assumptions for
values the source does not give; ``source`` on each parameter says which is which.
"""

from __future__ import annotations

from studies.scenes.base import Curve, CurveAxis, Parameter, Response
from studies.scenes.cam_laws import (
    LAWS,
    ramp_parameters,
    rise_angle_parameter,
    segment_parameters,
)

SRC, ASSUMED = "12V150 source", "assumption"


PARAMETERS: tuple[Parameter, ...] = (
    Parameter("law", "1", "six_segment", "lift law of the flat-faced tappet", choices=LAWS),
    Parameter(
        "cam_speed",
        "rpm",
        1300.0,
        "camshaft speed (engine speed / 2 for a four-stroke)",
        0.0,
        30000.0,
        True,
        source=SRC,
    ),
    Parameter(
        "base_radius", "mm", 20.5, "cam base-circle radius r0", 0.0, 500.0, True, source=ASSUMED
    ),
    Parameter(
        "lift",
        "mm",
        10.8,
        "rise H of a standard law; working lift the six-segment profile is scaled to "
        "(0 = keep the unscaled profile)",
        0.0,
        100.0,
        source=SRC,
    ),
    rise_angle_parameter(170.0, SRC),
    *ramp_parameters(0.25, 15.0, 1.2, ASSUMED),
    *segment_parameters(),
    Parameter(
        "polydyne_coefficients",
        "1",
        [0.0, 0.0, 0.0, 10.0, -15.0, 6.0],
        "polydyne f(x) = Σ c_k x^k, x = rise fraction (default: the 3-4-5 law)",
        vector=True,
    ),
    Parameter(
        "lift_table",
        "1",
        "",
        "CSV of measured (cam angle [deg], lift [mm]) for law = 'table'",
        text=True,
    ),
    Parameter(
        "cam_width", "mm", 20.0, "cam (contact line) width b", 0.0, 500.0, True, source=ASSUMED
    ),
    Parameter(
        "cam_modulus", "GPa", 210.0, "Young's modulus of the cam", 0.0, 2000.0, True, source=ASSUMED
    ),
    Parameter("cam_poisson", "1", 0.3, "Poisson's ratio of the cam", 0.0, 0.5, source=ASSUMED),
    Parameter(
        "tappet_modulus",
        "GPa",
        210.0,
        "Young's modulus of the tappet",
        0.0,
        2000.0,
        True,
        source=ASSUMED,
    ),
    Parameter(
        "tappet_poisson", "1", 0.3, "Poisson's ratio of the tappet", 0.0, 0.5, source=ASSUMED
    ),
    Parameter(
        "spring_preload",
        "N",
        400.0,
        "valve-spring preload Ps0 on the tappet axis",
        0.0,
        1e5,
        source=ASSUMED,
    ),
    Parameter(
        "spring_rate",
        "N/mm",
        40.0,
        "valve-spring rate ks on the tappet axis",
        0.0,
        1e4,
        source=ASSUMED,
    ),
    Parameter(
        "equivalent_mass",
        "kg",
        0.3,
        "equivalent reciprocating mass on the tappet axis",
        0.0,
        100.0,
        source=ASSUMED,
    ),
    Parameter(
        "oil_viscosity",
        "mPa*s",
        10.0,
        "dynamic viscosity of the oil at the contact",
        0.0,
        1e4,
        True,
        source=ASSUMED,
    ),
    Parameter(
        "pressure_viscosity",
        "1/GPa",
        20.0,
        "pressure-viscosity coefficient α",
        0.0,
        100.0,
        source=ASSUMED,
    ),
    Parameter(
        "nose_window",
        "degree",
        30.0,
        "half-width of the nose window for N and film",
        0.0,
        180.0,
        True,
        source=SRC,
    ),
    Parameter(
        "min_radius_limit",
        "mm",
        3.0,
        "smallest allowed radius of curvature",
        0.0,
        100.0,
        source="physics §2",
    ),
    Parameter(
        "stress_limit",
        "MPa",
        600.0,
        "allowed Hertz stress (carbon-steel cam, flat tappet)",
        0.0,
        1e4,
        True,
        source="physics §2",
    ),
    Parameter(
        "spring_margin_limit",
        "1",
        1.2,
        "smallest allowed spring margin",
        0.0,
        100.0,
        source="physics §2",
    ),
    Parameter(
        "jerk_limit",
        "mm/rad^3",
        1000.0,
        "largest allowed jerk over the working part",
        0.0,
        1e7,
        True,
        source="physics §2",
    ),
    Parameter(
        "fullness_limit",
        "1",
        0.55,
        "smallest wanted fullness coefficient",
        0.0,
        1.0,
        source="physics §2",
    ),
)

SETTINGS: tuple[Parameter, ...] = (
    Parameter(
        "angle_step",
        "degree",
        0.1,
        "cam-angle grid step (−180 … 180 deg, nose at 0)",
        0.001,
        5.0,
        True,
    ),
    Parameter(
        "table_smoothing",
        "mm",
        0.005,
        "measured tables: allowed RMS lift residual of the smoothing spline (0 = "
        "interpolate, no smoothing)",
        0.0,
        10.0,
    ),
)

KIN, GEO, LOAD = ("kinematics",), ("kinematics", "geometry"), ("kinematics", "geometry", "loads")

RESPONSES: tuple[Response, ...] = (
    Response("max_lift", "mm", "maximum tappet lift", KIN, "larger"),
    Response("face_half_width", "mm", "required tappet face half-width max|h'|", KIN),
    Response("max_acceleration", "mm/rad^2", "largest tappet acceleration h''", KIN),
    Response(
        "min_acceleration", "mm/rad^2", "most negative tappet acceleration h''", KIN, "larger"
    ),
    Response("max_acceleration_time", "m/s^2", "largest |tappet acceleration| at cam speed", KIN),
    Response("max_jerk", "mm/rad^3", "maximum |jerk| over the working part", KIN),
    Response("jerk_margin", "mm/rad^3", "jerk limit − max jerk", KIN, "larger"),
    Response("jerk_ok", "1", "max jerk below the limit", KIN, "larger", flag=True),
    Response(
        "fullness",
        "1",
        "fullness ∫h dθ / (h_max · event) over the working part (above "
        "the ramps), as the 12V150 source evaluates it",
        KIN,
        "larger",
    ),
    Response("event_fullness", "1", "fullness over the whole event, ramps included", KIN, "larger"),
    Response("fullness_ok", "1", "fullness at least the wanted value", KIN, "larger", flag=True),
    Response("working_lift_unscaled", "mm", "six-segment working lift before scaling", KIN),
    Response("fillet_monotone", "1", "fillet segment free of overshoot", KIN, "larger", flag=True),
    Response("ramp_feasible", "1", "ramp geometry feasible", KIN, "larger", flag=True),
    Response(
        "min_radius_of_curvature",
        "mm",
        "minimum radius of curvature ρ = r0 + h + h''",
        GEO,
        "larger",
    ),
    Response("radius_margin", "mm", "min ρ − radius limit", GEO, "larger"),
    Response(
        "radius_ok", "1", "cam convex with ρ above the limit everywhere", GEO, "larger", flag=True
    ),
    Response(
        "max_lubrication_coefficient_nose",
        "1",
        "maximum lubrication coefficient N within the nose window",
        GEO,
        "larger",
    ),
    Response(
        "min_lubrication_coefficient_nose",
        "1",
        "minimum lubrication coefficient N within the nose window",
        GEO,
        "larger",
    ),
    Response(
        "min_relative_film_thickness_nose",
        "1",
        "minimum relative film thickness h̄ within the nose window",
        GEO,
        "larger",
    ),
    Response("max_entrainment_velocity", "m/s", "maximum |entrainment velocity|", GEO, "larger"),
    Response("max_contact_force", "N", "maximum cam–tappet contact force", LOAD),
    Response(
        "min_contact_force",
        "N",
        "minimum contact force (≤ 0: the tappet lifts off)",
        LOAD,
        "larger",
    ),
    Response(
        "max_contact_stress",
        "MPa",
        "maximum Hertz line-contact stress (inf where the cam is not convex, ρ ≤ 0)",
        LOAD,
    ),
    Response(
        "stress_margin",
        "MPa",
        "stress limit − max contact stress (−inf where the cam is not convex)",
        LOAD,
        "larger",
    ),
    Response("stress_ok", "1", "contact stress within the limit", LOAD, "larger", flag=True),
    Response(
        "spring_margin", "1", "min spring force / inertia force where h'' < 0", LOAD, "larger"
    ),
    Response("spring_margin_ok", "1", "spring margin above the limit", LOAD, "larger", flag=True),
    Response(
        "min_film_thickness_nose",
        "um",
        "minimum Dowson–Higginson film thickness within the nose window",
        LOAD,
        "larger",
    ),
)

CURVES: tuple[Curve, ...] = (
    Curve("lift", "mm", "tappet lift h", KIN),
    Curve("velocity", "mm/rad", "tappet velocity h' per cam angle", KIN),
    Curve("acceleration", "mm/rad^2", "tappet acceleration h'' per cam angle", KIN),
    Curve("jerk", "mm/rad^3", "tappet jerk h''' per cam angle", KIN),
    Curve("radius_of_curvature", "mm", "cam radius of curvature ρ", GEO),
    Curve("lubrication_coefficient", "1", "lubrication coefficient N", GEO),
    Curve("entrainment_velocity", "m/s", "entrainment velocity u_e", GEO),
    Curve("relative_film_thickness", "1", "relative film thickness h̄", GEO),
    Curve("contact_force", "N", "cam–tappet contact force", LOAD),
    Curve("contact_stress", "MPa", "Hertz contact stress", LOAD),
    Curve("film_thickness", "um", "Dowson–Higginson minimum film thickness", LOAD),
)

CAM_ANGLE = CurveAxis("cam_angle", "degree", "cam angle from the nose (camshaft)")
