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

from dataclasses import dataclass

import numpy as np
import xarray as xr

from studies.scenes.base import NONE_MEANINGS

DEFAULT = "unknown"


@dataclass(frozen=True)
class Filled:
    """A response's values for the analysis and what was done to the runs without one.

    ``values``: finite, or NaN where left out. ``left_out``: runs without a value that the
    analysis leaves out. ``bounded``: runs counted at ``best_bound`` or ``worst_bound`` (NaN when
    that bound was not used). ``beyond``: +1 where a run is better than every computed value
    (counted at the best bound), -1 where it is worse than every one, 0 elsewhere."""

    values: np.ndarray
    left_out: np.ndarray
    bounded: np.ndarray
    best_bound: float
    worst_bound: float
    beyond: np.ndarray


def none_means(y: xr.DataArray) -> str:
    """What a NaN of ``y`` means (its ``none_means`` attribute, else "unknown")."""
    meaning = str(y.attrs.get("none_means", DEFAULT))
    return meaning if meaning in NONE_MEANINGS else DEFAULT


def fill(y: np.ndarray, ran: np.ndarray, meaning: str, sense: str) -> Filled:
    """``y`` (one value per run) with its non-finite values resolved as the module says.

    ``ran``: the runs that produced a value for some response (the others stay left out);
    ``sense``: "smaller" or "larger" is better."""
    y = np.asarray(y, dtype=float)
    finite = np.isfinite(y)
    if not finite.any():
        left = ~finite
        none = np.zeros(y.shape, dtype=np.int8)
        return Filled(np.full(y.shape, np.nan), left, np.zeros_like(left), np.nan, np.nan, none)
    low, high = float(y[finite].min()), float(y[finite].max())
    best, worst = (low, high) if sense == "smaller" else (high, low)
    nan = np.isnan(y) & ran
    positive = (y == np.inf) & ran
    negative = (y == -np.inf) & ran
    if sense not in ("smaller", "larger"):  # not ranked: nothing is best or worst
        positive = negative = np.zeros_like(nan)
        meaning = DEFAULT
    to_best = (positive if sense == "larger" else negative) | (nan if meaning == "best" else False)
    to_worst = (positive if sense == "smaller" else negative) | (
        nan if meaning == "worst" else False
    )
    values = np.where(finite, y, np.nan)
    values[to_best] = best
    values[to_worst] = worst
    bounded = to_best | to_worst
    return Filled(
        values,
        ~finite & ~bounded,
        bounded,
        best if to_best.any() else np.nan,
        worst if to_worst.any() else np.nan,
        to_best.astype(np.int8) - to_worst.astype(np.int8),
    )


def per_level(mask: np.ndarray, codes: np.ndarray, nlevels: int) -> np.ndarray:
    """How many runs of ``mask`` fall at each level of a factor (O(N), ``bincount``)."""
    return np.bincount(codes[mask], minlength=nlevels)[:nlevels]


def nothing_to_analyse(y: xr.DataArray) -> str:
    """Why a response has nothing to analyse: ``NaN in every design point``, or ``inf`` (or
    ``-inf``, ``±inf``) ``in every design point with a value``."""
    values = np.asarray(y.values, dtype=float)
    infinite = np.unique(values[np.isinf(values)])
    if not infinite.size:
        return "NaN in every design point"
    shown = "±inf" if infinite.size > 1 else ("inf" if infinite[0] > 0 else "-inf")
    return f"{shown} in every design point with a value"
