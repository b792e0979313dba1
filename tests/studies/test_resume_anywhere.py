"""A run stopped at any chunk boundary resumes to the same numbers (issue 18, item 4): for two
scenes, hypothesis picks the chunk size and the checkpoint at which the run dies (the write of
that chunk fails, as a kill or a full disk would end it there); the resumed results must equal,
bit for bit, those of a run that was never interrupted."""

from __future__ import annotations

import errno
import os
import tempfile
from pathlib import Path
from unittest import mock

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from run_faults import failing_on_call

from studies import pipeline
from studies.cli import EXIT_OUTPUT_ERROR, main
from studies.run.results import open_results
from studies.tracking.store import RunStore

STUDIES = {
    "cam": (
        'name = "anywhere_cam"\nscene = "cam"\nresponses = ["max_jerk", "max_contact_stress"]\n'
        "[factors.base_radius]\nlevels = [16.0, 18.0, 20.0, 22.0]\n"
        "[factors.cam_speed]\nlevels = [1000.0, 1300.0, 1600.0]\n"
    ),
    "crank": (
        'name = "anywhere_crank"\nscene = "crank"\n'
        'responses = ["max_piston_velocity", "max_rod_angle"]\n'
        "[factors.rod_ratio]\nlevels = [0.2, 0.25, 0.3]\n"
        "[factors.engine_speed]\nlevels = [1000.0, 2000.0, 3000.0, 4000.0]\n"
    ),
}
POINTS = 12


def results(outputs: Path) -> dict[str, np.ndarray]:
    (row,) = RunStore(outputs).list_runs()
    assert row["status"] == "finished"
    ds = open_results(Path(row["folder"]) / "results.nc")
    return {str(name): ds[name].values for name in ds.data_vars}


def run(study: Path, outputs: Path, *extra: str) -> int:
    return main(["run", str(study), "--outputs", str(outputs), "--no-progress", *extra])


@pytest.fixture(scope="module")
def uninterrupted(tmp_path_factory: pytest.TempPathFactory) -> dict[str, dict[str, np.ndarray]]:
    out = {}
    for scene, text in STUDIES.items():
        folder = tmp_path_factory.mktemp(scene)
        study = folder / "study.toml"
        study.write_text(text, encoding="utf-8")
        assert run(study, folder / "outputs") == 0
        out[scene] = results(folder / "outputs")
    return out


@pytest.mark.parametrize("scene", STUDIES)
@settings(max_examples=12, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(data=st.data())
def test_a_run_stopped_at_any_checkpoint_resumes_to_the_same_numbers(
    uninterrupted: dict[str, dict[str, np.ndarray]], scene: str, data: st.DataObject
) -> None:
    chunk = data.draw(st.integers(1, POINTS), label="chunk size")
    chunks = -(-POINTS // chunk)
    dies_at = data.draw(st.integers(1, chunks), label="checkpoint that fails")
    with tempfile.TemporaryDirectory() as tmp:
        study = Path(tmp) / "study.toml"
        study.write_text(STUDIES[scene], encoding="utf-8")
        outputs = Path(tmp) / "outputs"
        crash = OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        failing = failing_on_call(pipeline._save_chunk, dies_at, crash)
        with mock.patch.object(pipeline, "_save_chunk", failing):
            assert run(study, outputs, "--chunk-size", str(chunk)) == EXIT_OUTPUT_ERROR
        (row,) = RunStore(outputs).list_runs()
        assert row["status"] == "failed"
        kept = sorted((Path(row["folder"]) / "chunks").glob("*.npz"))
        assert len(kept) == dies_at - 1  # every chunk before the failing one was kept
        assert main(["run", "--resume", row["run_id"], "--outputs", str(outputs)]) == 0
        resumed = results(outputs)
    expected = uninterrupted[scene]
    assert resumed.keys() == expected.keys()
    for name, values in expected.items():
        np.testing.assert_array_equal(resumed[name], values, err_msg=name)
