"""The map of the probability of violating a limit over the two strongest control factors
(issue 27, item 5): in a small crossed study its cells equal a brute-force mean, over the runs
at each level pair, of each run's share of noise cases beyond the limit (counted here from the
results, not by the analysis).

Crank scene: the largest piston velocity is about (S/2) ω (1 + λ²/2) for a stroke S, crank
speed ω and rod ratio λ (the peak of [K3]): proportional to S and n, so across the levels
below the stroke moves it by ±6 %, the engine speed by ±4 % and the rod ratio by under 1 %. The two strongest
control factors are the stroke and the engine speed, and each cell averages the two rod-ratio
runs at its pair, whose probabilities differ (the limit cuts through the noise).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from studies.define.plan import plan_text
from studies.pipeline import run_plan

CROSSED = """
name = "crank_violation_map"
scene = "crank"
responses = ["max_piston_velocity"]
[design]
type = "full_factorial"
[factors.stroke]
levels = [150.0, 160.0, 170.0]
[factors.engine_speed]
levels = [2500.0, 2700.0]
[factors.rod_ratio]
levels = [0.25, 0.3]
[noise]
type = "sobol"
samples = 64
seed = 3
[noise.stroke]
distribution = "normal"
sd = 3
relative = true
[limits]
max_piston_velocity = { max = 22.0 }
"""
LIMIT = 22.0


@pytest.fixture(scope="module")
def crossed(tmp_path_factory: pytest.TempPathFactory):
    return run_plan(plan_text(CROSSED), tmp_path_factory.mktemp("outputs"), progress=False)


def test_the_map_is_the_mean_probability_per_level_pair(crossed) -> None:
    ds = crossed.dataset
    an = xr.open_dataset(crossed.folder / "analysis.nc")
    row = an.sel(noise_response="max_piston_velocity")
    assert str(row.violation_map_x.values) == "stroke"  # strongest: closed-form ranges above
    assert str(row.violation_map_y.values) == "engine_speed"
    assert "range analysis of max_piston_velocity_mean" in str(row.violation_map_basis.values)
    y = ds["max_piston_velocity"].transpose("run", "noise").values
    share = (y > LIMIT).mean(axis=1)  # each run's P, counted from the results
    sx, sy = ds["stroke_level"].values, ds["engine_speed_level"].values
    found = row["violation_map"].values
    averaged = 0
    for i in range(3):
        for j in range(2):
            runs = [r for r in range(ds.sizes["run"]) if sx[r] == i and sy[r] == j]
            assert len(runs) == 2  # the two rod ratios
            averaged += share[runs[0]] != share[runs[1]]
            assert found[i, j] == pytest.approx(sum(share[r] for r in runs) / 2, abs=1e-15)
    assert (row["violation_map_runs"].values[:3, :2] == 2).all()
    assert np.isnan(found[:, 2:]).all()  # engine speed has 2 levels of the 3 the frame holds
    assert averaged >= 3  # cells where picking one run instead of the mean would show


def test_the_robust_report_draws_the_map(crossed) -> None:
    folder: Path = crossed.folder
    png = folder / "violation_max_piston_velocity.png"
    assert png.read_bytes()[:4] == b"\x89PNG"
    report = (folder / "report.md").read_text(encoding="utf-8")
    assert (
        "![P(max_piston_velocity > 22 m/s) over the two strongest control factors]"
        "(violation_max_piston_velocity.png)"
    ) in report
    text = (folder / "analysis.txt").read_text(encoding="utf-8")
    assert "P(max_piston_velocity > 22 m/s) over stroke × engine_speed" in text
    assert "(2 design points per cell, over the other factors)" in text
