"""Best-of-``repeat`` timings for the benchmarks, taken in turns (see :mod:`studies.bench.benchmarks`)."""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence


def best_time(fn: Callable[[], object], repeat: int) -> float:
    return best_times([fn], repeat)[0]


def best_times(fns: Sequence[Callable[[], object]], repeat: int) -> list[float]:
    """Best of ``repeat`` timings of each function, taken in turns (after one warm-up call
    each), so that load from other users of the machine falls on all of them alike."""
    for fn in fns:
        fn()
    best = [math.inf] * len(fns)
    for _ in range(repeat):
        for i, fn in enumerate(fns):
            t0 = time.perf_counter()
            fn()
            best[i] = min(best[i], time.perf_counter() - t0)
    return best
