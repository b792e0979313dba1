"""Helpers for the per-design-point physical checks of a scene (``Scene.check_points``).

A problem that holds at many design points (a fixed parameter, or a factor level that appears
in several runs) is reported once, naming every design point it concerns, so a study with a
bad fixed value gives one message instead of one per run.
"""

from __future__ import annotations

import contextlib
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from contextvars import ContextVar

import numpy as np

from engine_kernels._jit import CompilerNeeded, claim_combinations
from studies.scenes.design_points import DesignPoints, Numbering

LATER_ADVICE = "`check --full` finds the rise angle that makes it convex"
"""The advice of a quick ``check`` whose budget the bisection would exceed."""
LISTED_RANGES = 12
"""A message names at most this many ranges of design points, then counts them all."""
_NUMBERING: ContextVar[Numbering | None] = ContextVar("numbering", default=None)
_CASES: ContextVar[int] = ContextVar("cases", default=1)  # noise cases per design point
_NOMINAL: ContextVar[bool] = ContextVar("nominal", default=False)


Left = list[tuple[tuple[str, ...], CompilerNeeded]]
_LEFT: ContextVar[Left | None] = ContextVar("left", default=None)


@contextlib.contextmanager
def each_check_alone(left: Left) -> Iterator[None]:
    """Within (a quick ``check``): a check run by :func:`on_distinct` that needs the compiler
    or more work than allowed (:class:`engine_kernels._jit.CompilerNeeded`) is left out and
    recorded in ``left`` with the parameters it reads; the other checks go on."""
    token = _LEFT.set(left)
    try:
        yield
    finally:
        _LEFT.reset(token)


def reading(names: Sequence[str]) -> str:
    """The parameters a check reads, for a message (the first four, then a count)."""
    shown = ", ".join(names[:4])
    return shown + (f" and {len(names) - 4} more" if len(names) > 4 else "")


@contextlib.contextmanager
def per_noise_case(cases: int) -> Iterator[None]:
    """Within: the points checked are design point major computed points, ``cases`` noise
    cases a design point, and the messages name design points and noise cases."""
    token = _CASES.set(cases)
    try:
        yield
    finally:
        _CASES.reset(token)


@contextlib.contextmanager
def at_nominal_values() -> Iterator[None]:
    """Within: the points checked are the design points at their nominal values (a quick
    check of a noise study, its noise cases not drawn), and the messages say so."""
    token = _NOMINAL.set(True)
    try:
        yield
    finally:
        _NOMINAL.reset(token)


def on_distinct(
    points: Mapping[str, np.ndarray], names: Sequence[str], check: Callable[..., list[str]]
) -> list[str]:
    """``check(values)`` over the distinct combinations of the parameters ``names`` (all that
    the check reads) instead of every point, the design points its messages name numbered back
    to the study's (:meth:`DesignPoints.distinct`). A plain dict of columns is checked whole."""
    if not isinstance(points, DesignPoints):
        return check(dict(points))
    left = _LEFT.get()
    try:
        claim_combinations(points.combinations_bound(names))
        values, numbering = points.distinct(names)
        token = _NUMBERING.set(numbering)
        try:
            with per_noise_case(points.cases):
                return check(values)
        finally:
            _NUMBERING.reset(token)
    except CompilerNeeded as exc:
        if left is None:
            raise
        left.append((tuple(names), exc))
        return []


def numbered(indices: np.ndarray) -> np.ndarray:
    """The design points of ``indices``: themselves, or inside :func:`on_distinct` the design
    points of the combinations they number (sorted)."""
    numbering = _NUMBERING.get()
    return indices if numbering is None else numbering(np.asarray(indices, dtype=np.int64))


def point_list(indices: Iterable[int] | np.ndarray) -> str:
    """``design point 3`` or ``design points 0–4, 7`` (0-based run indices, ranges merged; the
    first LISTED_RANGES ranges, then the count). Inside :func:`on_distinct` the indices are
    combinations, numbered back to design points here; under noise, to design points and
    noise cases ("design point 2 (all 4 noise cases)", "design point 2 (noise case 1)")."""
    idx = np.unique(
        np.fromiter(indices, dtype=np.int64) if not isinstance(indices, np.ndarray) else indices
    )
    idx = numbered(idx)
    cases = _CASES.get()
    if _NOMINAL.get():
        return f"{_ranges(idx)} at {'its' if idx.size == 1 else 'their'} nominal values"
    if cases == 1:
        return _ranges(idx)
    design, case = np.divmod(idx, cases)  # computed points are design point major
    designs, counts = np.unique(design, return_counts=True)
    if (counts == cases).all():
        return f"{_ranges(designs)} (all {cases} noise cases)"
    shown = [f"{d} (noise case {c})" for d, c in zip(design[:LISTED_RANGES], case, strict=False)]
    more = f", … ({idx.size} in all)" if idx.size > LISTED_RANGES else ""
    return f"design point{'s' if designs.size > 1 else ''} {', '.join(shown)}{more}"


def _ranges(idx: np.ndarray) -> str:
    """``design point 3`` or ``design points 0–4, 7`` of sorted distinct indices."""
    breaks = np.flatnonzero(np.diff(idx) != 1)
    shown = breaks[: LISTED_RANGES - 1]
    starts = idx[np.r_[0, shown + 1]].tolist()
    stops = idx[np.r_[shown, idx.size - 1]].tolist()
    if breaks.size >= LISTED_RANGES:
        stops[-1] = int(idx[breaks[LISTED_RANGES - 1]])
    parts = [str(a) if a == b else f"{a}–{b}" for a, b in zip(starts, stops, strict=True)]
    more = f", … ({idx.size} in all)" if breaks.size >= LISTED_RANGES else ""
    return f"design point{'s' if idx.size > 1 else ''} {', '.join(parts)}{more}"


class PointProblems:
    """Collects ``(design points, message)`` pairs and groups identical messages."""

    def __init__(self) -> None:
        self._points: dict[str, list[np.ndarray]] = {}

    def add(self, point: int, message: str) -> None:
        self.add_all(np.array([point], dtype=np.int64), message)

    def add_all(self, points: Iterable[int] | np.ndarray, message: str) -> None:
        idx = np.asarray(points if isinstance(points, np.ndarray) else list(points), np.int64)
        self._points.setdefault(message, []).append(idx)

    def add_grouped(
        self, points: np.ndarray, columns: Sequence[np.ndarray], message: Callable[[int], str]
    ) -> None:
        """Add ``message(i)`` for the design points ``points`` (indices), whose text depends
        only on ``columns`` (one value or row per design point): formatted once per distinct
        combination, at its first design point, in the order of first appearance."""
        for i, members in groups_of(points, columns):
            self.add_all(members, message(i))

    def add_checked(
        self, points: np.ndarray, columns: Sequence[np.ndarray], check: Callable[[int], list[str]]
    ) -> None:
        """Add the problems ``check(i)`` finds at design point i to the design points
        ``points``, calling it once per distinct combination of ``columns`` (the values it
        reads), as a loop over the points would add them (:func:`checked_groups`)."""
        for message, members in checked_groups(points, columns, check):
            self.add_all(members, message)

    def messages(self) -> list[str]:
        return [f"{point_list(np.concatenate(idx))}: {msg}" for msg, idx in self._points.items()]


def checked_groups(
    points: np.ndarray, columns: Sequence[np.ndarray], check: Callable[[int], list[str]]
) -> list[tuple[str, np.ndarray]]:
    """(message, design points) of each problem ``check(i)`` finds, ``check`` called once per
    distinct combination of ``columns`` among ``points`` (at its first design point), in the
    order a loop over the points meets them."""
    return [(message, members) for i, members in groups_of(points, columns) for message in check(i)]


class LoopOrder:
    """Problems found by numpy masks over all design points, listed as a loop over the points
    would list them: by ``phase`` (one loop after another), then by the first design point a
    message names, then by ``rank`` (the order of the checks inside the loop). Each message is
    formatted once per distinct combination of the values it shows."""

    def __init__(self) -> None:
        self.entries: dict[str, tuple[tuple[int, float], list[np.ndarray]]] = {}

    def add(
        self,
        rank: float,
        where: np.ndarray,
        columns: Sequence[np.ndarray],
        message: Callable[[int], str],
        phase: int = 0,
    ) -> None:
        """``message(i)`` (its text from ``columns`` at design point i) at the points where
        the mask ``where`` holds."""
        for i, members in groups_of(np.flatnonzero(where), columns):
            self.entries.setdefault(message(i), ((phase, rank), []))[1].append(members)

    def into(self, found: PointProblems) -> None:
        """Add the messages to ``found`` in loop order."""
        merged = {text: np.concatenate(parts) for text, (_, parts) in self.entries.items()}

        def key(text: str) -> tuple[int, int, float]:
            phase, rank = self.entries[text][0]
            return phase, int(merged[text].min()), rank

        for text in sorted(merged, key=key):
            found.add_all(merged[text], text)

    def messages(self) -> list[str]:
        found = PointProblems()
        self.into(found)
        return found.messages()


def fixed(text: str) -> Callable[[int], str]:
    """A message that shows no value of the design point (for :meth:`LoopOrder.add`)."""
    return lambda _: text


def groups_of(indices: np.ndarray, columns: Sequence[np.ndarray]) -> list[tuple[int, np.ndarray]]:
    """``indices`` split by the distinct combinations of ``columns`` at them (one value or row
    per index of the columns), in order of first appearance: (first index, indices) each."""
    indices = np.asarray(indices, dtype=np.int64)
    if indices.size == 0:
        return []
    if not columns:
        return [(int(indices[0]), indices)]
    whole = indices.size == len(columns[0]) and bool((indices == np.arange(indices.size)).all())
    first, inverse = distinct([np.asarray(c) if whole else take(c, indices) for c in columns])
    order = np.argsort(inverse, kind="stable")
    bounds = np.cumsum(np.bincount(inverse, minlength=first.size))[:-1]
    members = np.split(indices[order], bounds)
    return list(zip(indices[first].tolist(), members, strict=True))


def distinct(columns: Sequence[np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """The distinct combinations of ``columns`` (equally long; 1-D values of any dtype, or
    2-D rows), numbered in order of first appearance: the first index of each and, per index,
    its combination's number. O(n log n) in numpy, a column that holds one value costs O(n)."""
    n = len(columns[0]) if columns else 0
    group = np.zeros(n, dtype=np.int64)
    for column in columns:
        values = np.asarray(column)
        if n == 0 or _constant(values):
            continue
        if values.ndim > 1:
            codes = np.unique(values.reshape(n, -1), axis=0, return_inverse=True)[1]
        else:
            codes = np.unique(values, return_inverse=True)[1]
        group = np.unique(group * (int(codes.max()) + 1) + codes.ravel(), return_inverse=True)[1]
    group = group.ravel()
    firsts = np.full(int(group.max()) + 1 if n else 0, n, dtype=np.int64)
    np.minimum.at(firsts, group, np.arange(n))
    order = np.argsort(firsts, kind="stable")
    rank = np.empty_like(order)
    rank[order] = np.arange(order.size)
    return firsts[order], rank[group]


def take(values: np.ndarray, idx: np.ndarray) -> np.ndarray:
    """``values[idx]`` along the first axis; a column broadcast from one value (a fixed
    parameter, :func:`studies.define.plan.plan_study`) stays a broadcast view: O(1)."""
    values = np.asarray(values)
    if values.strides and values.strides[0] == 0:
        return np.broadcast_to(values[:1], (len(idx), *values.shape[1:]))
    return values[idx]


def take_points(points: dict[str, np.ndarray], idx: np.ndarray) -> dict[str, np.ndarray]:
    """Every column of ``points`` at the design points ``idx`` (:func:`take`)."""
    return {name: take(values, idx) for name, values in points.items()}


def _constant(values: np.ndarray) -> bool:
    """True when every element (or row) equals the first; a broadcast view is O(1)."""
    if values.strides and values.strides[0] == 0:
        return True
    return bool((values == values[0]).all())


def more_concave_line(
    rest: np.ndarray, shape: np.ndarray, radius_mm: np.ndarray, consequence: str
) -> str:
    """One line counting the concave cam shapes ``rest`` (``shape``: the shape of each point;
    ``radius_mm``: each shape's smallest radius of curvature) that were not warned one by one,
    and their design points (:func:`numbered`)."""
    count = numbered(np.flatnonzero(np.isin(shape, rest))).size
    return (
        f"{rest.size} more concave cams at {count} more design points (smallest radius of "
        f"curvature {radius_mm[rest].min():.3g} … {radius_mm[rest].max():.3g} mm): {consequence}"
    )


def convex_advice(cams: list[int], find: Callable[[], list[str]]) -> dict[int, str]:
    """``find()``'s advice per cam of ``cams`` (where each becomes convex), or, when a quick
    ``check`` cannot afford the bisection (:func:`engine_kernels._jit.without_compiler`),
    where to get it."""
    try:
        return dict(zip(cams, find(), strict=True))
    except CompilerNeeded:
        return dict.fromkeys(cams, LATER_ADVICE)
