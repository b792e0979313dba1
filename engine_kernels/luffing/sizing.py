"""Tower-crane test-rig trolley drive sizing checks: the ``luffing`` scene (physics §7).

This module holds the parameter and output columns and the batch driver; the formulas of the
drive chain are in :mod:`engine_kernels.luffing.drive`, those of the guide tube in
:mod:`engine_kernels.luffing.guide_tube`.

A servo motor drives the trolley through a coupling and a timing belt. The chain is
resistance [L1] → work power → drive efficiency → required motor power → next rated motor →
belt design power, pulley, shaft load → coupling torque, key, bearing life; the guide tube is a
simply supported beam loaded at mid-span [L2].

Choices the physics reference leaves open (documented here, applied in :func:`luffing_batch`):

* belt design power, coupling torque and everything downstream use the *rated* power of the
  selected motor (the drive must carry what the motor can deliver);
* the coupling torque is the design torque through the keyed coupling hub, so the key check
  uses it;
* the bearing sits on the pulley shaft, turning at motor speed / belt ratio, loaded by the
  shaft load Fr;
* the belt speed needed at the pulley implies a reduction ratio i = ω_motor d/(2V); it is
  checked against the belt ratio as built (1:1 in the source) within a relative tolerance.

Every check is written as (value, limit, pass) with pass = 1.0 or 0.0, or NaN (stored as −1,
"not evaluated") where the value could not be computed: the coupling torque, the key stress
and the bearing life need the selected motor, and none is selected where no listed motor
covers the required power (``motor_ok`` = 0 says so); all quantities SI
(the coupling-torque formula 9550·P[kW]·K/n[rpm] is T = P K/ω in SI; bearing life in seconds:
L10h = life/3600).

Reference: physics §7; bearing life ISO 281 (basic rating life L10 = (C/P)^p 10⁶ revolutions,
p = 3 ball, 10/3 roller).
"""

from __future__ import annotations

import math

from engine_kernels._jit import batch, jit, prange
from engine_kernels.luffing.drive import (
    NO_MOTOR,
    bearing_life,
    bearing_life_exponent,
    belt_design_power,
    coupling_torque,
    drive_efficiency,
    implied_reduction_ratio,
    key_crushing_stress,
    motor_power_required,
    next_rated_motor,
    pulley_pitch_diameter,
    shaft_load,
    travel_resistance,
    work_power,
)
from engine_kernels.luffing.guide_tube import (
    tube_end_slope,
    tube_midspan_deflection,
    tube_second_moment,
)

# Columns of params[n, N_PARAMS] (SI units).
TROLLEY_ACCELERATION = 0  # a [m/s²]
TROLLEY_MASS = 1  # m [kg]
DAMPING_COEFFICIENT = 2  # C [N s/m]
TROLLEY_SPEED = 3  # V [m/s], also the belt speed
FRICTION_COEFFICIENT = 4  # μ [-]
GRAVITY = 5  # g [m/s²]
WORK_EFFICIENCY = 6  # ηw [-]
COUPLING_EFFICIENCY = 7  # [-]
BELT_EFFICIENCY = 8  # [-]
BEARING_EFFICIENCY = 9  # [-]
MOTOR_SPEED = 10  # ω_motor [rad/s]
SERVICE_FACTOR = 11  # KA [-]
BELT_PITCH = 12  # p [m]
PULLEY_TEETH = 13  # Z [-]
BELT_RATIO = 14  # transmission ratio as built [-] (1 for a 1:1 belt)
RATIO_TOLERANCE = 15  # allowed relative deviation of the implied ratio [-]
COUPLING_KW = 16  # power-machine factor [-]
COUPLING_K = 17  # working-machine factor [-]
COUPLING_KZ = 18  # start-frequency factor [-]
COUPLING_KT = 19  # temperature factor [-]
COUPLING_RATED_TORQUE = 20  # [N m]
TUBE_OUTER_DIAMETER = 21  # D [m]
TUBE_INNER_DIAMETER = 22  # d [m]
TUBE_SPAN = 23  # l [m]
TUBE_LOAD = 24  # F [N]
TUBE_WEIGHT = 25  # G [N]
TUBE_MODULUS = 26  # E [Pa]
ALLOWABLE_DEFLECTION = 27  # [m]
ALLOWABLE_SLOPE = 28  # [rad]
KEY_CONTACT_HEIGHT = 29  # k [m]
KEY_LENGTH = 30  # working length l [m]
KEY_SHAFT_DIAMETER = 31  # d [m]
ALLOWABLE_CRUSHING_STRESS = 32  # [Pa]
BEARING_RATING = 33  # dynamic load rating C [N]
BEARING_TYPE = 34  # BALL_BEARING or ROLLER_BEARING
REQUIRED_BEARING_LIFE = 35  # [s]
N_PARAMS = 36
PARAM_NAMES = (
    "trolley_acceleration",
    "trolley_mass",
    "damping_coefficient",
    "trolley_speed",
    "friction_coefficient",
    "gravity",
    "work_efficiency",
    "coupling_efficiency",
    "belt_efficiency",
    "bearing_efficiency",
    "motor_speed",
    "service_factor",
    "belt_pitch",
    "pulley_teeth",
    "belt_ratio",
    "ratio_tolerance",
    "coupling_kw",
    "coupling_k",
    "coupling_kz",
    "coupling_kt",
    "coupling_rated_torque",
    "tube_outer_diameter",
    "tube_inner_diameter",
    "tube_span",
    "tube_load",
    "tube_weight",
    "tube_modulus",
    "allowable_deflection",
    "allowable_slope",
    "key_contact_height",
    "key_length",
    "key_shaft_diameter",
    "allowable_crushing_stress",
    "bearing_rating",
    "bearing_type",
    "required_bearing_life",
)

# Columns of out[n, N_OUT]; each check is (value, limit, pass).
OUT_RESISTANCE = 0
OUT_WORK_POWER = 1
OUT_DRIVE_EFFICIENCY = 2
OUT_MOTOR_POWER = 3  # check: required motor power ≤ rated power of the selected motor
OUT_MOTOR_RATED_POWER = 4
OUT_MOTOR_PASS = 5
OUT_MOTOR_INDEX = 6
OUT_BELT_DESIGN_POWER = 7
OUT_PULLEY_DIAMETER = 8
OUT_SHAFT_LOAD = 9
OUT_IMPLIED_RATIO = 10  # check: implied reduction ratio = belt ratio within tolerance
OUT_BELT_RATIO = 11
OUT_RATIO_PASS = 12
OUT_COUPLING_TORQUE = 13
OUT_COUPLING_LIMIT = 14
OUT_COUPLING_PASS = 15
OUT_TUBE_SECOND_MOMENT = 16
OUT_DEFLECTION = 17
OUT_DEFLECTION_LIMIT = 18
OUT_DEFLECTION_PASS = 19
OUT_SLOPE = 20
OUT_SLOPE_LIMIT = 21
OUT_SLOPE_PASS = 22
OUT_KEY_STRESS = 23
OUT_KEY_LIMIT = 24
OUT_KEY_PASS = 25
OUT_BEARING_LIFE = 26
OUT_BEARING_LIMIT = 27
OUT_BEARING_PASS = 28
N_OUT = 29
OUTPUTS = (
    "resistance",
    "work_power",
    "drive_efficiency",
    "motor_power",
    "motor_rated_power",
    "motor_pass",
    "motor_index",
    "belt_design_power",
    "pulley_diameter",
    "shaft_load",
    "implied_ratio",
    "belt_ratio",
    "ratio_pass",
    "coupling_torque",
    "coupling_limit",
    "coupling_pass",
    "tube_second_moment",
    "deflection",
    "deflection_limit",
    "deflection_pass",
    "slope",
    "slope_limit",
    "slope_pass",
    "key_stress",
    "key_limit",
    "key_pass",
    "bearing_life",
    "bearing_limit",
    "bearing_pass",
)
OUTPUT_UNITS = (
    "N", "W", "-", "W", "W", "-", "-", "W", "m", "N", "-", "-", "-", "N m", "N m", "-",
    "m^4", "m", "m", "-", "rad", "rad", "-", "Pa", "Pa", "-", "s", "s", "-",
)  # fmt: skip


@jit
def check_flag(passed, value):
    """Pass flag of a design check: 1.0 if it passes, 0.0 if not, NaN (not evaluated) where
    the checked ``value`` is NaN (it needs a motor and none was selected).

    passed: bool   Outcome of the comparison of ``value`` with its limit.
    value : float  The checked quantity.
    Reference: physics §7 (checks as value, limit, pass).
    """
    if math.isnan(value):
        return math.nan
    return 1.0 if passed else 0.0


@batch
def luffing_batch(params, rated_powers, out):
    """All physics §7 sizing quantities and checks of every case.

    params      : float[n, N_PARAMS]  Case parameters (columns of this module).
    rated_powers: float[k]            Rated powers of the available motors, ascending [W].
    out         : float[n, N_OUT]     Columns OUT_* (names OUTPUTS); NaN motor quantities (and
                                      those derived from them) when no listed motor suffices.
    Reference: physics §7; choices in the module docstring.
    """
    for i in prange(params.shape[0]):
        row = params[i]
        speed = row[TROLLEY_SPEED]
        resistance = travel_resistance(
            row[TROLLEY_ACCELERATION],
            row[TROLLEY_MASS],
            row[DAMPING_COEFFICIENT],
            speed,
            row[FRICTION_COEFFICIENT],
            row[GRAVITY],
        )
        power_w = work_power(resistance, speed, row[WORK_EFFICIENCY])
        efficiency = drive_efficiency(
            row[COUPLING_EFFICIENCY], row[BELT_EFFICIENCY], row[BEARING_EFFICIENCY]
        )
        required = motor_power_required(power_w, efficiency)
        index = next_rated_motor(required, rated_powers)
        rated = rated_powers[index] if index != NO_MOTOR else math.nan
        design = belt_design_power(row[SERVICE_FACTOR], rated)
        diameter = pulley_pitch_diameter(row[BELT_PITCH], row[PULLEY_TEETH])
        load = shaft_load(design, speed)
        ratio = implied_reduction_ratio(row[MOTOR_SPEED], speed, diameter)
        torque = coupling_torque(
            rated,
            row[MOTOR_SPEED],
            row[COUPLING_KW],
            row[COUPLING_K],
            row[COUPLING_KZ],
            row[COUPLING_KT],
        )
        inertia = tube_second_moment(row[TUBE_OUTER_DIAMETER], row[TUBE_INNER_DIAMETER])
        deflection = tube_midspan_deflection(
            row[TUBE_LOAD], row[TUBE_WEIGHT], row[TUBE_SPAN], row[TUBE_MODULUS], inertia
        )
        slope = tube_end_slope(
            row[TUBE_LOAD], row[TUBE_WEIGHT], row[TUBE_SPAN], row[TUBE_MODULUS], inertia
        )
        stress = key_crushing_stress(
            torque, row[KEY_CONTACT_HEIGHT], row[KEY_LENGTH], row[KEY_SHAFT_DIAMETER]
        )
        life = bearing_life(
            row[BEARING_RATING],
            load,
            row[MOTOR_SPEED] / row[BELT_RATIO],
            bearing_life_exponent(int(row[BEARING_TYPE])),
        )
        out[i, OUT_RESISTANCE] = resistance
        out[i, OUT_WORK_POWER] = power_w
        out[i, OUT_DRIVE_EFFICIENCY] = efficiency
        out[i, OUT_MOTOR_POWER] = required
        out[i, OUT_MOTOR_RATED_POWER] = rated
        out[i, OUT_MOTOR_PASS] = check_flag(required <= rated, required)
        out[i, OUT_MOTOR_INDEX] = index if index != NO_MOTOR else math.nan
        out[i, OUT_BELT_DESIGN_POWER] = design
        out[i, OUT_PULLEY_DIAMETER] = diameter
        out[i, OUT_SHAFT_LOAD] = load
        out[i, OUT_IMPLIED_RATIO] = ratio
        out[i, OUT_BELT_RATIO] = row[BELT_RATIO]
        out[i, OUT_RATIO_PASS] = check_flag(
            abs(ratio - row[BELT_RATIO]) <= row[RATIO_TOLERANCE] * row[BELT_RATIO], ratio
        )
        out[i, OUT_COUPLING_TORQUE] = torque
        out[i, OUT_COUPLING_LIMIT] = row[COUPLING_RATED_TORQUE]
        out[i, OUT_COUPLING_PASS] = check_flag(torque <= row[COUPLING_RATED_TORQUE], torque)
        out[i, OUT_TUBE_SECOND_MOMENT] = inertia
        out[i, OUT_DEFLECTION] = deflection
        out[i, OUT_DEFLECTION_LIMIT] = row[ALLOWABLE_DEFLECTION]
        out[i, OUT_DEFLECTION_PASS] = check_flag(
            deflection <= row[ALLOWABLE_DEFLECTION], deflection
        )
        out[i, OUT_SLOPE] = slope
        out[i, OUT_SLOPE_LIMIT] = row[ALLOWABLE_SLOPE]
        out[i, OUT_SLOPE_PASS] = check_flag(slope <= row[ALLOWABLE_SLOPE], slope)
        out[i, OUT_KEY_STRESS] = stress
        out[i, OUT_KEY_LIMIT] = row[ALLOWABLE_CRUSHING_STRESS]
        out[i, OUT_KEY_PASS] = check_flag(stress <= row[ALLOWABLE_CRUSHING_STRESS], stress)
        out[i, OUT_BEARING_LIFE] = life
        out[i, OUT_BEARING_LIMIT] = row[REQUIRED_BEARING_LIFE]
        out[i, OUT_BEARING_PASS] = check_flag(life >= row[REQUIRED_BEARING_LIFE], life)
