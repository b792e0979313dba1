"""Helpers for the per-design-point physical checks of a scene (``Scene.check_points``).

A problem that holds at many design points (a fixed parameter, or a factor level that appears
in several runs) is reported once, naming every design point it concerns, so a study with a
bad fixed value gives one message instead of one per run.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence

import numpy as np


def point_list(indices: Iterable[int]) -> str:
    """``design point 3`` or ``design points 0–4, 7`` (0-based run indices, ranges merged)."""
    idx = sorted(set(indices))
    parts: list[str] = []
    start = prev = idx[0]
    for i in [*idx[1:], None]:
        if i is not None and i == prev + 1:
            prev = i
            continue
        parts.append(str(start) if start == prev else f"{start}–{prev}")
        if i is not None:
            start = prev = i
    return f"design point{'s' if len(idx) > 1 else ''} {', '.join(parts)}"


class PointProblems:
    """Collects ``(design point, message)`` pairs and groups identical messages."""

    def __init__(self) -> None:
        self._points: dict[str, list[int]] = {}

    def add(self, point: int, message: str) -> None:
        self._points.setdefault(message, []).append(point)

    def add_all(self, points: Iterable[int], message: str) -> None:
        for i in points:
            self.add(i, message)

    def messages(self) -> list[str]:
        return [f"{point_list(idx)}: {msg}" for msg, idx in self._points.items()]


def more_concave_line(
    rest: np.ndarray, members: Sequence[np.ndarray], radius_mm: np.ndarray, consequence: str
) -> str:
    """One line counting the concave cam shapes ``rest`` (indices into ``members``, the design
    points of each shape; ``radius_mm`` their smallest radius of curvature) that were not
    warned one by one."""
    count = sum(len(members[g]) for g in rest)
    return (
        f"{rest.size} more concave cams at {count} more design points (smallest radius of "
        f"curvature {radius_mm[rest].min():.3g} … {radius_mm[rest].max():.3g} mm): {consequence}"
    )
