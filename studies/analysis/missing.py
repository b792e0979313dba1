"""Design points without a finite value, stated where they act on the analysis.

A response is NaN at a design point that ran when the physics has no value there (no resonance
crossing in the range, no jump), and ±inf when the value is beyond every finite one (the Hertz
stress of a concave cam). What such a point means is declared per response
(``Response.none_means``, stored as the attribute ``none_means``; a study's ``[none_means]``
overrides it):

* ``"best"`` / ``"worst"``: a NaN counts as the best / worst finite value seen over the design
  (a bound: its true value is at least that good / bad), so level means and the ANOVA keep every
  run;
* ``"unknown"`` (default): a NaN is left out, and every level that loses runs says how many.

A response declared not ranked (``[sense] = "none"``) has no best or worst: every run without a
finite value is left out. Otherwise an infinite value is ordered whatever the declaration: +inf is the worst value of a
smaller-is-better response and the best of a larger-is-better one; it counts as the worst /
best finite value seen, the same kind of bound. Design points that did not run at all (no value
in any response) are always left out.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import xarray as xr

from studies.common.blocks import finite_summary, run_slices
from studies.run.results import NOT_EVALUATED, is_status
from studies.scenes.base import NONE_MEANINGS

DEFAULT = "unknown"


@dataclass(frozen=True)
class Filled:
    """A response's values for the analysis and what was done to the runs without one.

    ``values``: finite, or NaN where left out. ``left_out``: runs without a value that the
    analysis leaves out. ``bounded``: runs counted at ``best_bound`` or ``worst_bound`` (NaN when
    that bound was not used). ``beyond``: +1 where a run is better than every computed value
    (counted at the best bound), -1 where it is worse than every one, 0 elsewhere. ``rule``
    resolves any subset of the runs the same way (:class:`Rule`)."""

    values: np.ndarray
    left_out: np.ndarray
    bounded: np.ndarray
    best_bound: float
    worst_bound: float
    beyond: np.ndarray
    rule: Rule | None = None  # how each run was resolved (None: no finite value)


def none_means(y: xr.DataArray | xr.Variable) -> str:
    """What a NaN of ``y`` means (its ``none_means`` attribute, else "unknown")."""
    meaning = str(y.attrs.get("none_means", DEFAULT))
    return meaning if meaning in NONE_MEANINGS else DEFAULT


@dataclass(frozen=True)
class Rule:
    """How :func:`fill` resolves a response's runs, one run at a time: what a NaN means, the
    sense, and the best and worst finite values seen over the whole design (so any subset of
    runs is resolved as the whole response is)."""

    meaning: str
    sense: str
    best: float
    worst: float

    def masks(self, y: np.ndarray, ran: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The runs of ``y`` counted at the best bound and at the worst bound."""
        nan = np.isnan(y) & ran
        if self.sense not in ("smaller", "larger"):  # not ranked: nothing is best or worst
            nothing = np.zeros_like(nan)
            return nothing, nothing
        positive = (y == np.inf) & ran
        negative = (y == -np.inf) & ran
        to_best = (positive if self.sense == "larger" else negative) | (
            nan if self.meaning == "best" else False
        )
        to_worst = (positive if self.sense == "smaller" else negative) | (
            nan if self.meaning == "worst" else False
        )
        return to_best, to_worst

    def apply(
        self, y: np.ndarray, ran: np.ndarray, masks: tuple[np.ndarray, np.ndarray] | None = None
    ) -> np.ndarray:
        """The values of runs ``y`` (finite, bounded, or NaN where left out); ``ran`` of the
        same runs; ``masks``: their :meth:`masks` when already made."""
        y = np.asarray(y, dtype=float)
        finite = np.isfinite(y)
        if masks is None and finite.all():  # nothing to resolve (the common block)
            return y.copy()
        to_best, to_worst = self.masks(y, ran) if masks is None else masks
        values = np.where(finite, y, np.nan)
        values[to_best] = self.best
        values[to_worst] = self.worst
        return values


def rule_of(y: np.ndarray, meaning: str, sense: str) -> Rule | None:
    """The :class:`Rule` of a response's values ``y`` (all runs); None without a finite one."""
    finite = y[np.isfinite(y)]
    if not finite.size:
        return None
    return _rule(float(finite.min()), float(finite.max()), meaning, sense)


def _rule(low: float, high: float, meaning: str, sense: str) -> Rule:
    """The :class:`Rule` of a response whose finite values span ``low`` … ``high``."""
    best, worst = (low, high) if sense == "smaller" else (high, low)
    return Rule(meaning if sense in ("smaller", "larger") else DEFAULT, sense, best, worst)


def fill(y: np.ndarray, ran: np.ndarray, meaning: str, sense: str) -> Filled:
    """``y`` (one value per run) with its non-finite values resolved as the module says.

    ``ran``: the runs that produced a value for some response (the others stay left out);
    ``sense``: "smaller" or "larger" is better."""
    y = np.asarray(y, dtype=float)
    finite = np.isfinite(y)
    rule = rule_of(y, meaning, sense)
    if rule is None:
        left = ~finite
        none = np.zeros(y.shape, dtype=np.int8)
        return Filled(np.full(y.shape, np.nan), left, np.zeros_like(left), np.nan, np.nan, none)
    to_best, to_worst = rule.masks(y, ran)
    values = rule.apply(y, ran, (to_best, to_worst))
    bounded = to_best | to_worst
    return Filled(
        values,
        ~finite & ~bounded,
        bounded,
        rule.best if to_best.any() else np.nan,
        rule.worst if to_worst.any() else np.nan,
        to_best.astype(np.int8) - to_worst.astype(np.int8),
        rule,
    )


class Beyond:
    """:attr:`Filled.beyond` of the runs read (``beyond[a:b]``), computed from the stored
    values where read: nothing held per run."""

    def __init__(self, values: Any, ran: np.ndarray, rule: Rule) -> None:
        self.values, self.ran, self.rule = values, ran, rule

    def __len__(self) -> int:
        return len(self.ran)

    def __getitem__(self, key: slice) -> np.ndarray:
        y = np.asarray(self.values[key], dtype=float)
        if np.isfinite(y).all():  # no run at a bound (the common block)
            return np.zeros(y.shape, dtype=np.int8)
        to_best, to_worst = self.rule.masks(y, self.ran[key])
        return to_best.astype(np.int8) - to_worst.astype(np.int8)


@dataclass(frozen=True)
class Resolved:
    """What :func:`fill` would do, counted without holding a value per run: the :class:`Rule`,
    the runs left out and bounded at each level of each term (terms × levels), the bounds
    used (NaN when not) and :class:`Beyond`."""

    rule: Rule
    left_out: np.ndarray
    bounded: np.ndarray
    best_bound: float
    worst_bound: float
    beyond: Beyond


def resolve(
    values: Any, ran: np.ndarray, meaning: str, sense: str, codes: Sequence[Any], nlevels: int
) -> Resolved | None:
    """:func:`fill` of ``values`` (read a block of runs at a time, e.g. a
    :class:`studies.common.blocks.RunValues`) with the left-out and bounded runs counted per
    level of each term's ``codes``, in two passes (the finite range, then the masks); None
    without a finite value."""
    seen = finite_summary(values)
    if not seen.count:
        return None
    rule = _rule(seen.low, seen.high, meaning, sense)
    left = np.zeros((len(codes), nlevels), dtype=np.int64)
    bounded = np.zeros((len(codes), nlevels), dtype=np.int64)
    used = [False, False]
    for part in run_slices(len(values)):
        y = np.asarray(values[part], dtype=float)
        finite = np.isfinite(y)
        if finite.all():  # no run left out or bounded in this block
            continue
        to_best, to_worst = rule.masks(y, ran[part])
        hit = to_best | to_worst
        miss = ~finite & ~hit
        used = [used[0] or bool(to_best.any()), used[1] or bool(to_worst.any())]
        for j, c in enumerate(codes):
            level = np.asarray(c[part])
            left[j] += np.bincount(level[miss], minlength=nlevels)[:nlevels]
            bounded[j] += np.bincount(level[hit], minlength=nlevels)[:nlevels]
    return Resolved(
        rule,
        left,
        bounded,
        rule.best if used[0] else np.nan,
        rule.worst if used[1] else np.nan,
        Beyond(values, ran, rule),
    )


def per_level(mask: np.ndarray, codes: Any, nlevels: int) -> np.ndarray:
    """How many runs of ``mask`` fall at each level of a factor (O(N), ``bincount`` a block
    of runs at a time; ``codes`` may be read lazily)."""
    counts = np.zeros(nlevels, dtype=np.int64)
    for part in run_slices(len(codes)):
        counts += np.bincount(np.asarray(codes[part])[mask[part]], minlength=nlevels)[:nlevels]
    return counts


def nothing_to_analyse(y: xr.DataArray) -> str:
    """Why a response has nothing to analyse: ``NaN in every design point``, or ``inf`` (or
    ``-inf``, ``±inf``) ``in every design point with a value``."""
    values = np.asarray(y.values, dtype=float)
    infinite = np.unique(values[np.isinf(values)])
    if not infinite.size:
        return "NaN in every design point"
    shown = "±inf" if infinite.size > 1 else ("inf" if infinite[0] > 0 else "-inf")
    return f"{shown} in every design point with a value"


def not_evaluated_as_missing(ds: xr.Dataset, responses: Sequence[str]) -> xr.Dataset:
    """``ds`` with each pass/fail flag that was not evaluated at some run (stored −1: a check
    whose value could not be computed there, as the luffing drive's coupling check where no
    listed motor fits) as float, NaN there: the analysis then leaves such runs out of the
    flag's means like any response without a value (its ``none_means``), instead of averaging
    −1 with the passes and fails. Flags are scanned a block of runs at a time; only those with
    a −1 are read whole."""
    flags = [
        r
        for r in responses
        if "flag_values" in ds[r].attrs
        and not is_status(ds[r])
        and any(
            (np.asarray(ds[r].variable[part]) == NOT_EVALUATED).any()
            for part in run_slices(ds.sizes["run"])
        )
    ]
    return ds.assign(
        {r: ds[r].where(ds[r] != NOT_EVALUATED).assign_attrs(ds[r].attrs) for r in flags}
    )
