"""Accuracy reference for the valve model [V2]: event-restarted scipy ``solve_ivp`` (SPEC §4).

The model is piecewise linear: the drive acts while ``k(Y − y) + b(Ẏ − ẏ) > 0`` and the
seat while ``y < δ0`` and ``kz(δ0 − y) − bz ẏ > 0``. Within one mode the right-hand side is
smooth, so a high-order adaptive solver (DOP853 or Radau, rtol ~1e-10) integrates each mode
to its switch, found as a terminal event, and restarts there in the new mode. Each event only
fires in the direction that leaves the current mode, so a restart on the switching surface
does not find the same event again. This is the oracle the fixed-step RK4 kernels of
``engine_kernels.valvetrain`` are measured against; it is slow and never used in studies.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from scipy.integrate import solve_ivp
from scipy.interpolate import CubicHermiteSpline

from engine_kernels import valvetrain as valve

Excitation = Callable[[float | np.ndarray], tuple[np.ndarray, np.ndarray, np.ndarray]]

MAX_SEGMENTS = 10_000
HYSTERESIS = (1e-9, 1e-18, 1e-9)  # drive force [N], seat gap [m], seat force [N]


@dataclass
class ReferenceSolution:
    """Lift and velocity at the requested cam angles, and the located mode switches."""

    theta: np.ndarray
    lift: np.ndarray
    velocity: np.ndarray
    switches: list[tuple[float, str]] = field(default_factory=list)


def table_excitation(excitation: np.ndarray, table_step: float, table_start: float) -> Excitation:
    """The cubic Hermite interpolant the kernels use, as a callable θ → (Y, Y', Y'').

    Y is interpolated with slopes Y', Y' with slopes Y'', Y'' linearly (SI units, per rad).
    """
    nodes = table_start + table_step * np.arange(excitation.shape[1])
    lift = CubicHermiteSpline(nodes, excitation[0], excitation[1])
    slope = CubicHermiteSpline(nodes, excitation[1], excitation[2])

    def evaluate(theta):
        return lift(theta), slope(theta), np.interp(theta, nodes, excitation[2])

    return evaluate


def _functions(params, excitation, theta, state):
    """Raw switching functions (drive force, seat gap, seat force) at one point."""
    speed = params[valve.P_SPEED]
    drive_lift, drive_slope, _ = excitation(theta)
    depth = params[valve.P_PRELOAD] / params[valve.P_SEAT_STIFFNESS]
    lift, velocity = state
    drive = params[valve.P_DRIVE_STIFFNESS] * (drive_lift - lift) + params[
        valve.P_DRIVE_DAMPING
    ] * (speed * drive_slope - velocity)
    gap = depth - lift
    seat = params[valve.P_SEAT_STIFFNESS] * gap - params[valve.P_SEAT_DAMPING] * velocity
    return float(drive), float(gap), float(seat)


def _modes(signs):
    drive, gap, seat = signs
    return drive > 0, gap > 0 and seat > 0


def valve_reference(
    excitation: Excitation,
    params: np.ndarray,
    theta_eval: np.ndarray,
    method: str = "DOP853",
    rtol: float = 1e-10,
    atol: float = 1e-14,
) -> ReferenceSolution:
    """Solve [V2] from ``theta_eval[0]`` to ``theta_eval[-1]`` with event restarts.

    excitation : callable θ [rad] → (Y [m], Y' [m/rad], Y'' [m/rad²]).
    params     : parameter row indexed by ``engine_kernels.valvetrain.P_*`` (SI units).
    theta_eval : increasing cam angles [rad] at which lift [m] and velocity [m/s] are returned.
    method     : ``"DOP853"`` or ``"Radau"``.
    rtol, atol : solver tolerances (atol in m and m/s).
    """
    speed = params[valve.P_SPEED]
    mass = params[valve.P_MASS]
    k, b = params[valve.P_DRIVE_STIFFNESS], params[valve.P_DRIVE_DAMPING]
    ks, ps0 = params[valve.P_SPRING_RATE], params[valve.P_PRELOAD]
    kz, bz = params[valve.P_SEAT_STIFFNESS], params[valve.P_SEAT_DAMPING]
    gamma = params[valve.P_EXTERNAL_DAMPING]
    depth = ps0 / kz

    theta_eval = np.asarray(theta_eval, dtype=float)
    theta = float(theta_eval[0])
    end = float(theta_eval[-1])
    state = np.array([params[valve.P_INITIAL_LIFT], params[valve.P_INITIAL_VELOCITY]])
    signs = [1.0 if f > 0 else -1.0 for f in _functions(params, excitation, theta, state)]
    lift = np.empty_like(theta_eval)
    velocity = np.empty_like(theta_eval)
    switches: list[tuple[float, str]] = []

    for _ in range(MAX_SEGMENTS):
        contact, seated = _modes(signs)

        def rhs(th, x, contact=contact, seated=seated):
            drive_lift, drive_slope, _ = excitation(th)
            force = -ks * x[0] - ps0 - gamma * x[1]
            if contact:
                force += k * (drive_lift - x[0]) + b * (speed * drive_slope - x[1])
            if seated:
                force += kz * (depth - x[0]) - bz * x[1]
            return [x[1] / speed, force / mass / speed]

        events = []
        for index in range(3):
            # Fire only when a function crosses away from its current sign, by a margin far
            # below the solver tolerance, so an identically zero function (the drive force on
            # the base circle) does not fire at every restart.
            def event(th, x, index=index, offset=signs[index] * HYSTERESIS[index]):
                return _functions(params, excitation, th, x)[index] + offset

            event.terminal = True  # type: ignore[attr-defined]
            event.direction = -signs[index]  # type: ignore[attr-defined]
            events.append(event)
        sol = solve_ivp(
            rhs,
            (theta, end),
            state,
            method=method,
            rtol=rtol,
            atol=atol,
            events=events,
            dense_output=True,
        )
        if not sol.success:
            raise RuntimeError(f"valve reference failed at {theta:.6f} rad: {sol.message}")
        stop = float(sol.t[-1])
        inside = (theta_eval >= theta) & (theta_eval <= stop)
        if inside.any():
            values = sol.sol(theta_eval[inside])
            lift[inside], velocity[inside] = values[0], values[1]
        if sol.status == 0:
            return ReferenceSolution(theta_eval, lift, velocity, switches)
        fired = [i for i in range(3) if sol.t_events[i].size]
        state = sol.y[:, -1]
        theta = stop
        values = _functions(params, excitation, theta, state)
        signs = [1.0 if f > 0 else -1.0 for f in values]
        for i in fired:
            signs[i] = events[i].direction  # type: ignore[attr-defined]
        switches.append((theta, "+".join(("drive", "seat_gap", "seat_force")[i] for i in fired)))
    raise RuntimeError(f"valve reference: more than {MAX_SEGMENTS} mode switches")
