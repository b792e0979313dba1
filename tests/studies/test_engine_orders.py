"""The crank and reed scenes mean the same thing by "engine order k at speed n": a component at
k times the crankshaft frequency, k·n/60 Hz (physics §5, §6). The reed's crossing order and speed
are checked against the crank's torque harmonics through the physical frequency they share."""

from __future__ import annotations

import numpy as np
import pytest

from study_text import run, scene_study


def reed_crossing() -> tuple[float, float, float]:
    """(f₁ [Hz], crossing engine order, crossing speed [rpm]) of the physics §6 reference reed."""
    text = scene_study(
        "reed",
        responses='["first_frequency", "first_crossing_order", "first_crossing_speed"]',
        factors="[factors.thickness]\nlevels = [0.3]",
    )
    got = {k: float(v[0]) for k, v in run(text).scalars.items()}
    return got["first_frequency"], got["first_crossing_order"], got["first_crossing_speed"]


def test_crank_and_reed_agree_on_order_one_and_a_half_at_8172_rpm() -> None:
    f1, order, speed = reed_crossing()
    # The reference reed: f₁ = 204.3 Hz meets engine order 1.5 at n = 60 f₁/1.5 = 8172 rpm.
    assert f1 == pytest.approx(204.3, abs=0.05)
    assert order == 1.5
    assert speed == pytest.approx(60.0 * f1 / order, rel=1e-9)
    assert speed == pytest.approx(8172, abs=1)
    # One cylinder of the crank scene at that speed: its torque over the 720° cycle as a time
    # signal (t = α/ω). Its Fourier amplitude at the reed's f₁, computed here directly from the
    # samples, must be what the crank scene calls the amplitude of engine order 1.5.
    text = scene_study(
        "crank",
        parameters='layout = "inline"\ncylinders = 1\nfiring = "even"\nfiring_order = [1]',
        responses='["torque_order_1_5", "torque_order_3", "torque_order_0_5"]',
        curves='["engine_torque"]',
        factors=f"[factors.engine_speed]\nlevels = [{speed!r}]",
    )
    ev = run(text)
    torque = ev.curves["engine_torque"][0]
    angle = np.deg2rad(720.0 * np.arange(torque.size) / torque.size)
    t = angle / (2.0 * np.pi * speed / 60.0)
    amplitude = 2.0 / torque.size * abs(np.sum(torque * np.exp(-2j * np.pi * f1 * t)))
    assert amplitude == pytest.approx(float(ev.scalars["torque_order_1_5"][0]), rel=1e-6)
    # Read as harmonic numbers of the reed's event frequency (the old reed convention: "order
    # 3") the crank would name another component, of a clearly different amplitude.
    for other in ("torque_order_3", "torque_order_0_5"):
        assert abs(float(ev.scalars[other][0]) - amplitude) > 0.05 * amplitude
