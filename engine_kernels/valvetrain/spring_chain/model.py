"""Multi-mass valve spring [V4]: coil chain forces, energy, natural frequencies, stiffest mode.

The spring (rate ks, mass m_s, preload Ps0) is N coil masses ``m_c = m_s/N`` joined by N+1
segments of rate ``k_seg = (N+1)·ks``. Displacements are measured in the valve-lift
direction: the head end is fixed (node 0), coil i is node i, the retainer moves with the valve
(node N+1, lift y). Segment j joins nodes j and j+1; its compression from the installed state
is ``d_j = u_{j+1} − u_j`` and its force (compression positive)::

    F_j = Ps0 + k_seg d_j + c_s ḋ_j + max(0, kc (d_j − g) + cc ḋ_j)·[d_j > g]

the last term being coil clash: a one-sided stop (rate kc, damper cc) once the segment has
closed its share ``g = clash_travel/(N+1)`` of the travel to solid. Equations of motion::

    m_c ü_i = F_i − F_{i−1}                                   i = 1 … N
    M_v ÿ   = max(0, k (Y − y) + b (Ẏ − ẏ))                    drive, as in [V2]
            + max(0, kz (δ0 − y) − bz ẏ)·[y < δ0]             seat, as in [V2]
            − F_N − γ ẏ                                        retainer-end segment force

``M_v`` is the valve-side mass without any spring share. The segment damper is stiffness
proportional, ``c_s = 2 ζ_s k_seg/ω_1``, so the first fixed–fixed spring mode has the modal
damping ratio ζ_s (higher modes ζ_n = ζ_s ω_n/ω_1). Reference: physics §4 [V2], [V4]; the
fixed–fixed lumped chain: Meirovitch, *Fundamentals of Vibrations*, §8.5 (beaded string).
"""

from __future__ import annotations

import math

from engine_kernels._jit import jit, jit_inline
from engine_kernels.valvetrain.spring_chain.layout import (
    SC_CLASH_DAMPING,
    SC_CLASH_STIFFNESS,
    SC_CLASH_TRAVEL,
    SC_DRIVE_DAMPING,
    SC_DRIVE_STIFFNESS,
    SC_EXTERNAL_DAMPING,
    SC_PRELOAD,
    SC_SEAT_DAMPING,
    SC_SEAT_STIFFNESS,
    SC_SPEED,
    SC_SPRING_DAMPING_RATIO,
    SC_SPRING_MASS,
    SC_SPRING_MASSES,
    SC_SPRING_RATE,
    SC_VALVE_MASS,
)
from engine_kernels.valvetrain.valve.model import positive_part


@jit
def chain_natural_frequency(spring_rate, spring_mass, masses, mode):
    """Natural frequency ω_n of the N-mass spring with both ends held [V4] [rad/s].

    ``ω_n = 2·√(k_seg/m_c)·sin(nπ/(2(N+1)))`` with ``k_seg = (N+1) ks``, ``m_c = m_s/N``.

    spring_rate : float  Spring rate ks [N/m].
    spring_mass : float  Spring mass m_s [kg].
    masses      : int    Number of coil masses N [-].
    mode        : int    Mode number n = 1 … N [-].
    """
    segment_rate = (masses + 1) * spring_rate
    coil_mass = spring_mass / masses
    return (
        2.0 * math.sqrt(segment_rate / coil_mass) * math.sin(mode * math.pi / (2.0 * (masses + 1)))
    )


@jit
def continuous_spring_frequency(spring_rate, spring_mass, mode):
    """Natural frequency of the continuous spring, ends held, ``f_n = (n/2)·√(ks/m_s)`` [Hz].

    spring_rate : float  Spring rate ks [N/m];  spring_mass : float  m_s [kg].
    mode        : int    Mode number n ≥ 1 [-]. Reference: [V4] (wave equation).
    """
    return 0.5 * mode * math.sqrt(spring_rate / spring_mass)


@jit
def segment_damping(spring_rate, spring_mass, masses, damping_ratio):
    """Segment damper ``c_s = 2 ζ_s k_seg/ω_1`` giving mode 1 the damping ratio ζ_s [N s/m].

    Stiffness-proportional damping ``C = (c_s/k_seg) K`` gives mode n the ratio
    ``ζ_n = (c_s/k_seg) ω_n/2``. Arguments as in :func:`chain_natural_frequency`;
    damping_ratio : float  ζ_s of the first spring mode [-] (typical 0.01–0.05).
    """
    first = chain_natural_frequency(spring_rate, spring_mass, masses, 1)
    return 2.0 * damping_ratio * (masses + 1) * spring_rate / first


@jit
def chain_coefficients(params):
    """Coefficients of the chain model from an ``SC_*`` row.

    Returns N, M_v [kg], m_c [kg], k_seg [N/m], c_s [N s/m], g [m], kc [N/m], cc [N s/m],
    k, b, kz, bz, γ (as in [V2]), Ps0 [N], δ0 = Ps0/kz [m] (−∞ without a seat) and ω [rad/s].
    """
    masses = int(params[SC_SPRING_MASSES])
    segments = masses + 1
    seat = params[SC_SEAT_STIFFNESS]
    depth = params[SC_PRELOAD] / seat if seat > 0.0 else -math.inf
    return (
        masses,
        params[SC_VALVE_MASS],
        params[SC_SPRING_MASS] / masses,
        segments * params[SC_SPRING_RATE],
        segment_damping(
            params[SC_SPRING_RATE],
            params[SC_SPRING_MASS],
            masses,
            params[SC_SPRING_DAMPING_RATIO],
        ),
        params[SC_CLASH_TRAVEL] / segments,
        params[SC_CLASH_STIFFNESS],
        params[SC_CLASH_DAMPING],
        params[SC_DRIVE_STIFFNESS],
        params[SC_DRIVE_DAMPING],
        seat,
        params[SC_SEAT_DAMPING],
        params[SC_EXTERNAL_DAMPING],
        params[SC_PRELOAD],
        depth,
        params[SC_SPEED],
    )


@jit
def chain_spectral_radius(params):
    """Upper bound on ``max |λ|`` over every contact state of the chain model [1/s].

    For an eigenpair of ``λ² M + λ C + K`` (M, C, K symmetric, positive semi-definite) with
    Rayleigh quotients ``k = x*Kx/x*Mx`` and ``c = x*Cx/x*Mx``: ``|λ| = √k`` when
    under-damped and ``|λ| ≤ c`` when over-damped, so ``|λ| ≤ max(√λmax(M⁻¹K), λmax(M⁻¹C))``.
    Both are bounded by Gershgorin row sums with every one-sided term active (drive, seat,
    coil clash on every segment), which bound every subset of them too. Stiff coil contact
    is therefore always included. params : 1-D array  ``SC_*`` row.
    Reference: Tisseur & Meerbergen, SIAM Review 43 (2001), §2 (quadratic eigenproblem).
    """
    _, valve_mass, coil_mass, rate, damper, _, kc, cc, k, b, kz, bz, gamma, _, _, _ = (
        chain_coefficients(params)
    )
    coil_k = 4.0 * (rate + kc) / coil_mass
    coil_c = 4.0 * (damper + cc) / coil_mass
    valve_k = (k + kz + 2.0 * (rate + kc)) / valve_mass
    valve_c = (b + bz + gamma + 2.0 * (damper + cc)) / valve_mass
    return max(math.sqrt(max(coil_k, valve_k)), coil_c, valve_c)


@jit_inline
def segment_force(compression, rate, damper, preload, gap, kc, cc, compression_rate):
    """Force of one spring segment, compression positive, with coil clash [V4] [N].

    compression      : float  d_j from the installed state [m]; compression_rate ḋ_j [m/s].
    rate, damper     : float  k_seg [N/m], c_s [N s/m];  preload : float  Ps0 [N].
    gap              : float  Travel of this segment to solid g [m].
    kc, cc           : float  Clash stop rate [N/m] and damper [N s/m].
    """
    force = preload + rate * compression + damper * compression_rate
    clash = kc * (compression - gap) + cc * compression_rate
    return force + (clash if compression > gap and clash > 0.0 else 0.0)


@jit
def chain_accelerations(
    pos,
    vel,
    acc,
    forces,
    drive_lift,
    drive_velocity,
    masses,
    valve_mass,
    coil_mass,
    rate,
    damper,
    gap,
    kc,
    cc,
    k,
    b,
    kz,
    bz,
    gamma,
    preload,
    depth,
):
    """Accelerations of the coils and the valve [V4]; fills ``acc`` and the segment ``forces``.

    pos, vel : 1-D arrays (N+1,)  Coil displacements u_1 … u_N then the valve lift y [m], and
                                  their velocities [m/s].
    acc      : 1-D array (N+1,)   Out: accelerations [m/s²].
    forces   : 1-D array (N+1,)   Out: segment forces F_0 … F_N [N] (F_N at the retainer).
    drive_lift, drive_velocity : float  Y [m] and Ẏ [m/s] of the excitation.
    Other arguments as returned by :func:`chain_coefficients`.
    Returns the drive force before clipping ``k (Y − y) + b (Ẏ − ẏ)`` [N] and the seat force
    (0 when off the seat) [N].
    """
    lower, lower_v = 0.0, 0.0
    for j in range(masses + 1):
        forces[j] = segment_force(
            pos[j] - lower, rate, damper, preload, gap, kc, cc, vel[j] - lower_v
        )
        lower, lower_v = pos[j], vel[j]
    inv_coil = 1.0 / coil_mass
    for i in range(masses):
        acc[i] = (forces[i + 1] - forces[i]) * inv_coil
    drive, seat, acc[masses] = valve_balance(
        pos[masses],
        vel[masses],
        drive_lift,
        drive_velocity,
        forces[masses],
        valve_mass,
        k,
        b,
        kz,
        bz,
        gamma,
        preload,
        depth,
    )
    return drive, seat


@jit_inline
def valve_balance(
    lift,
    velocity,
    drive_lift,
    drive_velocity,
    retainer,
    valve_mass,
    k,
    b,
    kz,
    bz,
    gamma,
    preload,
    depth,
):
    """Drive and seat forces on the valve and its acceleration [V4] (selects, no calls).

    lift, velocity : float  y [m], ẏ [m/s];  drive_lift, drive_velocity : float  Y [m], Ẏ [m/s].
    retainer       : float  Force of the retainer-end segment F_N [N].
    Other arguments as returned by :func:`chain_coefficients`.
    Returns the drive force before clipping [N], the seat force [N] and ÿ [m/s²].
    """
    drive = k * (drive_lift - lift) + b * (drive_velocity - velocity)
    seat = preload - kz * lift - bz * velocity  # kz (δ0 − y) − bz ẏ with kz δ0 = Ps0
    seat = seat if (lift < depth) & (seat > 0.0) else 0.0
    return drive, seat, (positive_part(drive) + seat - retainer - gamma * velocity) / valve_mass


@jit
def chain_energy(
    pos, vel, drive_lift, masses, valve_mass, coil_mass, rate, preload, gap, kc, k, kz, depth
):
    """Mechanical energy of the chain model above the rest state [J].

    ``E = ½M_v ẏ² + Σ ½m_c u̇_i² + Σ_j (½k_seg d_j² + ½kc (d_j − g)²·[d_j > g]) + Ps0 y
    + ½kz ((δ0 − y)²·[y < δ0] − δ0²) + ½k (Y − y)²·[Y > y]`` (Σ_j Ps0 d_j = Ps0 y). As for
    [V2], ``dE/dt ≤ F_drive·Ẏ``: every damper and one-sided contact only removes energy.
    Arguments as in :func:`chain_accelerations` (no damping needed).
    """
    lift = pos[masses]
    energy = kinetic_energy(0.0, valve_mass, vel[masses]) + preload * lift
    lower = 0.0
    for j in range(masses + 1):
        energy = segment_energy(energy, pos[j] - lower, rate, gap, kc)
        lower = pos[j]
    for i in range(masses):
        energy = kinetic_energy(energy, coil_mass, vel[i])
    return contact_energy(energy, lift, drive_lift, k, kz, depth)


@jit_inline
def kinetic_energy(energy, mass, velocity):
    """``energy + ½ m v²`` [J]: mass [kg], velocity [m/s]."""
    return energy + 0.5 * mass * (velocity * velocity)


@jit_inline
def segment_energy(energy, compression, rate, gap, kc):
    """``energy`` plus the strain energy of one segment, coil clash included [J] (selects).

    compression : float  d_j [m]; rate k_seg [N/m]; gap g [m]; kc clash rate [N/m].
    """
    energy += 0.5 * rate * compression * compression
    solid = compression - gap if compression > gap else 0.0
    return energy + 0.5 * kc * (solid * solid)


@jit_inline
def contact_energy(energy, lift, drive_lift, k, kz, depth):
    """``energy`` plus the seat and drive contact energies of :func:`chain_energy` [J] (selects).

    lift, drive_lift : float  y, Y [m]; k, kz [N/m]; depth δ0 [m] (−∞ without a seat).
    """
    seat = (depth - lift) * (depth - lift) - depth * depth if lift < depth else 0.0
    energy += 0.5 * kz * seat
    drive = drive_lift - lift if drive_lift > lift else 0.0
    return energy + 0.5 * k * (drive * drive)


@jit
def surge_displacement(pos, masses):
    """Largest coil deviation from the static (linear) deflection line, max_i |u_i − i y/(N+1)|.

    pos : 1-D array (N+1,)  Coil displacements then the valve lift [m]; masses : int  N.
    Returns [m]: 0 while the spring deflects quasi-statically, the surge wave otherwise.
    """
    lift = pos[masses]
    deviation = 0.0
    for i in range(masses):
        deviation = max(deviation, coil_deviation(pos[i], lift, i + 1, masses))
    return deviation


@jit_inline
def coil_deviation(displacement, lift, node, masses):
    """|u_i − i y/(N+1)| of coil ``node`` = i (1 … N) [m]; displacement u_i, lift y [m]."""
    return abs(displacement - node * lift / (masses + 1))
