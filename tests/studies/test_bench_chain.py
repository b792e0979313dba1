"""Benchmark figures of the multi-mass spring kernel [V4] (studies/scenes/valve/bench/multi_mass.py).

Timings are never asserted (shared machines); what is checked is that the chain rows are the
lumped valve train with the spring modelled as N masses (the [V1] equivalent mass
``M_v + m_s/3`` recovered exactly, and far below surge the same max lift as the lumped run:
the one-third rule, [V1]) and that every N gets its timings and consistent ratios.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from engine_kernels import valvetrain as valve
from engine_kernels.valvetrain.spring_chain import layout
from engine_kernels.valvetrain.spring_chain.one_case import spring_chain_response_batch
from studies.scenes.valve.bench.multi_mass import (
    CHAIN_MASSES,
    SPRING_MASS,
    chain_figures,
    chain_rows,
)

RPM = 2 * math.pi / 60
LUMPED = np.array([3500 * RPM, 0.04252, 1.17e7, 150.0, 3.0e4, 205.8, 5e7, 900.0, 0.0, 0.0, 0.0])


def cosine_event_table(step_deg=0.5):
    """1 − cos event of 8 mm lift over ±80° cam (as tests/engine_kernels), rows Y, Y', Y''."""
    theta = np.radians(np.arange(-100.0, 110.0 + step_deg / 4, step_deg / 2))
    wave, inside = math.pi / 1.4, np.abs(theta) < 1.4
    rows = (
        np.where(inside, 4e-3 * (1 + np.cos(wave * theta)), 0.0),
        np.where(inside, -4e-3 * wave * np.sin(wave * theta), 0.0),
        np.where(inside, -4e-3 * wave**2 * np.cos(wave * theta), 0.0),
    )
    return np.stack(rows), math.radians(step_deg / 2), theta[0]


def test_chain_rows_are_the_lumped_valve_train_with_a_spring_of_n_masses():
    rows = np.tile(LUMPED, (3, 1))
    rows[:, valve.P_SPEED] = np.array([500.0, 3000.0, 6000.0]) * RPM
    chain = chain_rows(rows, 8)
    assert chain.shape == (3, len(layout.CHAIN_PARAM_NAMES))
    np.testing.assert_array_equal(chain[:, layout.SC_SPEED], rows[:, valve.P_SPEED])
    np.testing.assert_allclose(
        chain[:, layout.SC_VALVE_MASS] + SPRING_MASS / 3, rows[:, valve.P_MASS], rtol=1e-15
    )
    assert (chain[:, layout.SC_SPRING_MASSES] == 8).all()
    assert (chain[:, layout.SC_CLASH_STIFFNESS] == 0.0).all()
    excitation, step, start = cosine_event_table()
    settings = valve.valve_settings()
    lumped = np.empty((3, len(valve.VALVE_OUTPUT_NAMES)))
    valve.valve_response_batch(excitation, step, start, rows, settings, lumped)
    out = np.empty((3, len(layout.CHAIN_OUTPUT_NAMES)))
    spring_chain_response_batch(excitation, step, start, chain, settings, out)
    assert (out[:, layout.CO_STATUS] == valve.STATUS_OK).all()
    # 500 rpm, far below surge: the one-third rule holds (test_spring_chain.py: within 5e-8 m).
    assert out[0, layout.CO_MAX_LIFT] == pytest.approx(lumped[0, valve.O_MAX_LIFT], abs=5e-8)


def test_chain_figures_time_every_n_and_give_consistent_ratios():
    rows = np.tile(LUMPED, (40, 1))
    rows[:, valve.P_SPEED] = np.linspace(3000.0, 6000.0, 40) * RPM
    figures = chain_figures(cosine_event_table(), rows, valve.valve_settings(), repeat=1)
    lumped = figures["lumped_lanes"]["cases_per_s"]
    assert figures["lumped_lanes"]["cases"] == 40
    for masses in CHAIN_MASSES:
        lanes, one_case = figures[f"n{masses}_lanes"], figures[f"n{masses}_one_case"]
        assert lanes["cases"] == one_case["cases"] == 40
        assert lanes["cases_per_s"] > 0.0
        ratio = figures[f"n{masses}_lanes_over_lumped_lanes"]
        assert ratio == pytest.approx(lanes["cases_per_s"] / lumped)
        ratio = figures[f"n{masses}_lanes_over_one_case"]
        assert ratio == pytest.approx(lanes["cases_per_s"] / one_case["cases_per_s"])
