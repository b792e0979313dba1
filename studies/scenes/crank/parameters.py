"""Declarations of the ``crank`` scene: parameters and settings (responses and curves in
:mod:`studies.scenes.crank.responses`).

Defaults are the 12V150 diesel of physics §5 (12 cylinders, V 90°, bore 150 mm, 2600 rpm, 23 MPa,
firing order 1-12-9-4-5-8-11-2-3-10-7-6). The source gives no stroke: 180 mm is the physics reference's
stated assumption. λ, the masses and the single-zone cycle are our assumptions (the values of
tests/engine_kernels/test_crank.py); ``source`` on each parameter says which is which.
"""

from __future__ import annotations

from studies.scenes.base import Parameter

SRC, ASSUMED = "12V150 source (physics §5)", "assumption"
STROKE_SOURCE = "assumption: the 12V150 source gives no stroke; 180 mm is the physics §5 assumption"
FIRING_ORDER_12V150 = [1, 12, 9, 4, 5, 8, 11, 2, 3, 10, 7, 6]

LAYOUTS = ("inline", "v")
FIRINGS = ("even", "shared_crankpins", "given")
PRESSURE_MODELS = ("cycle", "table")
HEAT_INPUTS = ("max_pressure", "cycle_heat")
MODELS = ("exact", "approximate")
MAX_ORDER_HALVES = 24
"""Torque harmonics reported: engine orders 0.5, 1, …, 12 (harmonic q of the 720° cycle)."""

PARAMETERS: tuple[Parameter, ...] = (
    Parameter("engine_speed", "rpm", 2600.0, "crankshaft speed n", 0.0, 30000.0, True, source=SRC),
    Parameter(
        "stroke",
        "mm",
        180.0,
        "stroke S = 2r (12V150: not in the source, 180 mm is an assumption)",
        0.0,
        5000.0,
        True,
        source=STROKE_SOURCE,
    ),
    Parameter(
        "rod_ratio",
        "1",
        0.28,
        "crank radius over rod length λ = r/l (must be < 1)",
        0.0,
        None,
        True,
        source=ASSUMED,
    ),
    Parameter("bore", "mm", 150.0, "cylinder bore D", 0.0, 5000.0, True, source=SRC),
    Parameter(
        "reciprocating_mass",
        "kg",
        3.5,
        "reciprocating mass mj per cylinder (piston group + rod small-end share)",
        0.0,
        1e5,
        source=ASSUMED,
    ),
    Parameter(
        "rotating_mass",
        "kg",
        3.0,
        "rotating mass mr per crank throw (crank + rod big-end share)",
        0.0,
        1e5,
        source=ASSUMED,
    ),
    Parameter(
        "crankcase_pressure",
        "kPa",
        101.325,
        "crankcase pressure p0 under the piston",
        0.0,
        1e5,
        source="physics §5 (≈ 1 atm)",
    ),
    Parameter("layout", "1", "v", "cylinder layout", choices=LAYOUTS, source=SRC),
    Parameter(
        "cylinders",
        "1",
        12.0,
        "number of cylinders z (a whole number)",
        1.0,
        64.0,
        source=SRC,
        integer=True,
    ),
    Parameter(
        "cylinder_pitch",
        "mm",
        180.0,
        "axial distance between neighbouring cylinders of an inline layout (free moments)",
        0.0,
        5000.0,
        True,
        source="assumption: 1.2 × bore, typical of 1.15–1.3 × bore",
    ),
    Parameter(
        "cylinder_positions",
        "mm",
        [],
        "axial position of cylinder 1, 2, …, z along the crankshaft (free moments of any "
        "layout; empty: inline cylinders every cylinder_pitch, V layouts none)",
        vector=True,
    ),
    Parameter(
        "bank_angle",
        "degree",
        90.0,
        "angle γ between the banks of a V engine",
        0.0,
        180.0,
        True,
        source=SRC,
    ),
    Parameter(
        "firing_order",
        "1",
        FIRING_ORDER_12V150,
        "cylinder numbers in firing order (every cylinder 1…z exactly once)",
        vector=True,
        source=SRC,
    ),
    Parameter(
        "firing",
        "1",
        "even",
        "firing angles: 'even' = 720°/z in firing order; 'shared_crankpins' = V engine with "
        "two rods per throw (even only when γ = 720°/z); 'given' = firing_angles",
        choices=FIRINGS,
        source="physics §5 (even firing by default)",
    ),
    Parameter(
        "firing_angles",
        "degree",
        [],
        "crank angle (0–720°) at which cylinder 1, 2, …, z fires (firing = 'given')",
        vector=True,
    ),
    Parameter(
        "pressure_model",
        "1",
        "cycle",
        "cylinder pressure: parametric single-zone 'cycle' or a measured 'table'",
        choices=PRESSURE_MODELS,
    ),
    Parameter(
        "pressure_table",
        "1",
        "",
        "CSV of crank angle [deg] (firing TDC at 0) and pressure [MPa] for "
        "pressure_model = 'table' (path relative to the working directory)",
        text=True,
    ),
    Parameter(
        "compression_ratio", "1", 14.0, "compression ratio ε", 1.0, 100.0, True, source=ASSUMED
    ),
    Parameter(
        "intake_pressure",
        "kPa",
        300.0,
        "cylinder pressure at inlet closing (BDC)",
        0.0,
        1e5,
        True,
        source=ASSUMED,
    ),
    Parameter(
        "exhaust_pressure",
        "kPa",
        250.0,
        "cylinder pressure during the exhaust stroke",
        0.0,
        1e5,
        True,
        source=ASSUMED,
    ),
    Parameter(
        "polytropic_exponent",
        "1",
        1.35,
        "polytropic exponent k of compression and expansion",
        1.0,
        2.0,
        True,
        source=ASSUMED,
    ),
    Parameter(
        "combustion_start",
        "degree",
        -15.0,
        "start of heat release after firing TDC (negative = before TDC)",
        -180.0,
        180.0,
        source=ASSUMED,
    ),
    Parameter(
        "combustion_duration",
        "degree",
        50.0,
        "heat-release duration",
        0.0,
        360.0,
        True,
        source=ASSUMED,
    ),
    Parameter(
        "wiebe_efficiency",
        "1",
        6.908,
        "Wiebe efficiency parameter a",
        0.0,
        100.0,
        True,
        source="Heywood (2018) §9.2",
    ),
    Parameter("wiebe_form", "1", 1.0, "Wiebe form factor m", 0.0, 10.0, source=ASSUMED),
    Parameter(
        "heat_input",
        "1",
        "max_pressure",
        "heat input of the cycle: from the target 'max_pressure' or from 'cycle_heat'",
        choices=HEAT_INPUTS,
    ),
    Parameter(
        "max_pressure",
        "MPa",
        23.0,
        "maximum combustion pressure (target of the cycle)",
        0.0,
        1000.0,
        True,
        source=SRC,
    ),
    Parameter(
        "cycle_heat",
        "kJ",
        12.0,
        "heat released per cycle and cylinder (heat_input = 'cycle_heat')",
        0.0,
        1e4,
        source=ASSUMED,
    ),
)

SETTINGS: tuple[Parameter, ...] = (
    Parameter(
        "model",
        "1",
        "exact",
        "piston kinematics: 'exact' [K1] or two-term "
        "'approximate' [K2]–[K4] (inertia forces, torque, kinematic curves)",
        choices=MODELS,
    ),
    Parameter(
        "angle_step",
        "degree",
        1.0,
        "crank-angle grid step over the 720° cycle (must divide 720°)",
        0.0,
        10.0,
        True,
    ),
)
