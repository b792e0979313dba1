"""The memory of a process and all its descendants together, sampled while it runs.

``wait4`` gives the peak resident memory of one process (and of the children it reaped); a run
also has figure workers forked from a forkserver (:mod:`studies.report.figure_pool`), which it
does not reap. :class:`TreePeak` adds up their proportional set size (PSS: a page shared by n
processes counts 1/n in each, so what the worker shares with its forkserver counts once) from
``/proc`` every ``INTERVAL_S`` seconds and keeps the largest sum. Where ``/proc`` has no
``smaps_rollup`` (not Linux), the peak is None.
"""

from __future__ import annotations

import threading
from pathlib import Path

INTERVAL_S = 0.05
PROC = Path("/proc")


def descendants(pid: int) -> list[int]:
    """``pid`` and every process below it (those that exist at this moment)."""
    found, todo = [], [pid]
    while todo:
        p = todo.pop()
        found.append(p)
        for task in (PROC / str(p) / "task").glob("*"):  # children forked by any thread
            try:
                todo += [int(c) for c in (task / "children").read_text().split()]
            except OSError:  # ended meanwhile, or no such file here
                continue
    return found


def pss_kb(pid: int) -> int | None:
    """The proportional set size of ``pid`` [kB]; None when it cannot be read."""
    try:
        text = (PROC / str(pid) / "smaps_rollup").read_text()
    except OSError:
        return None
    for line in text.splitlines():
        if line.startswith("Pss:"):
            return int(line.split()[1])
    return None


class TreePeak:
    """Samples the summed PSS of ``pid``'s process tree until :meth:`stop`; ``peak_mb`` is the
    largest sum seen [MB] (None when nothing could be read)."""

    def __init__(self, pid: int) -> None:
        self.pid, self.processes = pid, 0
        self.peak_kb: int | None = None
        self.done = threading.Event()
        self.thread = threading.Thread(target=self._sample, daemon=True)
        self.thread.start()

    def _sample(self) -> None:
        while not self.done.is_set():
            tree = descendants(self.pid)
            sizes = [s for s in map(pss_kb, tree) if s is not None]
            if sizes:
                self.peak_kb = max(self.peak_kb or 0, sum(sizes))
                self.processes = max(self.processes, len(sizes))
            self.done.wait(INTERVAL_S)

    def stop(self) -> float | None:
        self.done.set()
        self.thread.join()
        return None if self.peak_kb is None else self.peak_kb / 1024.0
