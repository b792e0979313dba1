"""Distributions of a study file: a value spread about its nominal, as ``[noise]`` tolerances
and the factors of a sampling design give them (``normal``: sd; ``uniform``, ``triangular``
(symmetric): half width; ``relative = true``: in % of the nominal).

A factor of a ``sobol``, ``lhs`` or ``saltelli`` design gives ``range = [lo, hi]`` (uniform) or a
distribution about a ``nominal`` value (default: the scene parameter's default)::

    [factors.spring_rate]
    distribution = "normal"
    nominal = 40.0
    sd = 5
    relative = true

Samples are drawn by the inverse CDF of the design's unit-cube points (Dakota's and SALib's
way: the design's balance carries over). A distribution whose support, or μ ± ``NORMAL_REACH``
σ for a normal one, leaves the parameter's valid range is refused, never truncated.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from studies.scenes.base import Parameter, is_finite_number, short

DISTRIBUTIONS = ("normal", "uniform", "triangular")
DISTRIBUTION_KEYS = ("distribution", "nominal", "sd", "half_width", "relative")
NORMAL_REACH = 6.0  # standard deviations of a normal distribution that must stay in range


def deviation(distribution: str, spread: float, u: np.ndarray) -> np.ndarray:
    """The deviation from the nominal at unit-cube points ``u`` (inverse CDF): ``spread`` is
    the sd of a normal, the half width of a uniform or symmetric triangular distribution."""
    if distribution == "uniform":
        return (2.0 * u - 1.0) * spread
    from scipy import stats  # noqa: PLC0415  (on use: reading a study must not import scipy)

    if distribution == "normal":
        return stats.norm.ppf(u) * spread
    return stats.triang.ppf(u, 0.5, loc=-spread, scale=2.0 * spread)


@dataclass(frozen=True)
class Spread:
    """A factor's distribution about ``nominal`` (the factor's units)."""

    distribution: str
    nominal: float
    spread: float  # sd or half width, in % of the nominal when relative
    relative: bool = False

    def values(self, u: np.ndarray) -> np.ndarray:
        """The factor's values at unit-cube points ``u`` (inverse CDF)."""
        d = deviation(self.distribution, self.spread, u)
        return self.nominal * (1.0 + d / 100.0) if self.relative else self.nominal + d

    def reach(self) -> tuple[float, float]:
        """The lowest and highest value the range check allows for."""
        half = self.spread * (NORMAL_REACH if self.distribution == "normal" else 1.0)
        half = abs(self.nominal) * half / 100.0 if self.relative else half
        return self.nominal - half, self.nominal + half


def factor_distribution(
    where: str, spec: dict[str, Any], param: Parameter, units: str, problems: list[str]
) -> Spread | None:
    """The distribution of a sampling design's factor (``where``: "factor x"), or None with
    the problems appended; its reach must stay inside the parameter's valid range."""
    kind = spec.get("distribution")
    if kind not in DISTRIBUTIONS:
        allowed = ", ".join(repr(d) for d in DISTRIBUTIONS)
        problems.append(f"{where}: distribution = {short(kind)} must be one of {allowed}")
        return None
    if param.integer:
        problems.append(f"{where}: {param.name} is a whole number (a count): give a range")
        return None
    key = "sd" if kind == "normal" else "half_width"
    other = "half_width" if kind == "normal" else "sd"
    if other in spec:
        problems.append(f"{where}: a {kind} distribution takes {key}, not {other}")
        return None
    spread: Any = spec.get(key)
    relative = spec.get("relative", False)
    if not is_finite_number(spread) or spread <= 0:
        problems.append(f"{where}: {key} = {short(spread)} must be a number > 0")
        return None
    if not isinstance(relative, bool):
        problems.append(f"{where}: relative = {short(relative)} must be true or false")
        return None
    if "nominal" not in spec and units != param.units:
        problems.append(f"{where}: give nominal in {units} (the default is in {param.units})")
        return None
    nominal: Any = spec.get("nominal", param.default)
    problem = param.check(nominal, units)
    if problem:
        problems.append(f"{where}: nominal {problem}")
        return None
    found = Spread(kind, float(nominal), float(spread), relative)
    span = f" ± {NORMAL_REACH:g} sd" if kind == "normal" else ""
    for value in found.reach():
        if param.check(value, units):
            problems.append(
                f"{where}: {kind} {key} = {spread:g}{' %' if relative else ' ' + units} about "
                f"{nominal:g} {units} reaches {value:g} {units}{span}, outside the valid range: "
                f"{param.name} allows {param.allowed()} (refused, never truncated: use a "
                "smaller spread)"
            )
            return None
    return found
