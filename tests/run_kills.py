"""``python tests/run_kills.py PHASE COMMAND…``: ``python -m studies COMMAND…`` in a process
that SIGKILLs itself (no handler, no clean-up runs) at one phase boundary of a run or an rm, or
that is slow at every chunk (``slow-chunks``: two resumes then overlap for certain).

    before-registration   run.json written, the registry not yet told
    after-first-chunk     the first chunk checkpointed
    before-analysis       results.nc complete, no analysis yet
    after-finished        run.json says "finished", the registry not yet updated
    rm-before-registry    the folder moved into the trash, its registry rows not yet deleted
"""

from __future__ import annotations

import os
import signal
import sys
import time
from collections.abc import Callable
from typing import Any

from studies import pipeline
from studies.cli import main
from studies.tracking import records, registry
from studies.tracking.store import RunStore

SLOW_CHUNK_S = 1.5


def die(*_: object, **__: object) -> None:
    os.kill(os.getpid(), signal.SIGKILL)


def on_call(original: Callable[..., Any], call: int, then: Callable[..., Any]) -> Callable:
    """``original``, except that its ``call``-th call runs ``then`` first."""
    calls = {"n": 0}

    def wrapped(*args: Any, **kwargs: Any) -> Any:
        calls["n"] += 1
        if calls["n"] == call:
            then()
        return original(*args, **kwargs)

    return wrapped


def after(original: Callable[..., Any], then: Callable[..., Any]) -> Callable:
    def wrapped(*args: Any, **kwargs: Any) -> Any:
        out = original(*args, **kwargs)
        then()
        return out

    return wrapped


def register_unless_finished(store: RunStore, record: records.RunRecord) -> None:
    if record.status == "finished":
        die()
    REGISTER(store, record)


REGISTER = RunStore.register


def patch(phase: str) -> None:
    if phase == "before-registration":
        RunStore.register = on_call(RunStore.register, 1, die)
    elif phase == "after-first-chunk":
        pipeline._save_chunk = after(pipeline._save_chunk, die)
    elif phase == "before-analysis":
        pipeline.write_analysis = on_call(pipeline.write_analysis, 1, die)
    elif phase == "after-finished":
        RunStore.register = register_unless_finished
    elif phase == "rm-before-registry":
        registry.delete_run = on_call(registry.delete_run, 1, die)
    elif phase == "slow-chunks":
        pipeline._save_chunk = after(pipeline._save_chunk, lambda: time.sleep(SLOW_CHUNK_S))
    else:
        raise SystemExit(f"unknown phase {phase!r}")


if __name__ == "__main__":
    patch(sys.argv[1])
    raise SystemExit(main(sys.argv[2:]))
