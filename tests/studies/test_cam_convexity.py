"""The cam scene warns of concave cams at ``check`` (issue 23, item 5), ``run --strict`` fails on
them, and their infinite contact stress is reported as inf, never as NaN."""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pytest

from studies.cli import main

POLY345 = """
name = "poly345_concave"
scene = "cam"
responses = ["max_contact_stress", "max_jerk"]
[parameters]
law = "poly345"
[factors.base_radius]
levels = [5.0, 12.5, 20.0]
[factors.rise_angle]
levels = [30.0, 50.0, 70.0]
"""
LIFT = 10.8  # mm: the cam scene's default lift


def convex_rise_angle(lift: float, base_radius: float) -> float:
    """Smallest rise angle β [deg] of the 3-4-5 polynomial (Norton: f = 10s³ − 15s⁴ + 6s⁵)
    with r0 + L f + L f''/β² > 0 over the rise, from the closed form on a fine grid."""
    s = np.linspace(0.0, 1.0, 200_001)
    f = 10 * s**3 - 15 * s**4 + 6 * s**5
    f2 = 60 * s - 180 * s**2 + 120 * s**3
    return math.degrees(math.sqrt(np.max(-lift * f2 / (base_radius + lift * f))))


def test_poly345_study_is_warned_at_check_and_strict_fails(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    study = tmp_path / "poly345.toml"
    study.write_text(POLY345, encoding="utf-8")
    assert main(["check", str(study)]) == 0
    quick = capsys.readouterr().err  # the advice's bisection is beyond a quick check's budget
    assert main(["check", "--full", str(study)]) == 0
    err = capsys.readouterr().err
    for point, (radius, beta) in enumerate(
        (r, b) for r in (5.0, 12.5, 20.0) for b in (30.0, 50.0, 70.0)
    ):
        expected = convex_rise_angle(LIFT, radius)
        assert expected > 70.0  # every point is concave: each one must be warned about
        warned = (
            rf"design point {point}: law = 'poly345' gives a concave cam at base_radius = "
            rf"{radius:g} mm, rise_angle = {beta:g} degree .*max_contact_stress is inf.*"
        )
        assert re.search(warned + "`check --full` finds the rise angle", quick), quick
        found = re.search(warned + r"convex from rise_angle = ([\d.]+) degree", err)
        assert found, f"point {point}: no warning in\n{err}"
        # the first 0.1° mark at or above the closed form's limit (none lies within 0.001°)
        assert abs(expected * 10 - round(expected * 10)) > 0.01
        assert float(found.group(1)) == pytest.approx(math.ceil(expected * 10) / 10, abs=1e-9)
    outputs = tmp_path / "out"
    assert main(["run", str(study), "--outputs", str(outputs), "--no-progress"]) == 0
    args = ["run", str(study), "--outputs", str(outputs), "--no-progress", "--strict", "--force"]
    assert main(args) == 3  # warned at check: --strict fails, as for a concave rocker cam
    assert "--strict" in capsys.readouterr().err
    assert main(args[:-1]) == 3  # the same result reused: the same warning, the same exit
    err = capsys.readouterr().err
    assert "--strict" in err
    assert "gives a concave cam" in err
    folder = max(outputs.glob("poly345_concave/*"))
    report = (folder / "report.md").read_text(encoding="utf-8")
    header = report[: report.index("## Design")]
    assert "inf in every design point with a value: not analysed" in header
    start = report.index("## Runs")
    runs = report[start : report.index("\n## ", start + 1)]
    assert "max_contact_stress [MPa]" in runs  # the column stays in the runs table
    assert runs.count("| inf |") == 9
    text = " ".join((folder / "analysis.txt").read_text(encoding="utf-8").split())
    assert "max_contact_stress" in text
    assert "inf in every design point with a value, so there is nothing to analyse" in text
    assert "NaN" not in text


def test_a_large_concave_grid_is_warned_in_a_few_lines_and_counted_right(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """3600 cam shapes: ten warned one by one, the rest counted in one line; the count is the
    closed form's (3-4-5 polynomial: concave below ``convex_rise_angle``), less at most 1 % of
    marginal cams a coarser scan may not see (their contact stress is still inf in ``run``)."""
    radii, betas = np.linspace(10.0, 40.0, 60), np.linspace(40.0, 110.0, 60)
    study = tmp_path / "grid.toml"
    study.write_text(
        POLY345.replace("[5.0, 12.5, 20.0]", str(radii.tolist()))
        .replace("[30.0, 50.0, 70.0]", str(betas.tolist()))
        .replace('name = "poly345_concave"', 'name = "poly345_grid"'),
        encoding="utf-8",
    )
    assert main(["check", "--full", str(study)]) == 0
    warnings = [w for w in capsys.readouterr().err.splitlines() if w.startswith("warning:")]
    assert len(warnings) == 11
    listed = [int(m) for w in warnings[:10] for m in re.findall(r"design point (\d+):", w)]
    convex_from = [convex_rise_angle(LIFT, r) for r in radii]
    truth = np.array([b < limit for limit in convex_from for b in betas])
    assert truth[listed].all()  # every cam warned one by one is concave
    more = re.search(r"(\d+) more concave cams at (\d+) more design points", warnings[-1])
    assert more, warnings[-1]
    reported = len(listed) + int(more.group(2))
    assert 0.99 * truth.sum() <= reported <= truth.sum()
