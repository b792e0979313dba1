"""The ``reed`` scene: the shipped study, the physics §6 reference reed, checks, mode shapes."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import brentq

from studies.common.figure_layout import save_figures
from studies.define.definition import StudyFileError
from studies.define.plan import plan_study, plan_text
from studies.pipeline import run_plan
from studies.run.results import build_dataset
from studies.run.runner import evaluate
from studies.scenes import get_scene
from studies.scenes.reed.campbell import campbell_figure
from study_text import scene_study

# Material table documented in studies/scenes/reed.py: E [Pa], ρ [kg/m³].
MATERIALS = {
    "spring_steel": (208e9, 7800.0),
    "stainless": (193e9, 7900.0),
    "glass_epoxy": (18.6e9, 1850.0),
}
# First root of cos X cosh X = −1 [B1] from scipy's brentq in (π/2, π), independent of the kernel.
X1 = brentq(lambda x: math.cos(x) * math.cosh(x) + 1.0, 1.0, 3.0, xtol=1e-15, rtol=1e-15)


def f1_closed_form(length, thickness, modulus, density):
    """[B2] with I/A = h²/12: f₁ = X₁²/(2π l²) √(E h²/(12 ρ))  [Hz] (SI inputs)."""
    return X1**2 / (2 * math.pi * length**2) * math.sqrt(modulus * thickness**2 / (12 * density))


def study(
    parameters: str = "",
    responses: str = '["first_frequency"]',
    curves: str = "[]",
    factors: str = "[factors.length]\nlevels = [30.0, 35.0]",
) -> str:
    return scene_study(
        "reed", parameters=parameters, responses=responses, curves=curves, factors=factors
    )


def test_reed_resonance_runs_and_reports_the_reference_reed(tmp_path: Path) -> None:
    result = run_plan(plan_study("reed_resonance"), tmp_path, progress=False)
    ds = result.dataset
    assert ds.sizes["run"] == 75
    assert ds["first_frequency"].attrs["units"] == "Hz"
    assert ds["first_margin"].attrs["units"] == "Hz"
    assert ds["resonance_speed"].attrs["units"] == "rpm"
    assert ds["length"].attrs["units"] == "mm"
    assert set(ds["material"].values) == set(MATERIALS)
    assert (result.folder / "frequency_map.png").stat().st_size > 10_000
    for run in range(ds.sizes["run"]):
        modulus, density = MATERIALS[str(ds["material"].values[run])]
        f1 = f1_closed_form(
            float(ds["length"][run]) * 1e-3, float(ds["thickness"][run]) * 1e-3, modulus, density
        )
        assert float(ds["first_frequency"][run]) == pytest.approx(f1, rel=1e-12)
        # The band is n/120 Hz for 1200–9000 rpm (physics §6): 10–75 Hz.
        margin = max(f1 - 75.0, 10.0 - f1)
        assert float(ds["first_margin"][run]) == pytest.approx(margin, rel=1e-12)
        assert int(ds["first_mode_clear"][run]) == int(margin > 0)
    # The physics §6 reference reed (l = 35, h = 0.3 mm, steel) is reported to 4 significant
    # figures with its margin to the band: f1 = 204.3 Hz, 129.3 Hz above 75 Hz.
    f1 = f1_closed_form(35e-3, 0.3e-3, 2.08e11, 7800.0)
    assert f"{f1:.4g}" == "204.3"
    text = (result.folder / "analysis.txt").read_text(encoding="utf-8")
    rows = [
        line.split()
        for line in text.splitlines()
        if line.split()[:3] == ["35.0", "0.30", "spring_steel"]
    ]
    assert len(rows) == 1
    assert rows[0][3:] == [f"{f1:.4g}", "10–75", f"{f1 - 75:.4g}", "outside", "the", "band"]


@pytest.mark.parametrize(
    ("parameters", "factors", "expected"),
    [
        (
            "",
            "[factors.length]\nlevels = [-35.0, 35.0]",
            "length = -35 mm is physically impossible",
        ),
        (
            "speed_min = 9000.0\nspeed_max = 1200.0",
            "[factors.length]\nlevels = [30.0, 35.0]",
            "design points 0–1: speed_min = 9000 rpm must be below speed_max = 1200 rpm",
        ),
        (
            "",
            "[factors.thickness]\nlevels = [0.3, 5.0]",
            "design point 1: length/thickness = 35 mm / 5 mm = 7 is below 10",
        ),
        (
            'material = "unobtainium"',
            "[factors.length]\nlevels = [30.0, 35.0]",
            "material = 'unobtainium' is not allowed",
        ),
    ],
)
def test_bad_parameters_give_clear_messages(parameters: str, factors: str, expected: str) -> None:
    with pytest.raises(StudyFileError) as info:
        plan_text(study(parameters=parameters, factors=factors))
    assert expected in str(info.value)


def test_custom_material_and_two_stroke_band() -> None:
    # Aluminium-like custom reed on a two-stroke: band n/60 Hz, 1200–9000 rpm → 20–150 Hz.
    ev = evaluate(
        plan_text(
            study(
                parameters=(
                    'material = "custom"\nyoungs_modulus = 70.0\ndensity = 2700.0\n'
                    'cycle = "two_stroke"'
                ),
                responses='["first_frequency", "band_min", "band_max", "first_margin"]',
            )
        ),
        progress=False,
    )
    for i, length in enumerate([30e-3, 35e-3]):
        f1 = f1_closed_form(length, 0.3e-3, 70e9, 2700.0)
        assert ev.scalars["first_frequency"][i] == pytest.approx(f1, rel=1e-12)
        assert ev.scalars["first_margin"][i] == pytest.approx(f1 - 150.0, rel=1e-12)
    np.testing.assert_allclose(ev.scalars["band_min"], 20.0, rtol=1e-12)
    np.testing.assert_allclose(ev.scalars["band_max"], 150.0, rtol=1e-12)


def test_mode_shape_curves_and_figure(tmp_path: Path) -> None:
    plan = plan_text(study(curves='["mode_shape_1", "mode_shape_2"]'))
    ev = evaluate(plan, progress=False)
    ds = build_dataset(plan, ev, {})
    xi = ds["position"].values
    assert ds["position"].attrs["units"] == "1"
    assert xi.size == 51
    assert xi[0] == 0.0
    assert xi[-1] == 1.0
    # Classic clamped–free shape (Blevins Table 4.2) with σ from X₁, scaled to a unit tip.
    sigma = (math.cos(X1) + math.cosh(X1)) / (math.sin(X1) + math.sinh(X1))
    z = X1 * xi
    w = np.cosh(z) - np.cos(z) - sigma * (np.sinh(z) - np.sin(z))
    np.testing.assert_allclose(ds["mode_shape_1"].values[0], w / w[-1], atol=1e-12)
    assert ds["mode_shape_2"].values[0, -1] == pytest.approx(1.0)
    paths = save_figures(ds, tmp_path, get_scene("reed").figures())
    assert [p.name for p in paths] == ["mode_shapes.png"]
    assert paths[0].stat().st_size > 5_000


ORDER_RESPONSES = (
    '["first_frequency", "first_crossing_order", "first_crossing_speed", "first_order_margin", '
    '"second_crossing_order", "resonance_free", "first_mode_clear", "events_per_revolution", '
    '"band_min", "band_max"]'
)


def reference_orders(cycle: str, thickness: float = 0.3) -> dict[str, float]:
    """Order responses of the physics §6 reference reed (one design point) for a cycle."""
    text = study(
        parameters=f'cycle = "{cycle}"',
        responses=ORDER_RESPONSES,
        factors=f"[factors.thickness]\nlevels = [{thickness}]",
    ).replace("[factors.length]\nlevels = [30.0, 35.0]", "")
    ev = evaluate(plan_text(text), progress=False)
    return {k: float(v[0]) for k, v in ev.scalars.items()}


@pytest.mark.parametrize(("cycle", "events"), [("four_stroke", 0.5), ("two_stroke", 1.0)])
def test_reference_reed_crosses_the_order_the_closed_form_says(cycle: str, events: float) -> None:
    # Closed form: harmonic k of the event frequency is engine order o = k e (multiples of the
    # crankshaft frequency) and meets f₁ at n = 60 f₁/o rpm. 1200–9000 rpm holds k = 3 only for
    # a four-stroke (e = 1/2: 24 516, 12 258, 8172, 6129 … rpm; engine order 1.5) and k = 2 for
    # a two-stroke (e = 1: 12 258, 6129 rpm; engine order 2). Default max_order = 3.
    f1 = f1_closed_form(35e-3, 0.3e-3, *MATERIALS["spring_steel"])
    got = reference_orders(cycle)
    speeds = {k: 60 * f1 / (k * events) for k in range(1, round(3 / events) + 1)}
    inside = [k for k, n in speeds.items() if 1200 <= n <= 9000]
    assert got["events_per_revolution"] == events
    assert inside[0] == (3 if cycle == "four_stroke" else 2)
    assert got["first_crossing_order"] == inside[0] * events == (1.5 if events == 0.5 else 2)
    assert got["first_crossing_speed"] == pytest.approx(speeds[inside[0]], rel=1e-9)
    if cycle == "four_stroke":
        assert got["first_crossing_speed"] == pytest.approx(8172, rel=1e-3)
        assert all(speeds[k] > 9000 for k in (1, 2))  # orders 0.5 and 1 do not cross
    # Depth into the crossing order's band [k f_min, k f_max] to its nearest edge (< 0).
    band = inside[0] * got["band_min"], inside[0] * got["band_max"]
    assert got["first_order_margin"] == pytest.approx(max(f1 - band[1], band[0] - f1), rel=1e-9)
    assert got["first_order_margin"] < 0
    # The first-order verdict alone says "clear" (the source's conclusion); the orders do not.
    assert got["first_mode_clear"] == 1
    assert got["resonance_free"] == 0


def test_a_stiff_reed_above_engine_order_3_is_resonance_free() -> None:
    # Engine order 3 is the sixth harmonic of a four-stroke's event frequency: f₁ must exceed
    # 6 × 9000/120 Hz × 1.05 = 472.5 Hz; h = 0.7 mm gives f₁ = 204.3 × 0.7/0.3.
    f1 = f1_closed_form(35e-3, 0.7e-3, *MATERIALS["spring_steel"])
    assert f1 > 6 * 9000 / 120 * 1.05
    got = reference_orders("four_stroke", thickness=0.7)
    assert got["resonance_free"] == 1
    assert math.isnan(got["first_crossing_order"])
    assert math.isnan(got["first_crossing_speed"])
    assert got["first_order_margin"] == pytest.approx(f1 - 6 * 9000 / 120, rel=1e-9)
    # ... and one just inside the ±5 % margin of engine order 3 is not.
    near = (
        0.3e-3 * (6 * 9000 / 120 * 1.03) / f1_closed_form(35e-3, 0.3e-3, *MATERIALS["spring_steel"])
    )
    assert reference_orders("four_stroke", thickness=near * 1e3)["resonance_free"] == 0


def test_reed_resonance_writes_a_campbell_diagram(tmp_path: Path) -> None:
    result = run_plan(plan_study("reed_resonance"), tmp_path, progress=False)
    assert (result.folder / "campbell.png").stat().st_size > 20_000
    text = (result.folder / "study.toml").read_text(encoding="utf-8")
    assert "from the event frequency alone" in text
    assert result.dataset["resonance_free"].values.min() == 0
    ax = campbell_figure(result.dataset.load()).axes[0]
    assert ax.get_xlabel() == "engine speed [rpm]"
    assert ax.get_ylabel() == "frequency [Hz]"
    order_lines = [line for line in ax.get_lines() if len(line.get_xdata()) == 2]
    assert len(order_lines) == 6  # engine orders 0.5, 1, …, 3 (max_order)
    assert "engine orders 0.5…3" in ax.get_title()
    (marks,) = [line for line in ax.get_lines() if line.get_marker() == "o"]
    # every marked crossing sits on its engine-order line: f = o n / 60
    ds = result.dataset
    crossing = np.isfinite(ds["first_crossing_speed"].values)
    expected = ds["first_crossing_order"].values * ds["first_crossing_speed"].values / 60
    np.testing.assert_allclose(expected[crossing], ds["first_frequency"].values[crossing])
    assert len(marks.get_xdata()) >= crossing.sum() > 0
