"""The SI parameter values of a study's computed points, made when they are read (issue #28).

A study computes design points × noise cases, design point major. A factor's column is its
levels (in SI, converted once) indexed by the design's level codes, a fixed parameter one value,
a noise factor one value per computed point. :class:`DesignPoints` stores nothing per point
beyond the design's codes (none for a full factorial: :class:`~studies.define.designs.
FactorialCodes`) and the noise values:

- ``points.at(part)`` makes the values of the computed points ``part`` (a chunk, when it runs);
- ``points[name]`` makes one whole column and keeps it (a plugin's check may read it);
- ``points.distinct(names)`` gives the distinct combinations of the parameters ``names`` and
  a numbering from them back to the computed points, so a physical check that reads only some
  parameters runs over their combinations (a 10⁷-point study of four operating factors has one
  cam to check), not over every point (:func:`studies.scenes.checks.on_distinct`).
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

DISTINCT_KEPT = 4
KEPT_COMBINATIONS = 1 << 16
"""Answers of :meth:`DesignPoints.distinct` with at most this many combinations are kept;
larger ones (10⁶ combinations of a 10⁸-point study: tens of MB) are made again when asked."""
Numbering = Callable[[np.ndarray], np.ndarray]
"""Indices of combinations -> the computed points that have them (sorted)."""


@dataclass(frozen=True)
class Factor:
    """A parameter varied by the design: its SI levels and each design point's level code."""

    levels: np.ndarray
    codes: Any  # an int array per design point, or a FactorialCodes (len and indexing)


class DesignPoints(Mapping[str, np.ndarray]):
    """Parameter values of ``runs`` design points × ``cases`` noise cases (see the module
    docstring). ``fixed``: one value (or vector row) per parameter; ``factors`` in the design's
    order (the first varies slowest in a full factorial); ``noise``: one value per computed
    point (flat)."""

    def __init__(
        self,
        runs: int,
        fixed: dict[str, Any],
        factors: dict[str, Factor],
        noise: dict[str, np.ndarray] | None = None,
        cases: int = 1,
        order: Sequence[str] = (),
    ) -> None:
        self.runs, self.cases = runs, cases
        self.fixed, self.factors, self.noise = fixed, factors, noise or {}
        self.order = tuple(order) or tuple(list(fixed) + list(factors) + list(self.noise))
        self.start = 0  # the first computed point whose noise values and codes are held
        self._columns: dict[str, np.ndarray] = {}
        self._distinct: dict[tuple[str, ...], tuple[dict[str, np.ndarray], Numbering]] = {}

    def for_chunk(self, part: slice) -> DesignPoints:
        """What a worker needs to make the values of the computed points ``part`` (whole
        design points) with :meth:`at`: the levels and fixed values, the codes and noise values
        of ``part`` only, no caches. A full factorial's chunk without noise pickles to a few kB
        whatever the study's size (a task carries it, not the chunk's values)."""
        start, stop, _ = part.indices(self.n)
        rows = slice(start // self.cases, -(-stop // self.cases))
        factors = {
            name: f if _strided(f) else Factor(f.levels, np.asarray(f.codes)[rows])
            for name, f in self.factors.items()
        }
        noise = {name: values[start:stop] for name, values in self.noise.items()}
        chunk = DesignPoints(self.runs, self.fixed, factors, noise, self.cases, self.order)
        chunk.start = start
        return chunk

    def __getstate__(self) -> dict[str, Any]:
        """Pickled without the caches (whole columns, combinations)."""
        return {**self.__dict__, "_columns": {}, "_distinct": {}}

    @property
    def n(self) -> int:
        """Computed points: design points × noise cases."""
        return self.runs * self.cases

    def __iter__(self) -> Iterator[str]:
        return iter(self.order)

    def __len__(self) -> int:
        return len(self.order)

    def __getitem__(self, name: str) -> np.ndarray:
        """The whole column (made on first use and kept: a check that reads it point by
        point must not remake it; the built-in checks read :meth:`distinct` instead)."""
        if name not in self._columns:
            if name not in self.order:
                raise KeyError(name)
            flat = np.arange(self.n)
            self._columns[name] = self._values(flat, flat // self.cases, (name,))[name]
        return self._columns[name]

    def at(self, part: slice | np.ndarray) -> dict[str, np.ndarray]:
        """The values of the computed points ``part`` (a slice or sorted indices), as arrays."""
        flat = np.arange(*part.indices(self.n)) if isinstance(part, slice) else np.asarray(part)
        rows = flat // self.cases
        return self._values(flat, rows)

    def _values(
        self, flat: np.ndarray, rows: np.ndarray, names: Sequence[str] = ()
    ) -> dict[str, np.ndarray]:
        out: dict[str, np.ndarray] = {}
        for name in names or self.order:
            if name in self.noise:
                out[name] = self.noise[name][flat - self.start]
            elif name in self.factors:
                factor = self.factors[name]
                held = rows if _strided(factor) else rows - self.start // self.cases
                out[name] = factor.levels[factor.codes[held]]
            else:
                value = np.asarray(self.fixed[name])
                out[name] = np.broadcast_to(value, (flat.size, *value.shape))
        return out

    def distinct(self, names: Sequence[str]) -> tuple[dict[str, np.ndarray], Numbering]:
        """The distinct combinations of the parameters ``names`` among the computed points, in
        order of first appearance, as values of every parameter (those not in ``names`` at the
        first point of each combination), and the numbering back to the computed points. The
        last DISTINCT_KEPT answers of at most KEPT_COMBINATIONS combinations are kept: a check
        and its warnings share them."""
        key = tuple(names)
        if key in self._distinct:
            return self._distinct[key]
        answer = self._combinations(names)
        if self.combinations_bound(names) <= KEPT_COMBINATIONS:
            while len(self._distinct) >= DISTINCT_KEPT:
                del self._distinct[next(iter(self._distinct))]
            self._distinct[key] = answer
        return answer

    def combinations_bound(self, names: Sequence[str]) -> int:
        """At most how many distinct combinations of ``names`` :meth:`distinct` finds, from the
        level counts alone (O(factors))."""
        varying = [n for n in self.order if n in names and (n in self.factors or n in self.noise)]
        if any(n in self.noise for n in varying):
            return self.n
        levels = math.prod(len(self.factors[n].levels) for n in varying)
        return min(levels, self.runs)

    def _combinations(self, names: Sequence[str]) -> tuple[dict[str, np.ndarray], Numbering]:
        varying = [n for n in self.order if n in names and (n in self.factors or n in self.noise)]
        if any(n in self.noise for n in varying):
            return self.at(slice(None)), _identity
        if all(_strided(f) for f in self.factors.values()):
            return self._factorial(varying)
        return self._coded(varying)

    def _factorial(self, chosen: list[str]) -> tuple[dict[str, np.ndarray], Numbering]:
        """Combinations of a full factorial's factors, made from the level counts alone."""
        chosen = sorted(chosen, key=lambda n: -self.factors[n].codes.stride)  # design order
        counts = [self.factors[n].codes.count for n in chosen]
        first = np.zeros(int(np.prod(counts, dtype=np.int64)), dtype=np.int64)
        if chosen:
            digits = np.unravel_index(np.arange(first.size), counts)
            for name, digit in zip(chosen, digits, strict=True):
                first += digit * self.factors[name].codes.stride
        others = [f.codes for n, f in self.factors.items() if n not in chosen]

        @functools.cache
        def free() -> np.ndarray:
            """Offsets of the other factors' levels, made on first use."""
            offsets = np.zeros(1, dtype=np.int64)
            for codes in others:
                offsets = np.add.outer(offsets, np.arange(codes.count) * codes.stride).ravel()
            return offsets

        def numbering(local: np.ndarray) -> np.ndarray:
            members = np.add.outer(first[np.asarray(local, dtype=np.int64)], free()).ravel()
            return self._cases(np.sort(members))

        return self._values(first * self.cases, first), numbering

    def _coded(self, chosen: list[str]) -> tuple[dict[str, np.ndarray], Numbering]:
        """Combinations found among the design's codes (an array's or a sweep's runs)."""
        from studies.scenes.checks import distinct  # noqa: PLC0415  (checks imports this module)

        if not chosen:
            first, inverse = np.zeros(1, dtype=np.int64), np.zeros(self.runs, dtype=np.int64)
        else:
            first, inverse = distinct([np.asarray(self.factors[n].codes) for n in chosen])

        def numbering(local: np.ndarray) -> np.ndarray:
            return self._cases(np.flatnonzero(np.isin(inverse, np.asarray(local))))

        return self._values(first * self.cases, first), numbering

    def _cases(self, design_points: np.ndarray) -> np.ndarray:
        """The computed points of ``design_points`` (each with its noise cases)."""
        if self.cases == 1:
            return design_points
        return (design_points[:, None] * self.cases + np.arange(self.cases)).ravel()


def _strided(factor: Factor) -> bool:
    """True when the factor's codes are a full factorial's (made from count and stride)."""
    return hasattr(factor.codes, "stride")


def _identity(local: np.ndarray) -> np.ndarray:
    return np.asarray(local, dtype=np.int64)
