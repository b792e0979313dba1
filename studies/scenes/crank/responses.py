"""Declarations of the ``crank`` scene: responses (each naming the stages it needs) and curves
over crank angle; engine orders in multiples of the crankshaft frequency (physics §5)."""

from __future__ import annotations

from studies.scenes.base import Curve, CurveAxis, Response
from studies.scenes.crank.parameters import MAX_ORDER_HALVES

KIN = ("kinematics",)
PRESSURE = ("pressure",)
FORCES = ("pressure", "forces")
MULTI = ("pressure", "multicylinder")


def order_name(halves: int) -> str:
    """Response name of engine order halves/2: ``torque_order_6``, ``torque_order_1_5``."""
    whole, half = divmod(halves, 2)
    return f"torque_order_{whole}_5" if half else f"torque_order_{whole}"


def _order_responses() -> tuple[Response, ...]:
    return tuple(
        Response(
            order_name(q), "N*m", f"amplitude of engine order {q / 2:g} of the engine torque", MULTI
        )
        for q in range(1, MAX_ORDER_HALVES + 1)
    )


RESPONSES: tuple[Response, ...] = (
    Response("mean_piston_speed", "m/s", "mean piston speed cm = S n/30", KIN),
    Response("max_piston_velocity", "m/s", "maximum piston velocity", KIN),
    Response(
        "crank_angle_max_velocity", "degree", "crank angle of the maximum piston velocity", KIN
    ),
    Response("piston_acceleration_tdc", "m/s^2", "piston acceleration at TDC", KIN),
    Response(
        "min_piston_acceleration", "m/s^2", "most negative piston acceleration", KIN, "larger"
    ),
    Response("max_rod_angle", "degree", "largest rod angle β = asin λ", KIN),
    Response("max_rod_angular_velocity", "rad/s", "largest rod angular velocity λω", KIN),
    Response("max_rod_angular_acceleration", "rad/s^2", "largest |rod angular acceleration|", KIN),
    Response(
        "approx_error_displacement",
        "mm",
        "max |exact − two-term| piston displacement over the cycle",
        KIN,
    ),
    Response(
        "approx_error_velocity", "m/s", "max |exact − two-term| piston velocity over the cycle", KIN
    ),
    Response(
        "approx_error_acceleration",
        "m/s^2",
        "max |exact − two-term| piston acceleration over the cycle",
        KIN,
    ),
    Response(
        "approx_error_displacement_relative",
        "1",
        "two-term displacement error over the crank radius r",
        KIN,
    ),
    Response("approx_error_velocity_relative", "1", "two-term velocity error over r ω", KIN),
    Response(
        "approx_error_acceleration_relative", "1", "two-term acceleration error over r ω²", KIN
    ),
    Response(
        "peak_pressure",
        "MPa",
        "peak cylinder pressure (cycle: located between the grid points; table: on the grid)",
        PRESSURE,
    ),
    Response(
        "peak_pressure_angle",
        "degree",
        "crank angle of the peak pressure after firing TDC",
        PRESSURE,
    ),
    Response("compression_pressure", "MPa", "compression pressure p_a ε^k (cycle only)", PRESSURE),
    Response("heat_released", "kJ", "heat released in the closed cycle (cycle only)", PRESSURE),
    Response(
        "cycle_work",
        "kJ",
        "indicated work per cycle and cylinder ∮p dV (cycle only)",
        PRESSURE,
        "larger",
    ),
    Response("imep", "MPa", "indicated mean effective pressure (cycle only)", PRESSURE, "larger"),
    Response("max_gas_force", "kN", "maximum gas force on the piston", FORCES),
    Response("max_piston_force", "kN", "maximum total piston force P = Pg + Pj", FORCES),
    Response("min_piston_force", "kN", "minimum total piston force", FORCES, "larger"),
    Response("max_rod_force", "kN", "maximum rod force S = P/cos β", FORCES),
    Response("min_rod_force", "kN", "minimum rod force", FORCES, "larger"),
    Response("max_side_force", "kN", "maximum |piston side force| N = P tan β", FORCES),
    Response("max_tangential_force", "kN", "maximum tangential crankpin force T", FORCES),
    Response("min_tangential_force", "kN", "minimum tangential crankpin force", FORCES, "larger"),
    Response("max_radial_force", "kN", "maximum radial crankpin force Z", FORCES),
    Response("min_radial_force", "kN", "minimum radial crankpin force", FORCES, "larger"),
    Response("cylinder_mean_torque", "N*m", "mean torque of one cylinder", FORCES, "larger"),
    Response("cylinder_max_torque", "N*m", "maximum torque of one cylinder", FORCES),
    Response("cylinder_min_torque", "N*m", "minimum torque of one cylinder", FORCES, "larger"),
    Response(
        "first_order_inertia_amplitude",
        "kN",
        "first-order reciprocating inertia amplitude mj r ω²",
        FORCES,
    ),
    Response(
        "second_order_inertia_amplitude",
        "kN",
        "second-order reciprocating inertia amplitude mj r ω² λ",
        FORCES,
    ),
    Response("rotating_inertia_force", "kN", "rotating inertia force mr r ω²", FORCES),
    Response("mean_torque", "N*m", "mean engine torque", MULTI, "larger"),
    Response("max_torque", "N*m", "maximum engine torque", MULTI),
    Response("min_torque", "N*m", "minimum engine torque", MULTI, "larger"),
    Response("torque_peak_to_peak", "N*m", "engine torque max − min", MULTI),
    Response("torque_nonuniformity", "1", "(max − min)/mean engine torque", MULTI),
    Response("mean_power", "kW", "mean indicated power (mean torque × ω)", MULTI, "larger"),
    Response(
        "free_first_order_force", "kN", "free first-order reciprocating force of the layout", MULTI
    ),
    Response(
        "free_second_order_force",
        "kN",
        "free second-order reciprocating force of the layout",
        MULTI,
    ),
    Response(
        "free_first_order_moment",
        "N*m",
        "free first-order reciprocating moment about the middle of the crankshaft (NaN for a "
        "V layout without cylinder_positions)",
        MULTI,
    ),
    Response(
        "free_second_order_moment",
        "N*m",
        "free second-order reciprocating moment about the middle of the crankshaft (NaN for a "
        "V layout without cylinder_positions)",
        MULTI,
    ),
    *_order_responses(),
    Response("dominant_torque_order", "1", "engine order with the largest torque amplitude", MULTI),
    Response("dominant_torque_amplitude", "N*m", "largest torque-harmonic amplitude", MULTI),
)

CURVES: tuple[Curve, ...] = (
    Curve("piston_displacement", "mm", "piston displacement from TDC", KIN),
    Curve("piston_velocity", "m/s", "piston velocity", KIN),
    Curve("piston_acceleration", "m/s^2", "piston acceleration", KIN),
    Curve("rod_angle", "degree", "connecting-rod angle β", KIN),
    Curve("rod_angular_velocity", "rad/s", "rod angular velocity", KIN),
    Curve("rod_angular_acceleration", "rad/s^2", "rod angular acceleration", KIN),
    Curve("cylinder_pressure", "MPa", "cylinder pressure", PRESSURE),
    Curve("gas_force", "kN", "gas force Pg", FORCES),
    Curve("inertia_force", "kN", "reciprocating inertia force Pj", FORCES),
    Curve("piston_force", "kN", "total piston force P", FORCES),
    Curve("rod_force", "kN", "rod force S", FORCES),
    Curve("side_force", "kN", "piston side force N", FORCES),
    Curve("tangential_force", "kN", "tangential crankpin force T", FORCES),
    Curve("radial_force", "kN", "radial crankpin force Z", FORCES),
    Curve("cylinder_torque", "N*m", "torque of cylinder 1", FORCES),
    Curve("engine_torque", "N*m", "summed engine torque", MULTI),
)

CRANK_ANGLE = CurveAxis(
    "crank_angle", "degree", "crank angle of cylinder 1 from gas-exchange TDC (firing TDC at 360°)"
)
