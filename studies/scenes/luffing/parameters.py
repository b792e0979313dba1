"""Declarations of the ``luffing`` scene: parameters and responses (physics §7).

Defaults are the physics §7 reference inputs; the values the source does not give are stated
assumptions (the same as tests/engine_kernels/test_luffing.py): a servo catalogue of 50…750 W,
coupling factors Kw = 1, K = 1.5, Kz = Kt = 1 and a 5 N·m coupling, allowable tube deflection
span/250 and end slope 0.01 rad, a 3 × 3 key (k = 1.5 mm, l = 14 mm) on an 8 mm shaft with
100 MPa allowed, a 6001 deep-groove ball bearing (C = 5.1 kN) for 20 000 h.

Every check is reported as value, limit and pass flag (``*_ok``); see
:mod:`engine_kernels.luffing.sizing` for the choices the physics reference leaves open.
"""

from __future__ import annotations

from studies.scenes.base import Parameter, Response

SRC, ASSUMED = "physics §7", "assumption"
BEARINGS = ("ball", "roller")

PARAMETERS: tuple[Parameter, ...] = (
    Parameter(
        "trolley_acceleration", "m/s^2", 20.0, "trolley acceleration a", 0.0, 1e4, source=SRC
    ),
    Parameter(
        "trolley_mass", "kg", 5.0, "moved mass m (trolley + payload)", 0.0, 1e6, True, source=SRC
    ),
    Parameter("damping_coefficient", "N*s/m", 0.2, "damping coefficient C", 0.0, 1e6, source=SRC),
    Parameter(
        "trolley_speed", "m/s", 0.5, "trolley (= belt) speed V", 0.0, 100.0, True, source=SRC
    ),
    Parameter("friction_coefficient", "1", 0.2, "friction coefficient μ", 0.0, 10.0, source=SRC),
    Parameter(
        "gravity",
        "m/s^2",
        10.0,
        "gravitational acceleration g (the source uses 10)",
        0.0,
        100.0,
        True,
        source=SRC,
    ),
    Parameter(
        "work_efficiency",
        "1",
        0.96,
        "efficiency of the working mechanism ηw",
        0.0,
        1.0,
        True,
        source=SRC,
    ),
    Parameter("coupling_efficiency", "1", 0.99, "coupling efficiency", 0.0, 1.0, True, source=SRC),
    Parameter("belt_efficiency", "1", 0.98, "timing-belt efficiency", 0.0, 1.0, True, source=SRC),
    Parameter("bearing_efficiency", "1", 0.98, "bearing efficiency", 0.0, 1.0, True, source=SRC),
    Parameter("motor_speed", "rpm", 2000.0, "rated motor speed", 0.0, 1e5, True, source=SRC),
    Parameter(
        "motor_ratings",
        "W",
        [50.0, 100.0, 200.0, 400.0, 750.0],
        "rated powers of the available motors, ascending (the source picks 100 W)",
        0.0,
        1e8,  # the largest electric motors built are rated ~100 MW
        True,
        vector=True,
        source=ASSUMED,
    ),
    Parameter("service_factor", "1", 1.2, "belt service factor KA", 0.0, 10.0, True, source=SRC),
    Parameter("belt_pitch", "mm", 12.7, "timing-belt pitch p", 0.0, 1000.0, True, source=SRC),
    Parameter(
        "pulley_teeth", "1", 20.0, "pulley teeth Z", 0.0, 1000.0, True, source=SRC, integer=True
    ),
    Parameter(
        "belt_ratio",
        "1",
        1.0,
        "belt transmission ratio as built (1:1)",
        0.0,
        1000.0,
        True,
        source=SRC,
    ),
    Parameter(
        "ratio_tolerance",
        "1",
        0.05,
        "allowed relative deviation of the implied ratio from the belt ratio",
        0.0,
        10.0,
        source=ASSUMED,
    ),
    Parameter(
        "coupling_kw", "1", 1.0, "coupling power-machine factor Kw", 0.0, 10.0, True, source=ASSUMED
    ),
    Parameter(
        "coupling_k", "1", 1.5, "coupling working-machine factor K", 0.0, 10.0, True, source=ASSUMED
    ),
    Parameter(
        "coupling_kz",
        "1",
        1.0,
        "coupling start-frequency factor Kz",
        0.0,
        10.0,
        True,
        source=ASSUMED,
    ),
    Parameter(
        "coupling_kt", "1", 1.0, "coupling temperature factor Kt", 0.0, 10.0, True, source=ASSUMED
    ),
    Parameter(
        "coupling_rated_torque",
        "N*m",
        5.0,
        "rated torque of the coupling",
        0.0,
        1e6,
        True,
        source=ASSUMED,
    ),
    Parameter(
        "tube_outer_diameter",
        "mm",
        16.0,
        "guide-tube outer diameter D",
        0.0,
        1000.0,
        True,
        source=SRC,
    ),
    Parameter(
        "tube_inner_diameter", "mm", 8.0, "guide-tube inner diameter d", 0.0, 1000.0, source=SRC
    ),
    Parameter("tube_span", "mm", 1467.0, "guide-tube span l", 0.0, 1e5, True, source=SRC),
    Parameter("tube_load", "N", 40.0, "load F at mid-span of the guide tube", 0.0, 1e7, source=SRC),
    Parameter(
        "tube_weight", "N", 13.6, "guide-tube weight G (taken at mid-span)", 0.0, 1e7, source=SRC
    ),
    Parameter(
        "tube_modulus", "GPa", 206.0, "Young's modulus E of the tube", 0.0, 2000.0, True, source=SRC
    ),
    Parameter(
        "allowable_deflection",
        "mm",
        1467.0 / 250.0,
        "allowed mid-span deflection (default: the default span/250; it does not follow tube_span)",
        0.0,
        1e4,
        True,
        source=ASSUMED,
    ),
    Parameter(
        "allowable_slope",
        "rad",
        0.01,
        "allowed end slope of the tube",
        0.0,
        1.0,
        True,
        source=ASSUMED,
    ),
    Parameter(
        "key_contact_height",
        "mm",
        1.5,
        "key height in contact with the hub k",
        0.0,
        100.0,
        True,
        source=ASSUMED,
    ),
    Parameter(
        "key_length", "mm", 14.0, "working length of the key l", 0.0, 1000.0, True, source=ASSUMED
    ),
    Parameter(
        "key_shaft_diameter",
        "mm",
        8.0,
        "shaft diameter at the key d",
        0.0,
        1000.0,
        True,
        source=ASSUMED,
    ),
    Parameter(
        "allowable_crushing_stress",
        "MPa",
        100.0,
        "allowed key crushing stress",
        0.0,
        1e4,
        True,
        source=ASSUMED,
    ),
    Parameter(
        "bearing_rating",
        "kN",
        5.1,
        "dynamic load rating C of the pulley bearing",
        0.0,
        1e5,
        True,
        source=ASSUMED,
    ),
    Parameter(
        "bearing_type",
        "1",
        "ball",
        "bearing type (life exponent 3 ball, 10/3 roller)",
        choices=BEARINGS,
        source=ASSUMED,
    ),
    Parameter(
        "required_bearing_life",
        "h",
        20000.0,
        "required basic rating life L10h",
        0.0,
        1e7,
        True,
        source=ASSUMED,
    ),
)

NEEDS = ("sizing",)
NO_MOTOR = " (−1, not evaluated, where no listed motor covers the required power: motor_ok 0)"

# (name, units, long name, sense); checks come as value, limit, flag in the kernel's order.
_VALUES = (
    ("resistance", "N", "travel resistance Fw = a m + C V + μ m g", "smaller"),
    ("work_power", "W", "work power Pw = Fw V/ηw", "smaller"),
    ("drive_efficiency", "1", "drive efficiency η", "larger"),
    ("motor_power", "W", "required motor power P0 = Pw/η", "smaller"),
    ("motor_rated_power", "W", "rated power of the selected motor (the limit)", "smaller"),
    ("motor_ok", "1", "a listed motor covers the required power", "larger"),
    ("selected_motor", "1", "index of the selected motor in motor_ratings (1-based)", "smaller"),
    ("belt_design_power", "W", "belt design power Pd = KA P", "smaller"),
    ("pulley_diameter", "mm", "pulley pitch diameter d = p Z/π", "smaller"),
    ("shaft_load", "N", "shaft load Fr = Pd/V", "smaller"),
    ("implied_ratio", "1", "reduction ratio the speeds need, ω_motor d/(2V)", "smaller"),
    ("belt_ratio", "1", "belt ratio as built (the limit)", "smaller"),
    ("ratio_ok", "1", "implied ratio equals the belt ratio within the tolerance", "larger"),
    ("coupling_torque", "N*m", "coupling design torque Tc", "smaller"),
    ("coupling_limit", "N*m", "coupling rated torque (the limit)", "smaller"),
    ("coupling_ok", "1", f"coupling torque within its rating{NO_MOTOR}", "larger"),
    ("tube_second_moment", "mm^4", "tube second moment of area I", "larger"),
    ("deflection", "mm", "guide-tube mid-span deflection", "smaller"),
    ("deflection_limit", "mm", "allowed deflection (the limit)", "smaller"),
    ("deflection_ok", "1", "deflection within the limit", "larger"),
    ("slope", "rad", "guide-tube end slope", "smaller"),
    ("slope_limit", "rad", "allowed slope (the limit)", "smaller"),
    ("slope_ok", "1", "slope within the limit", "larger"),
    ("key_stress", "MPa", "key crushing stress σp = 2T/(k l d)", "smaller"),
    ("key_limit", "MPa", "allowed crushing stress (the limit)", "smaller"),
    ("key_ok", "1", f"key stress within the limit{NO_MOTOR}", "larger"),
    (
        "bearing_life",
        "h",
        "bearing basic rating life L10h (pulley shaft at motor speed/belt_ratio, load Fr)",
        "larger",
    ),
    ("bearing_limit", "h", "required bearing life (the limit)", "larger"),
    ("bearing_ok", "1", f"bearing life at least the required life{NO_MOTOR}", "larger"),
)
KERNEL_NAMES = tuple(name for name, *_ in _VALUES)
"""Response names in the column order of :data:`engine_kernels.luffing.sizing.OUTPUTS`."""
CHECKS = ("motor", "ratio", "coupling", "deflection", "slope", "key", "bearing")
"""The design checks, each with an ``<check>_ok`` flag response."""

RESPONSES: tuple[Response, ...] = (
    *(
        Response(name, units, long_name, NEEDS, sense, flag=name.endswith("_ok"))
        for name, units, long_name, sense in _VALUES
    ),
    Response(
        "checks_passed", "1", f"number of the {len(CHECKS)} checks that pass", NEEDS, "larger"
    ),
    Response(
        "all_checks_ok",
        "1",
        "every check passes (0 once one fails, −1 where none fails but one is not evaluated)",
        NEEDS,
        "larger",
        flag=True,
    ),
)
