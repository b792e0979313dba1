"""Declarations of the ``rocker`` scene: parameters, settings, responses and curves.

Defaults are the physics §3 reference valve train (125 cc motorcycle OHC rocker) and a synthetic
convex cam: the §9 six-segment acceleration shape over ±70° cam without a ramp, scaled so that
the theoretical valve lift is 7.815 mm (about 6.30 mm of tappet lift). The segment parameters
are the ``cam`` scene's declarations (12V150 initial design, physics §9). ``source`` on each
parameter says where its default comes from.
"""

from __future__ import annotations

from studies.scenes.base import Curve, CurveAxis, Parameter, Response
from studies.scenes.cam_laws import (
    LAWS,
    ramp_parameters,
    rise_angle_parameter,
    segment_parameters,
)

PHYSICS_3, SYNTHETIC = "physics §3", "synthetic cam (physics §3 suggestion)"
ROCKER_LAWS = tuple(law for law in LAWS if law != "table")
PAD_SIDES = ("ahead", "behind")
# h = H (1 − u²)³ (1 + 2u²), u = θ/β, written in the rise fraction x = 1 + u: the convex law of
# the kernel tests (engine_kernels tests of the rocker and valve models).
CONVEX_POLYDYNE = [0.0, 0.0, 0.0, 24.0, -68.0, 82.0, -51.0, 16.0, -2.0]

_SEGMENTS = segment_parameters()

CAM_LAW_PARAMETERS: tuple[Parameter, ...] = (
    Parameter(
        "law",
        "1",
        "six_segment",
        "flat-tappet lift law of the cam (scaled to the target valve lift)",
        choices=ROCKER_LAWS,
        source=SYNTHETIC,
    ),
    Parameter(
        "valve_lift",
        "mm",
        7.815,
        "theoretical maximum valve lift Y the cam law is scaled to (nose, rigid chain)",
        0.0,
        30.0,
        True,
        source=PHYSICS_3,
    ),
    rise_angle_parameter(150.0, SYNTHETIC),
    *ramp_parameters(0.0, 0.0, 0.0, SYNTHETIC),
    *_SEGMENTS,
    Parameter(
        "polydyne_coefficients",
        "1",
        CONVEX_POLYDYNE,
        "polydyne f(x) = Σ c_k x^k, x = rise fraction (default: h = H (1 − u²)³ (1 + 2u²), "
        "convex over ±80° at 6.30 mm)",
        vector=True,
    ),
)

GEOMETRY_PARAMETERS: tuple[Parameter, ...] = (
    Parameter(
        "base_radius", "mm", 12.5, "cam base-circle radius r0", 0.0, 200.0, True, source=PHYSICS_3
    ),
    Parameter("pad_radius", "mm", 30.0, "rocker pad radius rs", 0.0, 500.0, True, source=PHYSICS_3),
    Parameter(
        "pad_arm",
        "mm",
        39.61,
        "pivot O to pad centre A, la = |OA|",
        0.0,
        500.0,
        True,
        source=PHYSICS_3,
    ),
    Parameter(
        "centre_distance",
        "mm",
        30.28,
        "pivot O to cam centre Oc, lc = |OOc|",
        0.0,
        500.0,
        True,
        source=PHYSICS_3,
    ),
    Parameter(
        "valve_arm",
        "mm",
        33.28,
        "pivot O to adjusting-screw ball centre, lb",
        0.0,
        500.0,
        True,
        source=PHYSICS_3,
    ),
    Parameter(
        "ball_radius", "mm", 10.0, "adjusting-screw ball radius ρb", 0.0, 100.0, source=PHYSICS_3
    ),
    Parameter(
        "stem_height",
        "mm",
        1.65,
        "height z of the valve-stem tip above the pivot",
        -100.0,
        100.0,
        source=PHYSICS_3,
    ),
    Parameter("lash", "mm", 0.05, "valve lash Δ", 0.0, 5.0, source=PHYSICS_3),
    Parameter(
        "pad_side",
        "1",
        "ahead",
        "pad centre A ahead of or behind the line Oc–O in the rotation sense [R4]",
        choices=PAD_SIDES,
        source="assumption",
    ),
)

PARAMETERS = CAM_LAW_PARAMETERS + GEOMETRY_PARAMETERS

TAPPET_STEP = Parameter(
    "tappet_step",
    "degree",
    0.1,
    "tappet-angle grid of the lift law fed to the chain [R1]–[R6] (resampled by cubic "
    "Hermite pieces, error O(step⁴))",
    0.001,
    1.0,
    True,
)
SETTINGS: tuple[Parameter, ...] = (
    Parameter(
        "angle_step",
        "degree",
        0.1,
        "cam-angle grid step of responses and curves (−180 … 180 deg, nose at 0); must "
        "divide 2 deg",
        0.001,
        2.0,
        True,
    ),
    TAPPET_STEP,
)

TAPPET, ROCKER = ("tappet",), ("tappet", "rocker")

RESPONSES: tuple[Response, ...] = (
    Response(
        "max_tappet_lift", "mm", "flat-tappet lift at the nose (scaled to valve_lift)", TAPPET
    ),
    Response(
        "min_radius_of_curvature",
        "mm",
        "minimum cam radius of curvature ρ = r0 + h + h''",
        TAPPET,
        "larger",
    ),
    Response(
        "cam_convex", "1", "cam convex: r0 + h + h'' > 0 everywhere", TAPPET, "larger", flag=True
    ),
    Response("max_valve_lift", "mm", "maximum theoretical valve lift Y (rigid chain)", ROCKER),
    Response(
        "max_valve_velocity", "mm/rad", "largest theoretical valve velocity Y' (opening)", ROCKER
    ),
    Response(
        "min_valve_velocity",
        "mm/rad",
        "most negative theoretical valve velocity Y' (closing)",
        ROCKER,
        "larger",
    ),
    Response("max_valve_acceleration", "mm/rad^2", "largest theoretical valve Y''", ROCKER),
    Response(
        "min_valve_acceleration",
        "mm/rad^2",
        "most negative theoretical valve Y''",
        ROCKER,
        "larger",
    ),
    Response(
        "valve_opening_angle", "degree", "cam angle where the valve opens (lash taken up)", ROCKER
    ),
    Response("valve_closing_angle", "degree", "cam angle where the valve closes", ROCKER),
    Response(
        "valve_open_duration", "degree", "cam angle over which the valve is open", ROCKER, "larger"
    ),
    Response("lift_ratio", "1", "max valve lift / max tappet lift", ROCKER),
    Response(
        "force_ratio_nose", "1", "force ratio i = valve force / cam force at the nose", ROCKER
    ),
    Response("max_force_ratio", "1", "largest force ratio i while the valve is open", ROCKER),
    Response("min_force_ratio", "1", "smallest force ratio i while the valve is open", ROCKER),
    Response("rocker_swing", "degree", "rocker angle range max W − min W", ROCKER),
    Response(
        "chain_status",
        "1",
        "kinematic chain status bits (0: valid)",
        ROCKER,
        bits=("cam_not_convex", "cam_rotation_not_increasing", "out_of_reach"),
    ),
    Response("chain_ok", "1", "kinematic chain valid (status 0)", ROCKER, "larger", flag=True),
)

CURVES: tuple[Curve, ...] = (
    Curve("tappet_lift", "mm", "flat-tappet lift law h at tappet angle = cam angle", TAPPET),
    Curve("valve_lift", "mm", "theoretical valve lift Y", ROCKER),
    Curve("valve_velocity", "mm/rad", "theoretical valve velocity Y' per cam angle", ROCKER),
    Curve("valve_acceleration", "mm/rad^2", "theoretical valve acceleration Y''", ROCKER),
    Curve("force_ratio", "1", "force ratio i = valve force / cam force", ROCKER),
    Curve("rocker_angle", "degree", "rocker angle W between OA and OOc", ROCKER),
    Curve("tappet_angle", "degree", "tappet (lift-table) angle φ in contact", ROCKER),
)

CAM_ANGLE = CurveAxis("cam_angle", "degree", "cam angle from the nose (camshaft, rotation sense)")
