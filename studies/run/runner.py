"""Evaluate a planned study in chunks, with a progress bar, timing compile and run separately.

Chunks bound memory (curves are runs × angles) and are the unit of work for executors. The
first design point is evaluated alone first: that call compiles (or loads from the on-disk
cache) every kernel the study needs, so ``compile_s`` and ``run_s`` are reported apart.

By default chunks run here, one after another (each chunk is already parallel inside its
compiled kernels). Any ``concurrent.futures.Executor`` can run them instead — a Dask cluster's
``Client.get_executor()`` (see :func:`dask_executor`) or a process pool started with the
``spawn`` method (the kernels' threading layer must not be forked). Every chunk is the
same pure function of its design points, so results are identical whichever executor ran
them. A task carries its chunk's index range and what makes the chunk's values (a few kB for a
full factorial, never the whole plan), and at most ``MAX_IN_FLIGHT`` chunks are out at a time.
"""

from __future__ import annotations

import itertools
import threading
import time
from collections.abc import Callable, Iterator, Mapping
from concurrent.futures import FIRST_COMPLETED, Executor, Future, wait
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from tqdm.auto import tqdm

from studies.common.errors import ClusterError
from studies.define.plan import Plan
from studies.scenes import Scene, SceneOutput, get_scene
from studies.scenes.design_points import DesignPoints

DEFAULT_CHUNK_SIZE = 2048
MAX_IN_FLIGHT = 16
"""Chunks submitted to an executor and not yet finished: the next is submitted when one
finishes, so neither the client nor the scheduler holds a task per chunk of a 10⁸-point study
(each cluster worker core still has chunks queued)."""
SCHEDULER_TIMEOUT_S = 5.0  # connecting to a --scheduler address; Dask's default is 30 s
HANDSHAKE_GRACE_S = 2.0  # beyond it, an address that accepted but never answered is given up
WORKERS_TIMEOUT_S = 30.0  # a scheduler with no worker: how long to wait for one to join


@dataclass
class Evaluation:
    """Concatenated scene outputs of a whole study, plus timings [s]."""

    scalars: dict[str, np.ndarray]
    curves: dict[str, np.ndarray]
    timings: dict[str, float] = field(default_factory=dict)


def chunks(runs: int, size: int) -> Iterator[slice]:
    for start in range(0, runs, size):
        yield slice(start, min(start + size, runs))


def chunk_cases(plan: Plan, size: int) -> int:
    """A chunk size of whole design points: ``size`` points rounded down to a multiple of the
    noise cases per design point (at least one design point's cases)."""
    n = plan.noise_cases
    return max(n, size // n * n)


def chunk_points(plan: Plan, part: slice) -> dict[str, np.ndarray]:
    """The SI parameter values of the computed points ``part`` (design points × noise cases)."""
    return plan.points.at(part)


def evaluate_chunk(plan: Plan, part: slice) -> SceneOutput:
    d = plan.definition
    return plan.scene.evaluate(
        chunk_points(plan, part), plan.settings, list(plan.responses), list(d.curves)
    )


_WORKER_SCENES: dict[str, Scene] = {}


def evaluate_part(
    scene: str,
    points: DesignPoints,
    part: slice,
    settings: dict[str, Any],
    responses: list[str],
    curves: list[str],
) -> SceneOutput:
    """One chunk on an executor's worker: the task carries the chunk's index range and what
    makes its values (:meth:`DesignPoints.for_chunk`), not the values; the scene is built once
    per worker process (its caches are reused across chunks)."""
    if scene not in _WORKER_SCENES:
        _WORKER_SCENES[scene] = get_scene(scene)
    return _WORKER_SCENES[scene].evaluate(points.at(part), settings, responses, curves)


def evaluate(
    plan: Plan,
    chunk_size: int = DEFAULT_CHUNK_SIZE,
    progress: bool = True,
    on_chunk: Callable[[int, SceneOutput], None] | None = None,
    done: Mapping[int, SceneOutput | None] | None = None,
    executor: Executor | None = None,
    collect: bool = True,
) -> Evaluation:
    """Evaluate every design point of ``plan``.

    ``on_chunk(index, output)`` sees each newly finished chunk (the run record checkpoints it
    and streams it into results.nc); ``done`` holds chunks finished by an earlier, interrupted
    run, which are not recomputed; ``executor`` runs the chunks elsewhere (``compile_s`` then
    times the first point on one of its workers; the others load their kernels in their first
    chunk). With ``collect=False`` no chunk is kept (``on_chunk`` has
    them all; the Evaluation holds the timings only), so memory does not grow with the study,
    and ``done`` needs only its keys.
    """
    if chunk_size < 1:
        msg = f"chunk_size = {chunk_size} must be a positive number of design points"
        raise ValueError(msg)
    finished = set(done or {})
    parts: dict[int, SceneOutput] = {i: o for i, o in (done or {}).items() if o is not None}
    todo = [(i, part) for i, part in enumerate(chunks(plan.cases, chunk_size)) if i not in finished]
    t0 = time.perf_counter()
    if todo:
        _warm_up(plan, slice(todo[0][1].start, todo[0][1].start + 1), executor)
    compile_s = time.perf_counter() - t0
    t1 = time.perf_counter()
    computed = sum(part.stop - part.start for _, part in todo)
    bar = tqdm(
        total=plan.cases,
        initial=plan.cases - computed,
        unit="pt",
        desc=plan.definition.name,
        disable=not progress,
        leave=False,
    )
    with bar:
        for index, part, out in _results(plan, todo, executor):
            if collect:
                parts[index] = out
            if on_chunk is not None:
                on_chunk(index, out)
            bar.update(part.stop - part.start)
    run_s = time.perf_counter() - t1
    ordered = [parts[i] for i in sorted(parts)] if collect else []
    first = ordered[0] if ordered else SceneOutput({}, {})
    scalars = {k: np.concatenate([p.scalars[k] for p in ordered]) for k in first.scalars}
    curves = {k: np.concatenate([p.curves[k] for p in ordered]) for k in first.curves}
    timings = {
        "compile_s": compile_s,
        "run_s": run_s,
        "points_computed": computed,
        "points_per_s": computed / run_s if run_s > 0 else float("inf"),
    }
    return Evaluation(scalars, curves, timings)


def _results(
    plan: Plan, todo: list[tuple[int, slice]], executor: Executor | None
) -> Iterator[tuple[int, slice, SceneOutput]]:
    """Finished chunks, here in order, or from ``executor`` as they complete."""
    if executor is None:
        for index, part in todo:
            yield index, part, evaluate_chunk(plan, part)
        return

    def submit(index: int, part: slice) -> tuple[Future[SceneOutput], tuple[int, slice]]:
        return executor.submit(evaluate_part, *_task(plan, part)), (index, part)

    waiting = iter(todo)
    running = dict(submit(*item) for item in itertools.islice(waiting, MAX_IN_FLIGHT))
    while running:
        finished, _ = wait(running, return_when=FIRST_COMPLETED)
        for future in finished:
            index, part = running.pop(future)
            for item in itertools.islice(waiting, 1):
                running.update([submit(*item)])
            yield index, part, future.result()


def _task(plan: Plan, part: slice) -> tuple[Any, ...]:
    """The arguments of :func:`evaluate_part` for the chunk ``part``."""
    d = plan.definition
    points = plan.points.for_chunk(part)
    return d.scene, points, part, plan.settings, list(plan.responses), list(d.curves)


def _warm_up(plan: Plan, part: slice, executor: Executor | None) -> None:
    """Evaluate ``part`` (one point) where the chunks will run, so that loading or compiling
    the kernels is timed apart (``compile_s``): here, or on one of ``executor``'s workers (this
    process then never loads a kernel)."""
    if executor is None:
        evaluate_chunk(plan, part)
    else:
        executor.submit(evaluate_part, *_task(plan, part)).result()


def dask_executor(scheduler: str) -> Executor:
    """An executor on a Dask cluster: ``scheduler`` is an address or ``local``
    (:func:`dask_client`)."""
    return dask_client(scheduler).get_executor()


LOCAL_CLUSTER = {"dashboard_address": None, "scheduler_kwargs": {"dashboard_address": ":0"}}
"""Options of a local Dask cluster (``LocalCluster``, ``Client``): no dashboard, and the
scheduler's HTTP server (health and metrics) on a free port. Without a dashboard that server
still takes port 8787, and a second cluster on the machine (another run, a notebook's) then
warns that the port is in use and perhaps a cluster runs already."""


def dask_client(scheduler: str) -> Any:
    """A client of a Dask cluster: ``scheduler`` is an address or ``local``.

    ``local`` starts a cluster of worker processes on this machine. Needs the ``cluster``
    extra (``pip install -e '.[cluster]'``). An address is given up after
    :data:`SCHEDULER_TIMEOUT_S` (:func:`_connect`), a scheduler without workers after
    :data:`WORKERS_TIMEOUT_S`.
    """
    try:
        from dask.distributed import Client  # noqa: PLC0415  (optional dependency)
    except ImportError:
        msg = "--scheduler needs dask.distributed: pip install -e '.[cluster]'"
        raise ClusterError(msg) from None
    if scheduler == "local":
        return Client(**LOCAL_CLUSTER)
    client = _connect(Client, scheduler)
    try:
        client.wait_for_workers(1, timeout=WORKERS_TIMEOUT_S)
    except (TimeoutError, OSError):
        client.close()
        msg = (
            f"--scheduler {scheduler}: the scheduler has no workers (none joined within "
            f"{WORKERS_TIMEOUT_S:g} s): start one with `dask worker {scheduler}`"
        )
        raise ClusterError(msg) from None
    return client


def _connect(client: Callable[..., Any], scheduler: str) -> Any:
    """A Dask client of ``scheduler`` within ``SCHEDULER_TIMEOUT_S`` (ValueError otherwise),
    even when the address accepts a connection and never answers (Dask's own timeout covers
    the connection, not the handshake): the client is made in a thread given a deadline."""
    result: dict[str, Any] = {}

    def connect() -> None:
        try:
            result["client"] = client(scheduler, timeout=SCHEDULER_TIMEOUT_S)
        except Exception as exc:  # noqa: BLE001  unreachable, malformed, or not a scheduler
            result["error"] = exc

    thread = threading.Thread(target=connect, daemon=True, name="dask-connect")
    thread.start()
    thread.join(SCHEDULER_TIMEOUT_S + HANDSHAKE_GRACE_S)
    if "client" in result:
        return result["client"]
    exc = result.get("error")
    detail = (str(exc).splitlines() or ["no detail"])[0] if exc else "no answer"
    kind = type(exc).__name__ if exc else "timeout"
    msg = (
        f"--scheduler {scheduler}: could not connect to a Dask scheduler within "
        f"{SCHEDULER_TIMEOUT_S:g} s ({kind}: {detail[:200]}); "
        "check the address (e.g. tcp://host:8786) or use --scheduler local"
    )
    raise ClusterError(msg)
