"""Results are identical whichever executor ran the chunks (physics §8)."""

from __future__ import annotations

import multiprocessing
import pickle
import socket
from concurrent.futures import Executor, Future, ProcessPoolExecutor, ThreadPoolExecutor

import numpy as np
import pytest

from studies.define.plan import plan_text
from studies.run import runner
from studies.run.runner import LOCAL_CLUSTER, evaluate

STUDY = """
name = "executors"
scene = "cam"
responses = ["max_contact_stress", "max_jerk", "radius_ok"]
curves = ["lift"]
design = "full_factorial"
[factors.base_radius]
levels = [16.0, 18.0, 20.0, 22.0, 24.0]
[factors.cam_speed]
levels = [1000.0, 1300.0, 1600.0]
"""


@pytest.fixture(scope="module")
def serial():
    return evaluate(plan_text(STUDY), chunk_size=4, progress=False)


# Same code gives bit-identical results. A kernel freshly JIT-compiled in one process and the
# same kernel loaded from the disk cache in another may contract multiply-adds differently
# (fastmath "contract"), which moves a value by an ulp: rtol 1e-14 allows that and nothing more.
RTOL = 1e-14


def assert_same(a, b) -> None:
    for name in a.scalars:
        np.testing.assert_allclose(a.scalars[name], b.scalars[name], rtol=RTOL, err_msg=name)
    np.testing.assert_allclose(a.curves["lift"], b.curves["lift"], rtol=RTOL, atol=0)


def test_thread_pool_gives_identical_results(serial) -> None:
    with ThreadPoolExecutor(max_workers=2) as pool:
        threaded = evaluate(plan_text(STUDY), chunk_size=4, progress=False, executor=pool)
    assert_same(serial, threaded)


def test_process_pool_gives_identical_results(serial) -> None:
    # spawn, not fork: the parent's compiled kernels run on a threading layer (OpenMP/TBB)
    # that must not be forked
    spawn = multiprocessing.get_context("spawn")
    with ProcessPoolExecutor(max_workers=2, mp_context=spawn) as pool:
        pooled = evaluate(plan_text(STUDY), chunk_size=4, progress=False, executor=pool)
    assert_same(serial, pooled)


def test_dask_cluster_gives_identical_results(serial) -> None:
    distributed = pytest.importorskip("dask.distributed")
    with distributed.Client(
        processes=False, n_workers=1, threads_per_worker=2, **LOCAL_CLUSTER
    ) as client:
        clustered = evaluate(
            plan_text(STUDY), chunk_size=4, progress=False, executor=client.get_executor()
        )
    assert_same(serial, clustered)


def test_dask_local_cluster_of_worker_processes_gives_identical_results(serial) -> None:
    distributed = pytest.importorskip("dask.distributed")
    with (
        distributed.LocalCluster(
            n_workers=2, processes=True, threads_per_worker=1, **LOCAL_CLUSTER
        ) as cluster,
        distributed.Client(cluster) as client,
    ):
        assert len(client.scheduler_info()["workers"]) == 2
        clustered = evaluate(
            plan_text(STUDY), chunk_size=4, progress=False, executor=client.get_executor()
        )
    assert_same(serial, clustered)


class Recorder(Executor):
    """Runs each task at once and records the pickled size of what it was given."""

    def __init__(self) -> None:
        self.sizes: list[int] = []

    def submit(self, fn, /, *args, **kwargs):
        self.sizes.append(len(pickle.dumps((fn, args, kwargs))))
        future: Future = Future()
        future.set_result(fn(*args, **kwargs))
        return future


def test_a_task_carries_only_its_chunk(serial) -> None:
    # What an executor receives for one chunk: its index range and the factors' levels, not
    # the chunk's values and not the whole plan (issue #28: at most 10 kB a task).
    small, big = Recorder(), Recorder()
    assert_same(serial, evaluate(plan_text(STUDY), chunk_size=4, progress=False, executor=small))
    levels = str(list(range(10, 110)))  # 300 runs instead of 15, the same chunk size
    large = plan_text(STUDY.replace("[16.0, 18.0, 20.0, 22.0, 24.0]", levels))
    evaluate(large, chunk_size=4, progress=False, executor=big)
    assert len(big.sizes) == 1 + 75  # the warm-up's one point (compile_s), then 75 chunks
    # 20x the runs: a task grows by the 95 more levels of base_radius (8 bytes each) only
    assert max(big.sizes) - max(small.sizes) <= 8 * 95 + 100
    wide = Recorder()
    evaluate(large, chunk_size=100, progress=False, executor=wide)
    assert max(wide.sizes) <= max(big.sizes) + 100  # nor with the chunk
    assert max(wide.sizes) <= 10_000


class Counting(ThreadPoolExecutor):
    """A thread pool that records how many submitted tasks were unfinished at once."""

    def __init__(self) -> None:
        super().__init__(max_workers=2)
        self.out, self.most = 0, 0

    def submit(self, fn, /, *args, **kwargs):
        self.out += 1
        self.most = max(self.most, self.out)
        future = super().submit(fn, *args, **kwargs)
        future.add_done_callback(self._done)
        return future

    def _done(self, _: Future) -> None:
        self.out -= 1


def test_an_executor_is_given_a_bounded_number_of_chunks_at_a_time() -> None:
    large = plan_text(STUDY.replace("[16.0, 18.0, 20.0, 22.0, 24.0]", str(list(range(10, 110)))))
    alone = evaluate(large, chunk_size=4, progress=False)
    with Counting() as pool:
        result = evaluate(large, chunk_size=4, progress=False, executor=pool)
    assert_same(alone, result)
    assert 1 < pool.most <= runner.MAX_IN_FLIGHT < 75  # 75 chunks, never all out at once


def test_an_unreachable_scheduler_is_one_line_and_writes_nothing(
    tmp_path, monkeypatch, capsys
) -> None:
    pytest.importorskip("dask.distributed")
    from studies.cli import main
    from studies.run import runner

    monkeypatch.setattr(runner, "SCHEDULER_TIMEOUT_S", 0.5)
    study = tmp_path / "executors.toml"
    study.write_text(STUDY)
    outputs = tmp_path / "out"
    address = "tcp://127.0.0.1:1"  # port 1: nothing listens there
    code = main(["run", str(study), "--outputs", str(outputs), "--scheduler", address])
    assert code == 2
    err = capsys.readouterr().err.strip()
    assert "Traceback" not in err
    assert len(err.splitlines()) == 1
    assert err.startswith(f"error: --scheduler {address}: could not connect to a Dask scheduler")
    assert "within 0.5 s" in err
    assert not outputs.exists()


def test_a_local_cluster_starts_quietly_beside_another_one_on_port_8787() -> None:
    # `--scheduler local` while another cluster (a notebook's, a second run's) held port 8787
    # warned "Port 8787 is already in use. Perhaps you already have a cluster running?": with
    # the dashboard off, the scheduler's HTTP server still took 8787. The suite turns warnings
    # into errors, so that warning would fail the start here.
    pytest.importorskip("dask.distributed")
    from studies.run.cluster import cluster_executor

    taken = socket.socket()
    try:
        taken.bind(("0.0.0.0", 8787))
        taken.listen()
    except OSError:
        pass  # held by another process already: the same situation
    try:
        with cluster_executor("local", ["cam"]) as executor:
            assert executor.submit(int, "7").result() == 7
    finally:
        taken.close()
