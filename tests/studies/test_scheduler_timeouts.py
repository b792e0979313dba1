"""``--scheduler`` cannot hang a run (issue 25, "Unbounded work"): an address that accepts the
connection and never answers (before: > 300 s despite the 5 s timeout) and a scheduler with no
worker (before: silent forever) each end in one line naming the address, with nothing run."""

from __future__ import annotations

import socket
import threading
import time
from collections.abc import Iterator

import pytest
from dask.distributed import LocalCluster

from studies.run import runner


@pytest.fixture
def silent_address() -> Iterator[str]:
    """A TCP port that accepts connections and never sends a byte."""
    server = socket.socket()
    server.bind(("127.0.0.1", 0))
    server.listen()
    held: list[socket.socket] = []
    stop = threading.Event()

    def accept() -> None:
        server.settimeout(0.2)
        while not stop.is_set():
            try:
                held.append(server.accept()[0])
            except OSError:
                continue

    thread = threading.Thread(target=accept, daemon=True)
    thread.start()
    yield f"tcp://127.0.0.1:{server.getsockname()[1]}"
    stop.set()
    thread.join()
    for conn in held:
        conn.close()
    server.close()


def test_an_address_that_never_answers_is_given_up(
    silent_address: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(runner, "SCHEDULER_TIMEOUT_S", 1.0)
    monkeypatch.setattr(runner, "HANDSHAKE_GRACE_S", 0.5)
    start = time.perf_counter()
    with pytest.raises(ValueError, match="could not connect to a Dask scheduler within 1 s"):
        runner.dask_executor(silent_address)
    print(f"given up after {time.perf_counter() - start:.1f} s")


@pytest.mark.filterwarnings("ignore::DeprecationWarning")
def test_a_scheduler_without_workers_is_named(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(runner, "WORKERS_TIMEOUT_S", 1.0)
    with LocalCluster(n_workers=0, processes=False, **runner.LOCAL_CLUSTER) as cluster:
        address = cluster.scheduler_address
        with pytest.raises(ValueError, match="has no workers") as refused:
            runner.dask_executor(address)
    assert str(refused.value) == (
        f"--scheduler {address}: the scheduler has no workers (none joined within 1 s): start "
        f"one with `dask worker {address}`"
    )
