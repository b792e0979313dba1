"""The run state of a scene's chunk: what its stages share (the stage protocol of
:class:`studies.scenes.base.Scene`).

A scene's own state subclasses :class:`RunState` with one field per result a stage leaves,
declared ``field(init=False)`` so it is unset until its stage runs. States have slots: writing a
mistyped field raises ``AttributeError`` at once, and so does reading a field no stage filled —
a bug in the scene, which the command line shows with its traceback, never as a user's error.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Self, TypeVar

import numpy as np


@dataclass(slots=True)
class RunState:
    """The request of one chunk of design points, which every stage reads."""

    points: dict[str, np.ndarray]  # parameter → values per design point of the chunk (SI)
    settings: dict[str, Any]  # setting → value (SI)
    responses: tuple[str, ...]  # the responses asked for, in the study's order
    curves: tuple[str, ...]  # the curves asked for, in the study's order
    n: int  # design points in the chunk

    @classmethod
    def of(
        cls,
        points: dict[str, np.ndarray],
        settings: dict[str, Any],
        responses: list[str],
        curves: list[str],
    ) -> Self:
        """The state of a request, before any stage ran."""
        n = len(next(iter(points.values()))) if points else 0
        return cls(points, settings, tuple(responses), tuple(curves), n)


State = TypeVar("State", bound=RunState)
