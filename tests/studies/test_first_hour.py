"""What a new user meets first: the README's own example runs, and what `check` passes,
`run` does not fail for a definition reason (issue: "The first hour of a new user")."""

from __future__ import annotations

import json
import math
import re
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from studies.cli import main
from studies.common.units import UNITS, conversion_factor
from studies.define.plan import plan_study
from studies.scenes import SCENES, get_scene
from studies.scenes.linkage.tappet import nose_tappet_lift
from study_text import readme_study


def test_readme_example_runs_to_the_end(tmp_path: Path) -> None:
    study = tmp_path / "my_cam.toml"
    study.write_text(readme_study(), encoding="utf-8")
    outputs = tmp_path / "outputs"
    assert main(["check", str(study)]) == 0
    assert main(["run", str(study), "--outputs", str(outputs)]) == 0
    (results,) = outputs.glob("my_cam/*/results.nc")
    with xr.open_dataset(results) as ds:
        assert ds.sizes["run"] == 12  # 3 base radii x 2 lifts x 2 cam speeds
        assert ds["cam_speed"].attrs["role"] == "operating"
        for response in ("max_contact_stress", "min_radius_of_curvature", "max_jerk"):
            assert ds[response].notnull().all()
        assert ds["acceleration"].dims == ("run", "cam_angle")


CLASHES = {
    "cam factor 'lift' with the curve 'lift'": """
name = "clash_cam"
scene = "cam"
responses = ["max_jerk"]
curves = ["lift"]
[factors.lift]
levels = [9.5, 10.8]
""",
    "valve factor 'valve_lift' with the curve 'valve_lift'": """
name = "clash_valve"
scene = "valve"
responses = ["max_lift"]
curves = ["valve_lift"]
[factors.valve_lift]
levels = [7.0, 7.815]
""",
}


@pytest.mark.parametrize("text", CLASHES.values(), ids=CLASHES.keys())
def test_check_refuses_a_factor_and_a_curve_of_one_name(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], text: str
) -> None:
    study = tmp_path / "clash.toml"
    study.write_text(text, encoding="utf-8")
    assert main(["check", str(study)]) == 2
    err = capsys.readouterr().err
    assert "factor and curve share the name" in err
    assert main(["run", str(study), "--outputs", str(tmp_path / "out")]) == 2
    assert not (tmp_path / "out").exists()


def test_valve_lift_can_be_a_factor(tmp_path: Path) -> None:
    # Was: "No variable named 'cam_angle'" after every point had run (a figure took the
    # factor coordinate valve_lift for the stored valve-lift curve).
    study = tmp_path / "valve_lift.toml"
    study.write_text(
        'name = "valve_lift_factor"\nscene = "valve"\nresponses = ["max_lift"]\n'
        "[factors.valve_lift]\nlevels = [7.0, 7.815]\n",
        encoding="utf-8",
    )
    assert main(["run", str(study), "--outputs", str(tmp_path / "out")]) == 0
    (results,) = (tmp_path / "out").glob("valve_lift_factor/*/results.nc")
    with xr.open_dataset(results) as ds:
        lift = ds["max_lift"].values
    # The valve follows the cam at the default speed: its peak scales with the cam's.
    assert lift[1] / lift[0] == pytest.approx(7.815 / 7.0, rel=0.02)


def test_every_unit_a_scene_declares_converts() -> None:
    # Was: a crank study asking for max_rod_angular_acceleration ended with "error: 'rad/s^2'".
    for name in SCENES:
        scene = get_scene(name)
        for item in (*scene.parameters, *scene.settings, *scene.responses, *scene.curves):
            units = getattr(item, "units", None)
            if units is None:
                continue
            assert units in UNITS, f"{name}.{item.name}: units {units!r} not in the table"
            assert conversion_factor(units, units) == 1.0


L18_WITH_A_CONCAVE_LAW = """
name = "law_l18"
scene = "valve"
responses = ["max_lift", "jump_speed"]
[design]
type = "L18"
[factors.law]
levels = ["six_segment", "polydyne"]
[factors.cam_speed]
levels = [3000.0, 4000.0, 5000.0]
[factors.spring_preload]
levels = [170.0, 205.8, 240.0]
"""


def test_points_that_did_not_run_are_reported_and_strict_fails(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # polydyne is not convex at the valve scene's default rise angle: its 9 of the 18 runs have
    # an invalid chain and give no value (counted here from the stored chain status).
    study = tmp_path / "law_l18.toml"
    study.write_text(L18_WITH_A_CONCAVE_LAW, encoding="utf-8")
    outputs = tmp_path / "out"
    assert main(["run", str(study), "--outputs", str(outputs), "--no-progress"]) == 0
    err = capsys.readouterr().err
    (folder,) = outputs.glob("law_l18/*")
    with xr.open_dataset(folder / "results.nc") as ds:
        chain_invalid = int((ds["chain_status"].values != 0).sum())
        no_value = int((~np.isfinite(ds["max_lift"].values)).sum())
    assert chain_invalid == no_value == 9
    assert "warning: 9 of 18 design points of law_l18 gave no value" in err
    report = (folder / "report.md").read_text(encoding="utf-8")
    assert report.index("**9 of 18 design points gave no value") < report.index("## Design")
    assert "9 of 18 design points" in (folder / "analysis.txt").read_text(encoding="utf-8")
    args = ["run", str(study), "--outputs", str(outputs), "--no-progress", "--strict", "--force"]
    assert main(args) == 3
    assert "--strict" in capsys.readouterr().err


# Closed-form rise laws f(s) and f''(s) on s ∈ [0, 1] (Norton, double-dwell functions),
# written here independently of engine_kernels.cam.lift_laws.
RISE_LAWS = {
    "cycloidal": (
        lambda s: s - np.sin(2 * np.pi * s) / (2 * np.pi),
        lambda s: 2 * np.pi * np.sin(2 * np.pi * s),
    ),
    "harmonic": (
        lambda s: 0.5 * (1 - np.cos(np.pi * s)),
        lambda s: 0.5 * np.pi**2 * np.cos(np.pi * s),
    ),
    "poly345": (
        lambda s: 10 * s**3 - 15 * s**4 + 6 * s**5,
        lambda s: 60 * s - 180 * s**2 + 120 * s**3,
    ),
}


def convex_rise_angle(law: str, lift: float, base_radius: float) -> float:
    """Smallest rise angle β [deg] with r0 + L f + L f''/β² > 0 over the rise: β² must exceed
    max(−L f''/(r0 + L f)) (f'' < 0 only where the cam could be concave)."""
    f, f2 = RISE_LAWS[law]
    s = np.linspace(0.0, 1.0, 200_001)
    return math.degrees(math.sqrt(np.max(-lift * f2(s) / (base_radius + lift * f(s)))))


def test_check_names_each_concave_law_and_the_rise_angle_that_makes_it_convex(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # Was: at the valve scene's default rise angle (70°) every standard law is concave, check
    # said OK, and the points ran without a value.
    laws = ["six_segment", *RISE_LAWS]
    study = tmp_path / "laws.toml"
    study.write_text(
        'name = "laws"\nscene = "valve"\nresponses = ["max_lift"]\n'
        f"[factors.law]\nlevels = {json.dumps(laws)}\n",
        encoding="utf-8",
    )
    assert main(["check", "--full", str(study)]) == 0  # 7 laws: more than a quick check scans
    err = capsys.readouterr().err
    plan = plan_study(str(study))
    lift = nose_tappet_lift(plan.points, 0)
    base_radius = float(plan.points["base_radius"][0])
    for i, law in enumerate(laws[1:], start=1):
        expected = convex_rise_angle(law, lift, base_radius)
        assert expected > 70.0, law  # concave at the default: the warning must be there
        found = re.search(
            rf"design point {i}: law = '{law}' gives a concave cam at rise_angle = 70 degree"
            r".*convex from rise_angle = ([\d.]+) degree",
            err,
        )
        assert found, f"{law}: no warning in\n{err}"
        assert float(found.group(1)) == pytest.approx(expected, abs=0.2)
    assert "six_segment" not in err  # convex: no warning
