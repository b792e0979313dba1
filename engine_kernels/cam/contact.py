"""Flat-faced tappet cam: curvature, lubrication and contact quantities (physics §2, [C1]-[C5]).

Scalar kernels per cam angle plus the two curve reductions of the design criteria (fullness,
spring margin). Lift h [m], its derivatives per rad of cam angle h' [m/rad], h'' [m/rad²], the
base-circle radius r0 [m], the camshaft speed ω [rad/s].
"""

from __future__ import annotations

import math

from engine_kernels._jit import jit

DOWSON_HIGGINSON_CONSTANT = 2.65
DOWSON_HIGGINSON_SPEED_EXPONENT = 0.70
DOWSON_HIGGINSON_MATERIAL_EXPONENT = 0.54
DOWSON_HIGGINSON_LOAD_EXPONENT = -0.13
FILM_RATIO_FACTOR = 0.25 * math.sqrt(2.0)
"""0.35355 = 1/(2√2) in [C4]."""


@jit
def radius_of_curvature(base_radius, lift, acceleration):
    """Radius of curvature of the cam outline rho = r0 + h + h''  [C1].

    base_radius : float  Base-circle radius r0 [m].
    lift        : float  Tappet lift h [m].
    acceleration: float  Tappet acceleration h'' per cam angle [m/rad²].

    Returns rho [m]; rho ≤ 0 marks a concave or cusped cam (a design error, physics §2).
    Reference: Norton, *Cam Design and Manufacturing Handbook*, 2nd ed. (flat-faced followers).
    """
    return base_radius + lift + acceleration


@jit
def lubrication_coefficient(base_radius, lift, acceleration):
    """Lubrication coefficient N = rho/(r0 + h) = 1 + h''/(r0 + h)  [C2].

    base_radius : float  Base-circle radius r0 > 0 [m].
    lift        : float  Tappet lift h [m].
    acceleration: float  Tappet acceleration h'' per cam angle [m/rad²].

    Returns N [-] (1 on the base circle).
    """
    return 1.0 + acceleration / (base_radius + lift)


@jit
def entrainment_velocity(cam_speed, base_radius, lift, acceleration):
    """Entrainment (mean surface) velocity u_e = ω (r0 + h)(2N - 1)/2  [C3].

    Equal to ω (r0 + h + 2h'')/2: the mean of the cam-surface speed ω rho and the face speed
    ω h'' of the contact point; positive along the cam-surface motion.

    cam_speed   : float  Camshaft angular speed ω [rad/s].
    base_radius : float  Base-circle radius r0 > 0 [m].
    lift        : float  Tappet lift h [m].
    acceleration: float  Tappet acceleration h'' per cam angle [m/rad²].

    Returns u_e [m/s].
    """
    n = lubrication_coefficient(base_radius, lift, acceleration)
    return cam_speed * (base_radius + lift) * (2.0 * n - 1.0) / 2.0


@jit
def relative_film_thickness(lubrication_coeff):
    """Relative film thickness h̄ = 0.35355·sqrt(|(2N - 1) N|)  [C4].

    Equal to ½·sqrt(|u_e| rho/(ω (r0 + h)²)) with u_e from [C3] and rho = N (r0 + h).

    lubrication_coeff: float  Lubrication coefficient N [-].

    Returns h̄ [-]: 0.354 on the base circle, zero at N = 0 and N = 0.5 (entrainment
    reverses), a local maximum 0.125 at N = 0.25.
    """
    return FILM_RATIO_FACTOR * math.sqrt(abs((2.0 * lubrication_coeff - 1.0) * lubrication_coeff))


@jit
def film_thickness_dowson_higginson(
    reduced_radius, entrainment_vel, load_per_width, viscosity, pressure_viscosity, modulus
):
    """Minimum EHL film thickness of a line contact (Dowson-Higginson).

    h_min = 2.65 R U^0.70 G^0.54 W^-0.13 with U = η0|u_e|/(E'R), G = alphaE', W = w/(E'R).
    E' is the Dowson-Higginson reduced modulus 2/[(1-nu1²)/E1 + (1-nu2²)/E2] = 2E*, where E* is
    Johnson's contact modulus taken by this function (``effective_modulus``).

    reduced_radius    : float  Reduced radius R, here the cam radius rho (flat tappet) [m].
    entrainment_vel   : float  Entrainment velocity u_e [m/s] (sign ignored).
    load_per_width    : float  Contact load per unit face width w [N/m].
    viscosity         : float  Dynamic viscosity at inlet η0 [Pa s].
    pressure_viscosity: float  Pressure-viscosity coefficient alpha [1/Pa].
    modulus           : float  Contact modulus E* [Pa].

    Returns h_min [m]; 0 when R ≤ 0 (concave or cusped cam: no EHL film), +inf when w ≤ 0
    (unloaded contact, no elastohydrodynamic limit).
    Reference: Dowson & Higginson, *Elasto-hydrodynamic Lubrication*, Pergamon 1966/1977;
    Hamrock, Schmid & Jacobson, *Fundamentals of Fluid Film Lubrication*, ch. 20.
    """
    if reduced_radius <= 0.0:
        return 0.0
    if load_per_width <= 0.0:
        return math.inf
    e_prime = 2.0 * modulus
    u = viscosity * abs(entrainment_vel) / (e_prime * reduced_radius)
    g = pressure_viscosity * e_prime
    w = load_per_width / (e_prime * reduced_radius)
    return (
        DOWSON_HIGGINSON_CONSTANT
        * reduced_radius
        * u**DOWSON_HIGGINSON_SPEED_EXPONENT
        * g**DOWSON_HIGGINSON_MATERIAL_EXPONENT
        * w**DOWSON_HIGGINSON_LOAD_EXPONENT
    )


@jit
def contact_force(spring_preload, spring_rate, equivalent_mass, cam_speed, lift, acceleration):
    """Cam-tappet contact force F = Ps0 + ks h + m_eq ω² h''  (physics §2).

    spring_preload : float  Spring preload Ps0 [N].
    spring_rate    : float  Spring rate ks [N/m].
    equivalent_mass: float  Equivalent mass on the tappet axis m_eq [kg].
    cam_speed      : float  Camshaft angular speed ω [rad/s].
    lift           : float  Tappet lift h [m].
    acceleration   : float  Tappet acceleration h'' per cam angle [m/rad²].

    Returns F [N]; F ≤ 0 means the tappet leaves the cam.
    """
    return spring_preload + spring_rate * lift + equivalent_mass * cam_speed**2 * acceleration


@jit
def effective_modulus(youngs_modulus_1, poisson_1, youngs_modulus_2, poisson_2):
    """Contact modulus E* from 1/E* = (1-nu1²)/E1 + (1-nu2²)/E2  (Johnson's E*, [C5]).

    youngs_modulus_1: float  Cam Young's modulus E1 [Pa].
    poisson_1       : float  Cam Poisson's ratio nu1 [-].
    youngs_modulus_2: float  Tappet Young's modulus E2 [Pa].
    poisson_2       : float  Tappet Poisson's ratio nu2 [-].

    Returns E* [Pa] (steel on steel, 210 GPa and 0.3: 115.4 GPa).
    Reference: Johnson, *Contact Mechanics*, Cambridge 1985, §4.2.
    """
    return 1.0 / ((1.0 - poisson_1**2) / youngs_modulus_1 + (1.0 - poisson_2**2) / youngs_modulus_2)


@jit
def hertz_line_contact_stress(force, modulus, width, radius):
    """Peak Hertz pressure of a cylinder on a flat, p0 = sqrt(F E*/(π b rho))  [C5].

    force  : float  Contact force F [N].
    modulus: float  Contact modulus E* [Pa].
    width  : float  Contact (cam) width b [m].
    radius : float  Cam radius of curvature rho [m].

    Returns p0 [Pa]: 0 for F ≤ 0 (no contact); +inf for rho ≤ 0 with F > 0 (a concave or
    cusped cam has no Hertz solution — reported as infinite stress, never NaN).
    Reference: Johnson, *Contact Mechanics*, Cambridge 1985, §4.3 (two-dimensional contact).
    """
    if force <= 0.0:
        return 0.0
    if radius <= 0.0:
        return math.inf
    return math.sqrt(force * modulus / (math.pi * width * radius))


@jit
def fullness_coefficient(theta, lift, event_duration):
    """Fullness = ∫h dθ / (h_max * event duration)  (physics §2; should be slightly > 0.55).

    theta         : array  Cam angles covering the event, increasing, shape (m,) [rad].
    lift          : array  Lift h on ``theta``, shape (m,) [m].
    event_duration: float  Event duration (twice the half-width incl. ramps) [rad].

    Returns the fullness [-] (trapezoidal area); 0 when h_max ≤ 0 or the duration ≤ 0.
    """
    area = 0.0
    h_max = 0.0
    for j in range(theta.shape[0]):
        h_max = max(h_max, lift[j])
        if j > 0:
            area += 0.5 * (lift[j] + lift[j - 1]) * (theta[j] - theta[j - 1])
    if h_max <= 0.0 or event_duration <= 0.0:
        return 0.0
    return area / (h_max * event_duration)


@jit
def spring_margin(lift, acceleration, spring_preload, spring_rate, equivalent_mass, cam_speed):
    """Spring margin = min over h'' < 0 of (Ps0 + ks h)/(m_eq ω² |h''|)  (physics §2; > 1.2).

    lift           : array  Lift h, shape (m,) [m].
    acceleration   : array  Acceleration h'' per cam angle, shape (m,) [m/rad²].
    spring_preload : float  Spring preload Ps0 [N].
    spring_rate    : float  Spring rate ks [N/m].
    equivalent_mass: float  Equivalent mass m_eq [kg].
    cam_speed      : float  Camshaft angular speed ω [rad/s].

    Returns the margin [-]; +inf when no point decelerates the tappet (or m_eq ω² = 0).
    """
    inertia = equivalent_mass * cam_speed**2
    margin = math.inf
    for j in range(lift.shape[0]):
        if acceleration[j] < 0.0 and inertia > 0.0:
            ratio = (spring_preload + spring_rate * lift[j]) / (inertia * -acceleration[j])
            margin = min(margin, ratio)
    return margin
