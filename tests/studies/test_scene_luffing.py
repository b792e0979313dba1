"""The ``luffing`` scene: the shipped sizing study, every check as value/limit/pass, messages."""

from __future__ import annotations

import json
import math
import re
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from studies.define.definition import StudyFileError
from studies.define.plan import plan_study, plan_text
from studies.pipeline import run_plan
from studies.run.runner import evaluate
from study_text import scene_study

CHECKS = {  # check → (value, limit, value must be ≤ limit)
    "motor": ("motor_power", "motor_rated_power", True),
    "ratio": ("implied_ratio", "belt_ratio", None),
    "coupling": ("coupling_torque", "coupling_limit", True),
    "deflection": ("deflection", "deflection_limit", True),
    "slope": ("slope", "slope_limit", True),
    "key": ("key_stress", "key_limit", True),
    "bearing": ("bearing_life", "bearing_limit", False),
}


def study(
    parameters: str = "",
    responses: str = '["motor_power"]',
    factors: str = "[factors.trolley_mass]\nlevels = [5.0, 10.0]",
) -> str:
    return scene_study("luffing", parameters=parameters, responses=responses, factors=factors)


def test_luffing_sizing_runs_with_every_check_as_value_limit_pass(tmp_path: Path) -> None:
    result = run_plan(plan_study("luffing_sizing"), tmp_path, progress=False)
    ds = result.dataset
    assert ds.sizes["run"] == 27
    units = {
        "motor_power": "W",
        "deflection": "mm",
        "coupling_torque": "N*m",
        "key_stress": "MPa",
        "bearing_life": "h",
        "slope": "rad",
        "all_checks_ok": "1",
    }
    for name, unit in units.items():
        assert ds[name].attrs["units"] == unit
    for name in ("pass_fail_map.png", "motor_power.png"):
        assert (result.folder / name).stat().st_size > 10_000
    # Each flag agrees with its value and limit (ratio: within 5 % of the 1:1 belt).
    for check, (value, limit, at_most) in CHECKS.items():
        v, lim = ds[value].values, ds[limit].values
        if at_most is None:
            expected = np.abs(v - lim) <= 0.05 * lim
        else:
            expected = v <= lim if at_most else v >= lim
        np.testing.assert_array_equal(ds[f"{check}_ok"].values, expected.astype(int))
    flags = np.stack([ds[f"{c}_ok"].values for c in CHECKS])
    np.testing.assert_array_equal(ds["all_checks_ok"].values, flags.min(axis=0))
    # Reference point a = 20 m/s², m = 5 kg, V = 0.5 m/s, by hand from the physics §7 inputs:
    # Fw = 20·5 + 0.2·0.5 + 0.2·5·10 = 110.1 N, P0 = Fw V/(0.96 · 0.99 · 0.98 · 0.98) = 60.31 W.
    ref = ds.isel(
        run=int(
            np.flatnonzero(
                (ds["trolley_mass"].values == 5.0)
                & (ds["trolley_acceleration"].values == 20.0)
                & (ds["trolley_speed"].values == 0.5)
            )[0]
        )
    )
    assert float(ref["motor_power"]) == pytest.approx(110.1 * 0.5 / (0.96 * 0.99 * 0.98 * 0.98))
    assert float(ref["motor_rated_power"]) == 100.0
    # Tube [L2] in N and mm: y = (40 + 13.6)·1467³/(48·206000·π(16⁴ − 8⁴)/64) = 5.674 mm.
    deflection = 53.6 * 1467**3 / (48 * 206000 * math.pi * (16**4 - 8**4) / 64)
    assert float(ref["deflection"]) == pytest.approx(deflection, rel=1e-12)
    # Implied reduction ω_motor d/(2V), d = 12.7·20/π mm: ≈ 16.9 instead of the 1:1 belt.
    implied = 2000 * math.pi / 30 * 12.7e-3 * 20 / math.pi / (2 * 0.5)
    assert float(ref["implied_ratio"]) == pytest.approx(implied, rel=1e-12)
    text = (result.folder / "analysis.txt").read_text(encoding="utf-8")
    assert "Design checks (value and limit over the design points)" in text
    assert "Failing checks per design point" in text
    assert "0 of 27" in text  # the ratio check fails everywhere (the source's 1:1 belt)


def test_no_listed_motor_fails_the_motor_check() -> None:
    # m = 10 kg needs P0 = (20·10 + 0.1 + 0.2·10·10)·0.5/0.9508 = 115.7 W > 100 W, the largest.
    ev = evaluate(
        plan_text(
            study(
                parameters="motor_ratings = [50.0, 100.0]",
                responses=json.dumps(
                    [
                        "motor_power",
                        "motor_rated_power",
                        "selected_motor",
                        "checks_passed",
                        "all_checks_ok",
                    ]
                    + [f"{c}_ok" for c in CHECKS]
                ),
            )
        ),
        progress=False,
    )
    flags = np.stack([ev.scalars[f"{c}_ok"] for c in CHECKS])
    # Without a motor the checks that need one are not evaluated (stored as -1), not failed.
    needs_motor = [list(CHECKS).index(c) for c in ("coupling", "key", "bearing")]
    assert np.isnan(flags[needs_motor, 1]).all()
    assert not np.isnan(np.delete(flags[:, 1], needs_motor)).any()
    assert not np.isnan(flags[:, 0]).any()
    np.testing.assert_array_equal(ev.scalars["checks_passed"], (flags == 1.0).sum(axis=0))
    assert ev.scalars["all_checks_ok"].tolist() == [flags[:, 0].min(), 0.0]  # the motor fails
    assert ev.scalars["motor_ok"].tolist() == [1.0, 0.0]
    assert ev.scalars["selected_motor"][0] == 2.0
    assert ev.scalars["motor_power"][1] == pytest.approx(220.1 * 0.5 / (0.96 * 0.99 * 0.98 * 0.98))
    assert np.isnan(ev.scalars["motor_rated_power"][1])
    assert np.isnan(ev.scalars["selected_motor"][1])


def test_checks_not_evaluated_are_left_out_of_the_level_means(tmp_path: Path) -> None:
    # Without a motor the coupling check is stored as -1 ("not evaluated"); averaged as a
    # value, it gave a pass flag the level means -0.75 and -1 (an audit's study).
    text = study(
        parameters="motor_ratings = [50.0, 100.0]",
        responses='["coupling_ok", "motor_ok"]',
        factors="[factors.trolley_mass]\nlevels = [5.0, 6.0, 10.0]\n"
        "[factors.trolley_speed]\nlevels = [0.4, 0.5]",
    )
    result = run_plan(plan_text(text), tmp_path, progress=False)
    flags = result.dataset["coupling_ok"].values
    assert (flags == -1).any()
    assert (flags >= 0).any()
    analysis = xr.open_dataset(result.folder / "analysis.nc")
    for term in ("trolley_mass", "trolley_speed"):
        codes = result.dataset[f"{term}_level"].values
        k = analysis["k"].sel(response="coupling_ok", term=term).values
        left = analysis["left_out"].sel(response="coupling_ok", term=term).values
        for level in range(k.size):
            mine = flags[(codes == level) & (flags >= 0)]  # brute force over the runs
            expected = mine.mean() if mine.size else np.nan
            np.testing.assert_equal(k[level], expected)
            assert left[level] == ((codes == level) & (flags == -1)).sum()
    # analysis.txt counted the passes as the sum of the flags: "-56 of 64" after this change
    text = (result.folder / "analysis.txt").read_text(encoding="utf-8")
    passes, unknown, n = (flags == 1).sum(), (flags == -1).sum(), flags.size
    assert re.search(rf"\n *coupling .* {passes} of {n} \({unknown} not evaluated\)\n", text)
    motor = result.dataset["motor_ok"].values
    lines = text.split("Failing checks per design point\n")[1].splitlines()[1:]
    for line, fails in zip(lines, motor == 0, strict=False):
        assert line.endswith("motor; not evaluated: coupling" if fails else "none")


@pytest.mark.parametrize(
    ("parameters", "factors", "expected"),
    [
        (
            "tube_inner_diameter = 16.0",
            "[factors.trolley_mass]\nlevels = [5.0, 10.0]",
            (
                "design points 0–1: tube_inner_diameter = 16 mm must be smaller than "
                "tube_outer_diameter = 16 mm"
            ),
        ),
        (
            "motor_ratings = [100.0, 50.0]",
            "[factors.trolley_mass]\nlevels = [5.0]",
            "motor_ratings = [100, 50] W must be positive and strictly ascending",
        ),
        (
            "",
            "[factors.trolley_mass]\nlevels = [-5.0, 5.0]",
            "trolley_mass = -5 kg is physically impossible",
        ),
        (
            "",
            "[factors.tube_span]\nlevels = [-1467.0]",
            "tube_span = -1467 mm is physically impossible",
        ),
    ],
)
def test_bad_parameters_give_clear_messages(parameters: str, factors: str, expected: str) -> None:
    with pytest.raises(StudyFileError) as info:
        plan_text(study(parameters=parameters, factors=factors))
    assert expected in str(info.value)
