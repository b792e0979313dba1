"""results.nc streamed chunk by chunk (studies.run.results_writer) against the Dataset built in
memory from the same evaluation (studies.run.results.build_dataset, the independent path)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from studies.define.plan import plan_text
from studies.pipeline import run_plan
from studies.run.results import build_dataset
from studies.run.results_writer import ResultsWriter
from studies.run.runner import chunks, evaluate

STUDY = """
name = "streamed"
scene = "cam"
responses = ["max_jerk", "min_radius_of_curvature", "jerk_ok", "radius_ok"]
curves = ["lift", "radius_of_curvature"]
[design]
type = "L9"
[factors.base_radius]
levels = [16.0, 18.0, 20.5]
units = "mm"
[factors.cam_speed]
levels = [1000.0, 1300.0, 1600.0]
[factors.seg2_width]
levels = [7.0, 9.0, 11.0]
"""


@pytest.mark.parametrize("chunk_size", [1, 4, 9, 64])
def test_streamed_file_equals_the_in_memory_dataset(tmp_path: Path, chunk_size: int) -> None:
    plan = plan_text(STUDY)
    attrs = {"run_id": "x", "git_dirty": True, "versions": {"numpy": np.__version__}}
    ev = evaluate(plan, chunk_size=chunk_size, progress=False)
    expected = build_dataset(plan, ev, attrs | {"timings": ev.timings})
    writer = ResultsWriter(plan, tmp_path / "results.nc", attrs, chunk_size)
    for part in reversed(list(chunks(plan.runs, chunk_size))):  # any order of completion
        writer.write(part, plan.scene.evaluate(
            {k: v[part] for k, v in plan.points.items()}, plan.settings,
            list(plan.responses), list(plan.definition.curves),
        ))  # fmt: skip
    path = writer.close({"timings": ev.timings})
    assert not list(tmp_path.glob("*.partial"))
    with xr.open_dataset(path) as streamed:
        xr.testing.assert_identical(streamed.load(), expected)
        assert streamed["jerk_ok"].dtype == np.int8
        assert streamed["lift"].dims == ("run", "cam_angle")


def test_a_run_streams_its_results_and_keeps_no_partial_file(tmp_path: Path) -> None:
    result = run_plan(plan_text(STUDY), tmp_path, chunk_size=2, progress=False)
    assert (result.folder / "results.nc").exists()
    assert not list(result.folder.glob("*.partial"))
    assert (result.folder / "analysis.nc").exists()
    ev = evaluate(plan_text(STUDY), progress=False)
    np.testing.assert_array_equal(result.dataset["max_jerk"].values, ev.scalars["max_jerk"])
    assert json.loads(result.dataset.attrs["timings"])["points_computed"] == 9
