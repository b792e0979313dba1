"""A Dask cluster whose workers would compute with other code is refused before any chunk runs,
in one line naming the worker and the difference (a LocalCluster of worker processes: its
workers build their scene registry from what is installed, not from this process)."""

from __future__ import annotations

import sys
import threading
from pathlib import Path

import pytest

from studies.cli import main
from studies.run import cluster, provenance
from studies.run.runner import LOCAL_CLUSTER
from studies.scenes import SCENES, get_scene

distributed = pytest.importorskip("dask.distributed")
PLUGIN = Path(__file__).resolve().parents[1] / "plugin_scene"
OSCILLATOR = """
name = "oscillator_cluster"
scene = "oscillator"
responses = ["amplitude"]
[factors.drive_frequency]
levels = [3.0, 8.0]
"""
CAM = """
name = "cam_cluster"
scene = "cam"
responses = ["max_jerk"]
[factors.base_radius]
levels = [16.0, 18.0]
"""


@pytest.fixture(scope="module")
def address():
    with distributed.LocalCluster(
        n_workers=1, processes=True, threads_per_worker=1, **LOCAL_CLUSTER
    ) as cluster:
        yield cluster.scheduler_address


def run_on(address: str, tmp_path: Path, text: str) -> list[str]:
    study = tmp_path / "study.toml"
    study.write_text(text, encoding="utf-8")
    outputs = tmp_path / "out"
    argv = ["run", str(study), "--outputs", str(outputs), "--no-progress", "--scheduler", address]
    return [str(main(argv)), str(outputs.exists())]


def one_line_error(capsys: pytest.CaptureFixture[str]) -> str:
    err = capsys.readouterr().err.strip()
    assert "Traceback" not in err
    assert len(err.splitlines()) == 1, err
    return err


def test_a_scene_the_workers_lack_is_refused_before_any_chunk_runs(
    address: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys
) -> None:
    monkeypatch.syspath_prepend(str(PLUGIN))
    from oscillator_scene import OscillatorScene

    found = SCENES.plugins() | {"oscillator": OscillatorScene}  # registered here only
    monkeypatch.setattr(SCENES, "plugins", lambda: found)
    get_scene.cache_clear()
    try:
        assert run_on(address, tmp_path, OSCILLATOR) == ["2", "False"]  # nothing written
    finally:
        get_scene.cache_clear()
        sys.modules.pop("oscillator_scene", None)
    err = one_line_error(capsys)
    assert err.startswith(f"error: --scheduler {address}: worker tcp://")
    assert "scene 'oscillator' is not installed there (here: plugin" in err
    assert "nothing was run" in err


def test_another_engine_source_on_the_workers_is_refused(
    address: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys
) -> None:
    real = provenance.engine_code()
    edited = real | {"source_sha256": "0" * 64}  # this process runs an edited copy
    monkeypatch.setattr(provenance, "engine_code", lambda: edited)
    assert run_on(address, tmp_path, CAM) == ["2", "False"]
    err = one_line_error(capsys)
    assert (
        f"engine-studies {real['version']} (source {real['source_sha256'][:8]}) there, "
        f"{real['version']} (source 00000000) here"
    ) in err


def test_workers_with_the_same_code_run_the_study(address: str, tmp_path: Path, capsys) -> None:
    assert run_on(address, tmp_path, CAM) == ["0", "True"]
    assert "cam_cluster: 2 design points" in capsys.readouterr().out


def test_workers_that_never_answer_the_code_check_end_the_command(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """A hung worker: its first task (the code check) is given up after CHECK_TIMEOUT_S."""
    released = threading.Event()

    class HungClient:
        def run(self, *args: object, **kwargs: object) -> None:
            released.wait(30)  # a worker that never answers (released when the test ends)

    monkeypatch.setattr(cluster, "CHECK_TIMEOUT_S", 0.2)
    try:
        with pytest.raises(ValueError, match=r"did not answer the code check .* within 0.2 s"):
            cluster.check_workers(HungClient(), "tcp://10.0.0.1:8786", ["cam"])
    finally:
        released.set()
