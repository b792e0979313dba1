"""A study's figures drawn by this process and worker processes side by side, once the
numbers are on disk.

Each figure is independent of the others and costs 0.1-1 s of matplotlib in one process; a
study draws from a few to a few dozen. ``python -m studies run`` and ``analyze`` call
:func:`warm` before they import anything heavy: a forkserver then imports matplotlib, xarray
and the renderers while this process plans the study and computes it, and :class:`Drawing`
shares the figures between this process and ``WORKERS`` worker process(es) forked from that
server, each taking the next figure when it has finished one (this process draws alone until
the worker runs) (on the 2-core machine: the figures of the
10⁶-point bench study in 2.9-3.2 s instead of 4.0-4.9 s, for about 165 MB more while the
worker and its server live). Everything else (the Python API, a script calling the command
line, the tests) draws in its own process, as do a figure whose arguments cannot be sent (a
plugin's builder that cannot be pickled), a figure whose worker died, and every figure where
no pool can start (no forkserver on this platform): the same files either way.

``ENGINE_STUDIES_FIGURE_WORKERS`` sets the number of workers (``0``: draw in this process).
"""

from __future__ import annotations

import contextlib
import multiprocessing
import os
import pickle
import signal
import sys
import threading
import time
from collections.abc import Callable
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from pathlib import Path
from typing import Any

from studies.common.errors import NotDrawn, StudyError

WORKERS = 1
PRELOAD = ["studies.report.write"]  # imports matplotlib, xarray and every generic renderer
ENVIRONMENT = "ENGINE_STUDIES_FIGURE_WORKERS"

_pool: ProcessPoolExecutor | None = None
_workers = 0  # of the pool
_ready = threading.Event()  # set once the worker has started (not when it could not)


def workers() -> int:
    """The number of figure workers: ``ENGINE_STUDIES_FIGURE_WORKERS``, else ``WORKERS`` when
    this machine has more than one core, else 0."""
    text = os.environ.get(ENVIRONMENT, "").strip()
    if not text:
        return WORKERS if (os.cpu_count() or 1) > 1 else 0
    if not (text.isascii() and text.isdecimal()):
        msg = f"{ENVIRONMENT} = {text!r}: a whole number >= 0 (0: figures drawn in this process)"
        raise StudyError(msg)
    return int(text)


def warm() -> None:
    """Start the worker pool (:func:`start`) when this process is the engine's command line
    (``python -m studies``): a worker imports the main module, and a user's script that calls
    :func:`studies.cli.main` without an ``if __name__ == "__main__"`` guard would run again
    in it. Nothing otherwise: the figures are drawn in this process."""
    main = sys.modules.get("__main__")
    if getattr(getattr(main, "__spec__", None), "name", None) == "studies.__main__":
        start()


def start() -> None:
    """Start the worker pool (idempotent); nothing when workers are off or cannot start. A
    malformed ``ENGINE_STUDIES_FIGURE_WORKERS`` is an error here, before anything runs."""
    global _pool, _workers  # noqa: PLW0603  (one pool per process, for the runs of a command)
    count = workers()
    if _pool is not None or count == 0:
        return
    try:
        context = multiprocessing.get_context("forkserver")
        context.set_forkserver_preload(PRELOAD)
        _pool = ProcessPoolExecutor(count, mp_context=context, initializer=_worker_setup)
        _workers = count
    except (OSError, ValueError, RuntimeError):  # no forkserver on this platform
        _pool, _workers = None, 0
        return
    # The first job starts the forkserver and waits while it imports: on a thread of its
    # own, so that this process plans and computes meanwhile; figures go to the worker only
    # once it runs (until then, and if it never starts, they are drawn here).
    _ready.clear()
    threading.Thread(target=_start, args=(_pool,), daemon=True).start()


def _start(pool: ProcessPoolExecutor) -> None:
    # Ctrl-C is the run's to handle: the server and the worker it forks start from this
    # thread with SIGINT blocked (the mask passes through fork and exec), so neither is
    # interrupted while it imports or draws (the run shuts them down).
    signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
    try:
        pool.submit(int).result()
    except Exception:  # noqa: BLE001  (e.g. no room for the forkserver's socket: drawn here)
        return
    _ready.set()


def _worker_setup() -> None:
    """In each worker: Ctrl-C is the run's to handle (the worker finishes its figure and is
    shut down), and results files are read with the run's small chunk cache."""
    from studies.run.results import small_chunk_cache  # noqa: PLC0415  (xarray: not at warm)

    signal.signal(signal.SIGINT, signal.SIG_IGN)
    small_chunk_cache()


def stop() -> None:
    """Shut the pool down (the command is done with figures). A worker still starting is
    waited for (up to the server's imports, about a second): torn down under it, its start
    would print a traceback."""
    global _pool, _workers
    if _pool is not None:
        with contextlib.suppress(Exception):
            _pool.shutdown(wait=True, cancel_futures=True)
        _pool, _workers = None, 0
        _ready.clear()


class Drawing:
    """The figures of one analysis: :meth:`add` lists each, :meth:`paths` draws them all and
    returns their files in the order asked for. The workers take figures from the front of
    the list while this process takes them from the back, so neither waits while figures
    remain once the worker runs; a figure whose worker died is drawn here.

    ``problems`` gets one line per figure kind and error that drew nothing (a figure the
    results give no readable picture of: its own line, :class:`NotDrawn`); a
    full disk or exhausted memory is the run's failure, not the figure's: it propagates.
    ``timings['figures_s']`` gets the seconds :meth:`paths` took."""

    def __init__(self, timings: dict[str, float], problems: list[str]) -> None:
        self.timings, self.problems = timings, problems
        self.jobs: list[tuple[Callable[..., list[Path]], tuple[Any, ...]]] = []

    def add(self, figures: Callable[..., list[Path]], *args: Any) -> None:
        self.jobs.append((figures, args))

    def paths(self) -> list[Path]:
        """Draw every figure listed (here and on the workers); their files, in order."""
        start = time.perf_counter()
        done: dict[int, Future[list[Path]]] = {}
        running: dict[Future[list[Path]], int] = {}
        front, back = 0, len(self.jobs)  # the workers' next job, one past this process's
        try:
            while front < back or running:
                for future in [f for f in running if f.done()]:
                    done[running.pop(future)] = future
                while front < back and len(running) < _workers:
                    sent = _send(*self.jobs[front])
                    if sent is None:
                        break  # no pool, or this job cannot be sent: drawn here below
                    running[sent], front = front, front + 1
                if front < back:
                    back -= 1
                    done[back] = _here(*self.jobs[back])
                else:
                    finished, _ = wait(running, return_when=FIRST_COMPLETED)
                    for future in finished:
                        done[running.pop(future)] = future
        except BaseException:  # a full disk here: no worker writes after the run has failed
            wait(running)
            raise
        drawn = [path for i in range(len(self.jobs)) for path in self._result(i, done[i])]
        self.jobs = []
        self.timings["figures_s"] = self.timings.get("figures_s", 0.0) + time.perf_counter() - start
        return drawn

    def _result(self, index: int, job: Future[list[Path]]) -> list[Path]:
        figures, args = self.jobs[index]
        try:
            try:
                return job.result()
            except BrokenProcessPool:  # the worker died (killed, out of memory): here
                return figures(*args)
        except (OSError, MemoryError):
            raise
        except Exception as exc:  # noqa: BLE001  (any other failure of one figure job)
            name = getattr(figures, "__name__", "figures")
            line = f"{name} drew nothing: {type(exc).__name__}: {exc}"
            if isinstance(exc, NotDrawn):  # says which figure and why
                line = str(exc)
            if line not in self.problems:  # once, not per response
                self.problems.append(line)
            return []


def _here(figures: Callable[..., list[Path]], args: tuple[Any, ...]) -> Future[list[Path]]:
    """``figures(*args)`` drawn in this process now, as a finished future (a full disk or
    exhausted memory propagates at once)."""
    future: Future[list[Path]] = Future()
    try:
        future.set_result(figures(*args))
    except (OSError, MemoryError):
        raise
    except Exception as exc:  # noqa: BLE001  (reported by Drawing.paths)
        future.set_exception(exc)
    return future


def _send(figures: Callable[..., list[Path]], args: tuple[Any, ...]) -> Future[list[Path]] | None:
    """``figures(*args)`` on the worker; None when there is none (yet), or the job cannot be
    sent (its arguments do not pickle, whatever the exception)."""
    if _pool is None or not _ready.is_set():
        return None
    try:
        pickle.dumps((figures, args), protocol=pickle.HIGHEST_PROTOCOL)
        return _pool.submit(figures, *args)
    except Exception:  # noqa: BLE001
        return None
