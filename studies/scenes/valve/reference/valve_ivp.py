"""Accuracy reference for the valve model [V2]: event-restarted scipy ``solve_ivp`` (physics §4).

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
from typing import TYPE_CHECKING, Any

import numpy as np

from engine_kernels import valvetrain as valve

if TYPE_CHECKING:
    from scipy.integrate import OdeSolution

Excitation = Callable[[float | np.ndarray], tuple[np.ndarray, np.ndarray, np.ndarray]]

MAX_SEGMENTS = 10_000
HYSTERESIS = (1e-9, 1e-18, 1e-9)  # drive force [N], seat gap [m], seat force [N]
SCAN_POINTS = 16
"""Points of each solver step's dense output where the event functions are checked for a
switch the solver stepped over (:func:`_missed_switch`)."""
XTOL = 1e-13
"""Angle [rad] to which such a switch is located."""


@dataclass
class Segment:
    """One stretch of the solution in a fixed mode: from ``start`` to ``stop`` [rad], with
    the drive contact and the seat contact on or off, and the solver's dense output
    θ → (lift [m], velocity [m/s])."""

    start: float
    stop: float
    contact: bool
    seated: bool
    dense: OdeSolution


@dataclass
class ReferenceSolution:
    """Lift and velocity at the requested cam angles, the located mode switches and the
    segments between them (the whole solution, for outputs located between grid points)."""

    theta: np.ndarray
    lift: np.ndarray
    velocity: np.ndarray
    switches: list[tuple[float, str]] = field(default_factory=list)
    segments: list[Segment] = field(default_factory=list)


def table_excitation(excitation: np.ndarray, table_step: float, table_start: float) -> Excitation:
    """The cubic Hermite interpolant the kernels use, as a callable θ → (Y, Y', Y'').

    Y is interpolated with slopes Y', Y' with slopes Y'', Y'' linearly (SI units, per rad),
    then clipped at the lash take-up as the kernels do
    (:func:`engine_kernels.valvetrain.valve.model.lash_clip`): 0 wherever the interpolated Y ≤ 0.
    """
    from scipy.interpolate import CubicHermiteSpline  # noqa: PLC0415  (scipy on use: a second)

    nodes = table_start + table_step * np.arange(excitation.shape[1])
    lift = CubicHermiteSpline(nodes, excitation[0], excitation[1])
    slope = CubicHermiteSpline(nodes, excitation[1], excitation[2])

    def evaluate(theta):
        raw = lift(theta)
        taken_up = raw > 0.0
        return (
            np.where(taken_up, raw, 0.0),
            np.where(taken_up, slope(theta), 0.0),
            np.where(taken_up, np.interp(theta, nodes, excitation[2]), 0.0),
        )

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


def _seat_force_watched(params) -> bool:
    """False with no seat damping: the seat force kz (δ0 − y) is then the seat gap times kz,
    one switch with one root, watched as the gap alone (watched twice, each event's restart
    fired the other at the same angle without end: 10 000 switches at one angle)."""
    return bool(params[valve.P_SEAT_DAMPING] != 0.0)


def _tied(params, signs):
    """``signs`` with the seat force's tied to the gap's where only the gap is watched."""
    if not _seat_force_watched(params):
        signs[2] = signs[1]
    return signs


def _guards(params, excitation, theta, lift, velocity, signs):
    """The event functions (drive force, seat gap, seat force, each with its hysteresis
    offset) at the angles ``theta`` [rad] for the states there, times their sign at the
    segment's start: negative once a function has crossed away from it."""
    speed = params[valve.P_SPEED]
    drive_lift, drive_slope, _ = excitation(theta)
    depth = params[valve.P_PRELOAD] / params[valve.P_SEAT_STIFFNESS]
    drive = params[valve.P_DRIVE_STIFFNESS] * (drive_lift - lift) + params[
        valve.P_DRIVE_DAMPING
    ] * (speed * drive_slope - velocity)
    gap = depth - lift
    seat = params[valve.P_SEAT_STIFFNESS] * gap - params[valve.P_SEAT_DAMPING] * velocity
    guards = np.stack(
        [
            sign * (value + sign * hysteresis)
            for sign, value, hysteresis in zip(signs, (drive, gap, seat), HYSTERESIS, strict=True)
        ]
    )
    if not _seat_force_watched(params):
        guards[2] = np.inf
    return guards


def _missed_switch(
    params: np.ndarray, excitation: Excitation, sol: Any, signs: list[float]
) -> tuple[float, list[int]] | None:
    """An earlier switch the solver stepped over: (angle [rad], [its index]) or None.

    The solver sees an event only where its function changes sign between two step ends; a
    contact shorter than a step (a grazing landing on a stiff seat, a rebound) can begin and
    end inside one. Each step's dense output is sampled at ``SCAN_POINTS`` points, and the
    first crossing before the segment's end is located on it (Brent's method to ``XTOL``).
    """
    steps = sol.t
    fractions = np.linspace(0.0, 1.0, SCAN_POINTS + 1)[1:]
    theta = (steps[:-1, None] + np.diff(steps)[:, None] * fractions).ravel()
    lift, velocity = sol.sol(theta)
    guards = _guards(params, excitation, theta, lift, velocity, signs)
    crossed = np.flatnonzero((guards < 0.0).any(axis=0))
    if crossed.size == 0:
        return None
    first = int(crossed[0])
    if theta[first] >= steps[-1] - XTOL:
        return None  # the segment's own terminal event
    index = int(np.flatnonzero(guards[:, first] < 0.0)[0])
    low = theta[first - 1] if first > 0 else steps[0]

    def guard(th: float) -> float:
        at = np.array([th])
        y, v = sol.sol(at)
        return float(_guards(params, excitation, at, y, v, signs)[index, 0])

    if guard(low) < 0.0:
        return None
    from scipy.optimize import brentq  # noqa: PLC0415  (on use, as above)

    root = brentq(guard, low, theta[first], xtol=XTOL, rtol=4 * np.finfo(float).eps)
    # step just past the root, so the restart is on the new side
    while guard(root) >= 0.0 and root < theta[first]:
        root = min(root + XTOL, theta[first])
    return root, [index]


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
    from scipy.integrate import solve_ivp  # noqa: PLC0415  (on use, as above)

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
    signs = _tied(
        params, [1.0 if f > 0 else -1.0 for f in _functions(params, excitation, theta, state)]
    )
    lift = np.empty_like(theta_eval)
    velocity = np.empty_like(theta_eval)
    switches: list[tuple[float, str]] = []
    segments: list[Segment] = []

    watched = _seat_force_watched(params)  # once, not at every event evaluation
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
            def event(
                th,
                x,
                index=index,
                offset=signs[index] * HYSTERESIS[index],
                never=index == 2 and not watched,
            ):
                if never:
                    return 1.0  # never crosses: the gap's event is this switch
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
        fired = [i for i in range(3) if sol.t_events[i].size]
        missed = _missed_switch(params, excitation, sol, signs)
        if missed is not None:
            stop, fired = missed
        segments.append(Segment(theta, stop, contact, seated, sol.sol))
        inside = (theta_eval >= theta) & (theta_eval <= stop)
        if inside.any():
            values = sol.sol(theta_eval[inside])
            lift[inside], velocity[inside] = values[0], values[1]
        if sol.status == 0 and missed is None:
            return ReferenceSolution(theta_eval, lift, velocity, switches, segments)
        state = sol.sol(stop)
        theta = stop
        values = _functions(params, excitation, theta, state)
        signs = [1.0 if f > 0 else -1.0 for f in values]
        for i in fired:
            signs[i] = events[i].direction  # type: ignore[attr-defined]
        signs = _tied(params, signs)
        switches.append((theta, "+".join(("drive", "seat_gap", "seat_force")[i] for i in fired)))
    raise RuntimeError(f"valve reference: more than {MAX_SEGMENTS} mode switches")
