"""Test scenes of a closed-form function of three inputs x1, x2, x3 in [−4, 4] (no kernel):
the sampling-design tests use a linear one, the Saltelli tests the Ishigami function. Each is
registered as a plugin scene for the duration of a test (:func:`registered`)."""

from __future__ import annotations

from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field

import numpy as np
import pytest

from studies.scenes import SCENES, Parameter, Response, Scene, SceneOutput, get_scene
from studies.scenes.state import RunState

Function = Callable[[np.ndarray, np.ndarray, np.ndarray], np.ndarray]


@dataclass(slots=True)
class FunctionState(RunState):
    value: np.ndarray = field(init=False)  # the response per design point


def function_scene(scene: str, response: str, function: Function, about: str) -> type[Scene]:
    """A scene called ``scene`` whose one response ``response`` [1] is ``function(x1, x2, x3)``
    (one stage, ``response``; ``about`` describes it)."""

    class FunctionScene(Scene[FunctionState]):
        name = scene
        description = f"{about} (test scene)"
        parameters = tuple(
            Parameter(f"x{i}", "1", 0.0, f"input x{i}", -4.0, 4.0) for i in (1, 2, 3)
        )
        responses = (Response(response, "1", about, ("response",)),)
        stage_order = ("response",)
        state_type = FunctionState

        def stage_response(self, state: FunctionState) -> None:
            state.value = function(state.points["x1"], state.points["x2"], state.points["x3"])

        def finish(self, state: FunctionState) -> SceneOutput:
            return SceneOutput(scalars={response: state.value})

    return FunctionScene


@contextmanager
def registered(monkeypatch: pytest.MonkeyPatch, scene: type[Scene]) -> Iterator[None]:
    """``scene`` known to the engine (as a plugin) inside the ``with`` block."""
    monkeypatch.setattr(SCENES, "_plugins", {**SCENES.plugins(), scene.name: scene})
    get_scene.cache_clear()
    yield
    get_scene.cache_clear()
