"""Run records: checkpoints, resume after a failure, reuse of identical finished runs."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from studies import tracking
from studies.cli import main
from studies.plan import plan_text
from studies.study_run import resume_run, run_plan

STUDY = """
name = "resumable"
scene = "cam"
responses = ["max_jerk", "min_radius_of_curvature"]
design = "full_factorial"
[factors.base_radius]
levels = [16.0, 18.0, 20.0, 22.0]
[factors.cam_speed]
levels = [1000.0, 1300.0, 1600.0]
"""


def test_failed_run_resumes_from_its_last_finished_chunk(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    plan = plan_text(STUDY)
    scene = plan.scene
    original = scene.stages["geometry"]
    calls = {"n": 0}

    def failing_on_third_chunk(ctx):
        calls["n"] += 1
        if calls["n"] == 4:  # 1 warm-up call + chunks 0 and 1, then chunk 2 fails
            raise RuntimeError("simulated crash")
        return original(ctx)

    monkeypatch.setitem(scene.stages, "geometry", failing_on_third_chunk)
    with pytest.raises(RuntimeError, match="simulated crash"):
        run_plan(plan, tmp_path, chunk_size=3, progress=False)
    (folder,) = (tmp_path / "resumable").iterdir()
    record = json.loads((folder / "run.json").read_text())
    assert record["status"] == "failed"
    assert "simulated crash" in record["error"]
    assert sorted(p.name for p in (folder / "chunks").iterdir()) == ["000000.npz", "000001.npz"]

    monkeypatch.setitem(scene.stages, "geometry", original)
    resumed = resume_run(record["run_id"], tmp_path, progress=False)
    assert resumed.record.status == "finished"
    assert resumed.record.timings["points_computed"] == 6  # chunks 2 and 3 only
    assert not (folder / "chunks").exists()
    fresh = run_plan(plan_text(STUDY), tmp_path / "fresh", progress=False).dataset
    for name in ("max_jerk", "min_radius_of_curvature"):
        np.testing.assert_array_equal(resumed.dataset[name].values, fresh[name].values)


def test_identical_definition_on_clean_commit_is_reused(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.setattr("studies.provenance.git_state", lambda: ("c0ffee" * 6 + "cafe", False))
    study = tmp_path / "resumable.toml"
    study.write_text(STUDY)
    outputs = tmp_path / "outputs"
    args = ["run", str(study), "--outputs", str(outputs), "--no-progress"]
    assert main(args) == 0
    assert main(args) == 0
    assert "reusing run" in capsys.readouterr().out
    assert len(tracking.list_runs(outputs)) == 1
    assert main([*args, "--force"]) == 0
    assert len(tracking.list_runs(outputs)) == 2
