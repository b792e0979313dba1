"""A Dask cluster that tells what is wrong before any chunk runs (``run --scheduler``).

On connect, every worker reports the code it would compute with (:func:`worker_code`: the
engine's version and source hash, each scene the run needs, the numba/numpy/scipy versions) and
the client compares it with its own: a worker that lacks a scene plugin, or runs another
version or an edited copy of the engine or a scene, refuses the run in one line naming the
worker and the difference. Results are then identical whichever executor ran them because the
code is. Dask's shutdown chatter (workers "still alive … killing") is not the user's business:
the client and a ``local`` cluster are closed quietly when the run is over.
"""

from __future__ import annotations

import logging
import threading
from collections.abc import Iterator
from concurrent.futures import Executor
from contextlib import contextmanager
from typing import Any

from studies.common.errors import ClusterError
from studies.run import provenance
from studies.run.runner import dask_client

SHUTDOWN_LOGGERS = ("distributed", "tornado", "asyncio")
CHECK_TIMEOUT_S = 60.0
"""The workers' first task, the code check: a cluster that has not answered it by then (a hung
or overloaded worker) ends the command with one line instead of hanging it."""


def worker_code(scenes: list[str]) -> dict[str, Any]:
    """What a process would compute ``scenes`` with: engine, scenes (None when not installed)
    and libraries (run on each worker, and here)."""
    from studies.scenes import SCENES  # noqa: PLC0415  (the registry of the process it runs in)

    return {
        "engine": provenance.engine_code(),
        "scenes": {n: provenance.scene_code(SCENES[n]) if n in SCENES else None for n in scenes},
        "libraries": provenance.libraries(),
    }


def differences(here: dict[str, Any], there: dict[str, Any] | BaseException) -> list[str]:
    """How a worker's code differs from this process's, in words (empty when identical)."""
    if isinstance(there, BaseException):
        detail = (str(there).splitlines() or [""])[0][:160]
        return [f"it cannot run the engine ({type(there).__name__}: {detail})"]
    out = []
    mine, theirs = here["engine"], there["engine"]
    if (mine["version"], mine["source_sha256"]) != (theirs["version"], theirs["source_sha256"]):
        out.append(
            f"engine-studies {theirs['version']} (source {theirs['source_sha256'][:8]}) there, "
            f"{mine['version']} (source {mine['source_sha256'][:8]}) here"
        )
    for name, code in here["scenes"].items():
        other = there["scenes"].get(name)
        if other is None:
            out.append(
                f"scene {name!r} is not installed there "
                f"(here: {provenance.describe_scene_code(code)})"
            )
        elif code.get("plugin") and _key(other) != _key(code):  # a built-in one: the engine's
            out.append(
                f"scene {name!r}: {provenance.describe_scene_code(other)} there, "
                f"{provenance.describe_scene_code(code)} here"
            )
    for library, version in here["libraries"].items():
        if there["libraries"].get(library) != version:
            out.append(f"{library} {there['libraries'].get(library)} there, {version} here")
    return out


def _within(seconds: float, call: Any, *args: Any, **kwargs: Any) -> Any:
    """``call(*args, **kwargs)`` in a thread given ``seconds``: its result, None past them
    (the thread is left to finish on its own: a daemon, it never holds the process)."""
    box: dict[str, Any] = {}

    def target() -> None:
        try:
            box["result"] = call(*args, **kwargs)
        except BaseException as exc:  # noqa: BLE001  re-raised in the caller's thread
            box["error"] = exc

    thread = threading.Thread(target=target, daemon=True, name="dask-code-check")
    thread.start()
    thread.join(seconds)
    if "error" in box:
        raise box["error"]
    return box.get("result")


def _key(code: dict[str, Any]) -> tuple[Any, ...]:
    return code.get("distribution"), code.get("version"), code.get("source_sha256")


def check_workers(client: Any, scheduler: str, scenes: list[str]) -> None:
    """ValueError in one line when a worker's code differs from this process's."""
    here = worker_code(scenes)
    reports = _within(CHECK_TIMEOUT_S, client.run, worker_code, scenes, on_error="return")
    if reports is None:
        msg = (
            f"--scheduler {scheduler}: the workers did not answer the code check (their first "
            f"task) within {CHECK_TIMEOUT_S:g} s: a worker is hung or overloaded; restart the "
            "workers; nothing was run"
        )
        raise ClusterError(msg)
    wrong = {w: d for w, r in sorted(reports.items()) if (d := differences(here, r))}
    if not wrong:
        return
    worker, found = next(iter(wrong.items()))
    others = f" (and {len(wrong) - 1} other worker(s))" if len(wrong) > 1 else ""
    msg = (
        f"--scheduler {scheduler}: worker {worker}{others} differs from this machine: "
        f"{'; '.join(found)}. Install the same engine-studies, scenes and libraries on every "
        "worker and restart it; nothing was run"
    )
    raise ClusterError(msg)


@contextmanager
def cluster_executor(scheduler: str, scenes: list[str]) -> Iterator[Executor]:
    """An executor on the cluster at ``scheduler`` (or ``local``) whose workers were checked
    to run the same code as this process; closed quietly on exit."""
    client = dask_client(scheduler)
    try:
        check_workers(client, scheduler, scenes)
        yield client.get_executor()
    finally:
        _close_quietly(client)


def _close_quietly(client: Any) -> None:
    """Close the client (and the local cluster it started) without Dask's shutdown warnings."""
    levels = {name: logging.getLogger(name).level for name in SHUTDOWN_LOGGERS}
    for name in SHUTDOWN_LOGGERS:
        logging.getLogger(name).setLevel(logging.CRITICAL)
    try:
        client.close()
    finally:
        for name, level in levels.items():
            logging.getLogger(name).setLevel(level)
