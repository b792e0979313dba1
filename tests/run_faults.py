"""Fault injection for run tests: make a function (a scene stage, the checkpoint writer) fail on
its n-th call, as a crash, a kill or a full disk would at that moment of a run."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import pytest


def failing_on_call(original: Callable[..., Any], call: int, error: BaseException) -> Callable:
    """``original``, except that its ``call``-th call raises ``error`` instead."""
    calls = {"n": 0}

    def failing(*args: Any, **kwargs: Any) -> Any:
        calls["n"] += 1
        if calls["n"] == call:
            raise error
        return original(*args, **kwargs)

    return failing


def fail_on_call(
    monkeypatch: pytest.MonkeyPatch,
    plan: Any,
    call: int,
    error: BaseException,
    stage: str = "geometry",
) -> None:
    """Make the plan's ``stage`` raise ``error`` on its ``call``-th call (the first call is
    the runner's one-point warm-up; chunk k is then call k + 2)."""
    original = plan.scene.stages[stage]
    monkeypatch.setitem(plan.scene.stages, stage, failing_on_call(original, call, error))
