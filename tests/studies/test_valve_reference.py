"""The scipy accuracy reference for the valve model [V2] against closed forms and itself."""

from __future__ import annotations

import math

import numpy as np
import pytest

from engine_kernels import valvetrain as valve
from studies.scenes.valve.reference.valve_ivp import table_excitation, valve_reference

# physics §4 reference data with the values the source does not give (see test_valve.py).
PARAMS = np.array(
    [2 * math.pi * 3500 / 60, 0.0425, 1.17e7, 150.0, 3.0e4, 205.8, 5.0e7, 900.0, 0.0, 0.0, 0.0]
)
OFFSET, AMPLITUDE, WAVES = 6e-3, 2e-3, 2.0


def harmonic(theta):
    theta = np.asarray(theta, dtype=float)
    return (
        OFFSET + AMPLITUDE * np.cos(WAVES * theta),
        -AMPLITUDE * WAVES * np.sin(WAVES * theta),
        -AMPLITUDE * WAVES**2 * np.cos(WAVES * theta),
    )


def cosine_event(theta, height=4e-3, half=1.4):
    theta = np.asarray(theta, dtype=float)
    inside = np.abs(theta) < half
    w = math.pi / half
    return (
        np.where(inside, height * (1 + np.cos(w * theta)), 0.0),
        np.where(inside, -height * w * np.sin(w * theta), 0.0),
        np.where(inside, -height * w * w * np.cos(w * theta), 0.0),
    )


def far_below(theta):
    """An excitation far below the valve: the drive never touches it."""
    theta = np.asarray(theta, dtype=float)
    return np.full_like(theta, -1.0), np.zeros_like(theta), np.zeros_like(theta)


def closed_form_contact(params, theta):
    """Valve in contact and off its seat: a linear oscillator with harmonic forcing.

    M y'' + (b + g) y' + (k + ks) y = k Y + b Ydot - Ps0, Y = Yc + A cos(W w t), started at
    rest at y0: steady-state response plus the damped free vibration fitting y0 and 0.
    """
    speed, mass, k, b, ks, ps0 = params[:6]
    damping = b + params[valve.P_EXTERNAL_DAMPING]
    stiffness = k + ks
    omega = WAVES * speed
    t = theta / speed
    mean = (k * OFFSET - ps0) / stiffness
    amplitude = (k * AMPLITUDE + 1j * b * AMPLITUDE * omega) / (
        stiffness - mass * omega**2 + 1j * damping * omega
    )
    decay = -damping / (2 * mass)
    natural = math.sqrt(stiffness / mass - decay**2)
    c1 = params[valve.P_INITIAL_LIFT] - (mean + amplitude.real)
    c2 = (params[valve.P_INITIAL_VELOCITY] + omega * amplitude.imag - decay * c1) / natural
    forced = mean + (amplitude * np.exp(1j * omega * t)).real
    return forced + np.exp(decay * t) * (c1 * np.cos(natural * t) + c2 * np.sin(natural * t))


def test_reference_matches_closed_form_without_switches():
    params = PARAMS.copy()
    params[valve.P_INITIAL_LIFT] = (params[2] * (OFFSET + AMPLITUDE) - params[5]) / (
        params[2] + params[4]
    )
    theta = np.linspace(0.0, math.pi, 181)
    solution = valve_reference(harmonic, params, theta, rtol=1e-12, atol=1e-15)
    assert solution.switches == []
    np.testing.assert_allclose(
        solution.lift, closed_form_contact(params, theta), rtol=0, atol=1e-12
    )


def test_dop853_and_radau_agree_through_contact_and_seat_switches():
    theta = np.radians(np.arange(-100.0, 110.0, 0.5))
    dop = valve_reference(cosine_event, PARAMS, theta)
    radau = valve_reference(cosine_event, PARAMS, theta, method="Radau")
    kinds = {kind for _, kind in dop.switches}
    assert {"drive", "seat_gap"} <= kinds
    np.testing.assert_allclose(dop.lift, radau.lift, rtol=0, atol=1e-10)
    np.testing.assert_allclose(dop.velocity, radau.velocity, rtol=0, atol=1e-7)


def test_free_flight_on_the_spring_alone():
    # Drive far below and valve above its seat: the valve swings on its spring about -Ps0/ks,
    # y = -Ps0/ks + (y0 + Ps0/ks) cos(sqrt(ks/M) t), staying off the seat until theta = 0.41.
    params = PARAMS.copy()
    params[valve.P_INITIAL_LIFT] = 5e-3
    theta = np.linspace(0.0, 0.4, 41)

    solution = valve_reference(far_below, params, theta, rtol=1e-12, atol=1e-15)
    rest = -params[5] / params[4]
    t = theta / params[0]
    expected = rest + (5e-3 - rest) * np.cos(math.sqrt(params[4] / params[1]) * t)
    assert solution.switches == []
    np.testing.assert_allclose(solution.lift, expected, rtol=0, atol=1e-12)


def test_table_excitation_is_the_kernels_hermite_interpolant():
    # Closed form: the cubic Hermite through exact values and slopes of a cubic is exact.
    step = math.radians(0.5)
    nodes = np.arange(-0.2, 0.2 + step / 2, step)
    cubic = np.polynomial.Polynomial([1e-3, 2e-3, -3e-3, 4e-3])
    table = np.stack([cubic(nodes), cubic.deriv()(nodes), cubic.deriv(2)(nodes)])
    evaluate = table_excitation(table, step, nodes[0])
    x = np.linspace(-0.19, 0.19, 37)
    lift, slope, _ = evaluate(x)
    np.testing.assert_allclose(lift, cubic(x), rtol=0, atol=1e-15)
    np.testing.assert_allclose(slope, cubic.deriv()(x), rtol=0, atol=1e-14)
    assert valve.excitation_at(table, step, (0.05 - nodes[0]) / step, 1.0)[0] == pytest.approx(
        cubic(0.05), abs=1e-15
    )


def test_an_undamped_seat_returns_the_valve_to_its_height_bounce_after_bounce():
    # No seat, drive or external damping, drive far below: the valve falls on its spring,
    # lands on the seat and leaves it again with the same energy (the seat is a linear spring
    # while y < δ0), so every apex is the start height y0 and the energy
    # ½Mẏ² + ½ks y² + Ps0 y + ½kz (δ0 − y)²(y < δ0) stays what it was (closed form). With no
    # seat damping the seat force kz (δ0 − y) and the gap δ0 − y switch at one root: the
    # reference restarted each on the other at one angle until it gave up (an audit's valve).
    params = PARAMS.copy()
    params[[valve.P_DRIVE_DAMPING, valve.P_SEAT_DAMPING]] = 0.0
    params[valve.P_SPEED] = 2 * math.pi * 500 / 60
    params[valve.P_INITIAL_LIFT] = 1e-4
    theta = np.linspace(0.0, 1.0, 20001)

    solution = valve_reference(far_below, params, theta, rtol=1e-12, atol=1e-15)
    mass, ks, ps0, kz = params[[1, 4, 5, 6]]
    y, v = solution.lift, solution.velocity
    depth = ps0 / kz
    energy = 0.5 * mass * v**2 + 0.5 * ks * y**2 + ps0 * y
    energy += np.where(y < depth, 0.5 * kz * (depth - y) ** 2, 0.0)
    landings = sum(name == "seat_gap" for _, name in solution.switches) // 2
    assert landings >= 3  # it bounced, and more than once
    np.testing.assert_allclose(energy, energy[0], rtol=1e-8)
    apexes = y[1:-1][(y[1:-1] >= y[:-2]) & (y[1:-1] >= y[2:])]
    np.testing.assert_allclose(apexes, 1e-4, rtol=1e-6)


def test_an_undamped_seat_is_solved_through_grazing_bounces():
    # The audit's case in small: 500 rpm, seat 1e11 N/m with no seat damping, through closure
    # into the bounces, where a grazing bounce made the reference give up (more than 10 000
    # switches at one angle). Expected: the same reference with the seat damping at 1e-3
    # N·s/m (a damping ratio of 8e-9: nothing the lift feels), where the seat force and the
    # gap are two switches with two roots.
    params = PARAMS.copy()
    params[valve.P_SEAT_STIFFNESS] = 1e11
    params[valve.P_SPEED] = 2 * math.pi * 500 / 60
    theta = np.linspace(-1.6, 1.42, 201)
    lifts = []
    for damping in (0.0, 1e-3):
        params[valve.P_SEAT_DAMPING] = damping
        lifts.append(valve_reference(cosine_event, params, theta, rtol=1e-10, atol=1e-14).lift)
    np.testing.assert_allclose(lifts[0], lifts[1], rtol=0, atol=1e-10)  # m
