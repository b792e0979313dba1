"""Trolley drive chain of the luffing rig: resistance, motor, belt, coupling, key, bearing (physics §7).

Resistance [L1] → work power → drive efficiency → required motor power → next rated motor →
belt design power, pulley, shaft load → coupling torque, key crushing stress, bearing life
(ISO 281: L10 = (C/P)^p 10⁶ revolutions, p = 3 ball, 10/3 roller). SI units throughout.
"""

from __future__ import annotations

import math

from engine_kernels._jit import jit

BALL_BEARING = 0
ROLLER_BEARING = 1
BALL_EXPONENT = 3.0
ROLLER_EXPONENT = 10.0 / 3.0
RATING_REVOLUTIONS = 1.0e6
"""Revolutions of the basic rating life L10 (ISO 281)."""
NO_MOTOR = -1
"""Index returned by :func:`next_rated_motor` when no listed motor is large enough."""


@jit
def travel_resistance(
    acceleration, mass, damping_coefficient, speed, friction_coefficient, gravity
):
    """Trolley travel resistance Fw = a·m + C·V + μ·m·g  [L1].

    acceleration        : float  a [m/s²].
    mass                : float  m [kg].
    damping_coefficient : float  C [N s/m].
    speed               : float  V [m/s].
    friction_coefficient: float  μ [-].
    gravity             : float  g [m/s²].
    Reference: physics §7 [L1].
    """
    return acceleration * mass + damping_coefficient * speed + friction_coefficient * mass * gravity


@jit
def work_power(resistance, speed, work_efficiency):
    """Work power Pw = Fw·V/ηw [W].

    resistance     : float  Fw [N].
    speed          : float  V [m/s].
    work_efficiency: float  ηw [-].
    Reference: physics §7.
    """
    return resistance * speed / work_efficiency


@jit
def drive_efficiency(coupling_efficiency, belt_efficiency, bearing_efficiency):
    """Drive efficiency η = η_coupling·η_belt·η_bearing [-].

    coupling_efficiency: float  [-].
    belt_efficiency    : float  [-].
    bearing_efficiency : float  [-].
    Reference: physics §7.
    """
    return coupling_efficiency * belt_efficiency * bearing_efficiency


@jit
def motor_power_required(work_power_, efficiency):
    """Required motor power P0 = Pw/η [W].

    work_power_: float  Pw [W].
    efficiency : float  η [-].
    Reference: physics §7.
    """
    return work_power_ / efficiency


@jit
def next_rated_motor(required_power, rated_powers):
    """Index of the smallest listed motor whose rated power covers the requirement.

    required_power: float     P0 [W].
    rated_powers  : float[:]  Rated powers of the available motors, ascending [W].
    Returns the index, or NO_MOTOR. Reference: physics §7.
    """
    for k in range(rated_powers.shape[0]):
        if rated_powers[k] >= required_power:
            return k
    return NO_MOTOR


@jit
def belt_design_power(service_factor, power):
    """Belt design power Pd = KA·P [W].

    service_factor: float  KA [-].
    power         : float  Transmitted power P [W].
    Reference: physics §7.
    """
    return service_factor * power


@jit
def pulley_pitch_diameter(pitch, teeth):
    """Timing-pulley pitch diameter d = p·Z/π [m].

    pitch: float  Belt pitch p [m].
    teeth: float  Number of teeth Z [-].
    Reference: physics §7.
    """
    return pitch * teeth / math.pi


@jit
def shaft_load(design_power, belt_speed):
    """Shaft load of the belt drive Fr ≈ Pd/V [N].

    design_power: float  Pd [W].
    belt_speed  : float  V [m/s].
    Reference: physics §7.
    """
    return design_power / belt_speed


@jit
def implied_reduction_ratio(motor_speed, belt_speed, pitch_diameter):
    """Reduction ratio needed between motor and pulley, i = ω_motor·d/(2V) [-].

    motor_speed   : float  ω_motor [rad/s].
    belt_speed    : float  V [m/s].
    pitch_diameter: float  d [m].
    Reference: physics §7 (consistency check of the 1:1 belt).
    """
    return motor_speed * pitch_diameter / (2.0 * belt_speed)


@jit
def coupling_torque(power, speed, kw, k, kz, kt):
    """Coupling design torque Tc = P·Kw·K·Kz·Kt/ω (= 9550·P[kW]·…/n[rpm]) [N m].

    power: float  P [W].
    speed: float  Shaft speed ω [rad/s].
    kw   : float  Power-machine factor [-].
    k    : float  Working-machine factor [-].
    kz   : float  Start-frequency factor [-].
    kt   : float  Temperature factor [-].
    Reference: physics §7.
    """
    return power * kw * k * kz * kt / speed


@jit
def key_crushing_stress(torque, contact_height, length, shaft_diameter):
    """Key crushing (bearing) stress σp = 2T/(k·l·d) [Pa].

    torque        : float  T [N m].
    contact_height: float  k, key height in contact with the hub [m].
    length        : float  l, working length of the key [m].
    shaft_diameter: float  d [m].
    Reference: physics §7.
    """
    return 2.0 * torque / (contact_height * length * shaft_diameter)


@jit
def bearing_life_exponent(bearing_type):
    """Life exponent p: 3 for ball bearings, 10/3 for roller bearings.

    bearing_type: int  BALL_BEARING or ROLLER_BEARING. Reference: ISO 281.
    """
    return ROLLER_EXPONENT if bearing_type == ROLLER_BEARING else BALL_EXPONENT


@jit
def bearing_life(rating, load, speed, exponent):
    """Basic rating life L10 = (C/P)^p·10⁶ revolutions, as time [s] (L10h = value/3600).

    rating  : float  Dynamic load rating C [N].
    load    : float  Equivalent load P [N].
    speed   : float  Shaft speed ω [rad/s].
    exponent: float  p [-] (:func:`bearing_life_exponent`).
    Reference: physics §7; ISO 281.
    """
    return (rating / load) ** exponent * RATING_REVOLUTIONS * 2.0 * math.pi / speed
