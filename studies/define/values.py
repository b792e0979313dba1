"""The values of a study file: fixed parameters, factors (levels, units, array column, sweep
base) and settings, each checked against the scene's declarations (type, units, range). A part
of the study parser (:mod:`studies.define.definition`) that collects every problem it finds."""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass
from difflib import get_close_matches
from typing import Any

from studies.common.units import UNITS, canonical, compatible_units
from studies.define.distributions import DISTRIBUTION_KEYS, Spread, factor_distribution
from studies.define.sampling import SAMPLING_DESIGNS as SAMPLED  # factors give range = [lo, hi]
from studies.scenes import Scene
from studies.scenes.base import is_finite_number, short

FACTOR_KEYS = {"levels", "units", "column", "base", "role", "range", *DISTRIBUTION_KEYS}
SHOWN_LEVEL_PROBLEMS = 3  # refused levels listed per factor; the rest are counted
ROLES = ("control", "operating", "model")
"""A control factor is a design choice (its best level is chosen); an operating factor is a
condition the design must meet at every level (engine speed, load): never "chosen"; a model
factor is a rung of a model ladder (the spring's coil masses: 0 = lumped) that computes the
same design another way: never chosen either, its results are reported per model."""


@dataclass(frozen=True)
class Factor:
    """A varied parameter: its levels in ``units``, optional array column and sweep base, and
    its role (``ROLES``: a design choice, or an operating condition the design must meet)."""

    name: str
    levels: tuple[Any, ...]
    units: str
    column: int | None = None
    base: Any = None
    role: str = "control"
    distribution: Spread | None = None  # a sampling design's factor: instead of a range


class ValueParser:
    """Parses ``[parameters]``, ``[factors.*]`` and ``[settings]``, collecting every problem
    in ``problems`` (the study parser adds the other tables' problems to the same list)."""

    def __init__(self) -> None:
        self.problems: list[str] = []

    def problem(self, msg: str) -> None:
        self.problems.append(msg)

    def _parameters(self, scene: Scene, raw: dict[str, Any]) -> dict[str, tuple[Any, str]]:
        out: dict[str, tuple[Any, str]] = {}
        for name, given in raw.items():
            value = given
            param = scene.parameter(name)
            if param is None:
                known = [p.name for p in scene.parameters]
                self.problem(
                    f"unknown parameter {name!r} for scene {scene.name!r}{suggest(name, known)}"
                )
                continue
            units = param.units
            if isinstance(given, dict):
                extra = set(given) - {"value", "units"}
                if extra or "value" not in given:
                    self.problem(f"parameter {name} must be a number or {{value = …, units = …}}")
                    continue
                units = given.get("units", param.units)
                value = given["value"]
            if not self._units_ok(f"parameter {name}", param, units):
                continue
            problem = param.check(value, None if param.kind != "number" else units)
            if problem:
                self.problem(problem)
                continue
            out[name] = (value, canonical(units) if isinstance(units, str) else units)
        return out

    def _units_ok(self, what: str, param: Any, units: Any) -> bool:
        if param.kind != "number":
            if isinstance(units, str) and canonical(units) == param.units:
                return True
            self.problem(f"{what}: units = {short(units)} do not apply to a {param.kind} parameter")
            return False
        if not isinstance(units, str) or units not in UNITS:
            self.problem(f"{what}: unknown units {short(units)} (expected {param.units!r})")
            return False
        if UNITS[units].dimension != UNITS[param.units].dimension:
            compatible = sorted(compatible_units(param.units))
            self.problem(
                f"{what}: units {units!r} measure {UNITS[units].dimension}, but {param.name} is "
                f"measured in {UNITS[param.units].dimension} (use one of {', '.join(compatible)})"
            )
            return False
        return True

    def _factors(self, scene: Scene, raw: dict[str, Any], design: str) -> list[Factor]:
        factors: list[Factor] = []
        for name, spec in raw.items():
            param = scene.parameter(name)
            if param is None:
                known = [p.name for p in scene.parameters]
                self.problem(
                    f"unknown factor {name!r}: scene {scene.name!r} has no such parameter"
                    f"{suggest(name, known)}"
                )
                continue
            if not isinstance(spec, dict):
                self.problem(f"factor {name} must be a table with 'levels' (got {short(spec)})")
                continue
            for key in sorted(set(spec) - FACTOR_KEYS):
                self.problem(f"unknown key {key!r} in factor {name}{suggest(key, FACTOR_KEYS)}")
            if param.kind in ("vector", "text"):
                self.problem(f"{name} is a {param.kind} parameter and cannot be a factor")
                continue
            units = spec.get("units", param.units)
            levels = spec.get("levels")
            given = [k for k in ("range", "distribution") if k in spec]
            if (design in SAMPLED) != bool(given) or (design in SAMPLED and "levels" in spec):
                self.problem(
                    f"factor {name}: a {design} design needs "
                    + (
                        "range = [lo, hi] or a distribution (no levels)"
                        if design in SAMPLED
                        else "levels, not a range or a distribution"
                    )
                )
                continue
            stray = sorted(set(spec) & set(DISTRIBUTION_KEYS) - {"distribution"})
            if len(given) > 1:
                self.problem(f"factor {name}: give a range or a distribution, not both")
                continue
            if stray and "distribution" not in spec:
                self.problem(f"factor {name}: {stray[0]} applies only with a distribution")
                continue
            spread = None
            if "distribution" in spec:
                if not self._units_ok(f"factor {name}", param, units):
                    continue
                spread = factor_distribution(f"factor {name}", spec, param, units, self.problems)
                if spread is None:
                    continue
                levels = [spread.nominal]
            elif design in SAMPLED:
                levels = spec["range"]
                if not (
                    isinstance(levels, list)
                    and len(levels) == 2
                    and all(is_finite_number(v) for v in levels)
                    and levels[0] < levels[1]
                ):
                    self.problem(
                        f"factor {name}: range = {short(levels)} must be [lo, hi], lo < hi"
                    )
                    continue
            ok = self._units_ok(f"factor {name}", param, units)
            if not isinstance(levels, list) or not levels:
                self.problem(f"factor {name} has no levels: give a non-empty list 'levels'")
                continue
            dups = duplicates(levels)
            if dups:
                self.problem(f"factor {name} has duplicate levels: {', '.join(dups)}")
            if ok:
                refused = [
                    p
                    for v in levels
                    if (p := param.check(v, units if param.kind == "number" else None))
                ]
                for problem in refused[:SHOWN_LEVEL_PROBLEMS]:
                    self.problem(f"factor {name}: {problem}")
                if len(refused) > SHOWN_LEVEL_PROBLEMS:
                    more = len(refused) - SHOWN_LEVEL_PROBLEMS
                    self.problem(f"factor {name}: {more} more of its levels are refused likewise")
            column = spec.get("column")
            if column is not None and not (is_finite_number(column) and isinstance(column, int)):
                self.problem(
                    f"factor {name}: column = {short(column)} must be a whole number ≥ 1 "
                    "(an array column)"
                )
                column = None
            elif column is not None and column < 1:
                self.problem(f"factor {name}: column = {column} must be a whole number ≥ 1")
                column = None
            base = spec.get("base")
            if base is not None and (isinstance(base, bool) or base not in levels):
                self.problem(
                    f"factor {name}: base = {short(base)} must be one of its levels {short(levels)}"
                )
                base = None
            if column is not None and design in ("full_factorial", "sweep"):
                self.problem(f"factor {name}: 'column' only applies to orthogonal-array designs")
            role = spec.get("role", "control")
            if role not in ROLES:
                self.problem(
                    f"factor {name}: role = {short(role)} must be one of "
                    f"{', '.join(repr(r) for r in ROLES)} (a design choice, a condition such as "
                    "engine speed that the design must meet at every level, or a model rung)"
                )
                role = "control"
            factors.append(
                Factor(name, tuple(levels), canonical(str(units)), column, base, role, spread)
            )
        return factors

    def _settings(self, scene: Scene, raw: dict[str, Any]) -> dict[str, Any]:
        settings = {s.name: s.default for s in scene.settings}
        for name, value in raw.items():
            setting = scene.setting(name)
            if setting is None:
                known = [s.name for s in scene.settings]
                self.problem(
                    f"unknown setting {name!r} for scene {scene.name!r}{suggest(name, known)}"
                )
                continue
            problem = setting.check(value)
            if problem:
                self.problem(f"setting {problem}")
                continue
            settings[name] = value
        return settings


def duplicates(values: list[Any]) -> list[str]:
    """The values that occur more than once (as ``repr``, sorted), counted in O(n): numbers,
    strings and booleans only (anything else is refused by the value checks)."""
    counted = Counter(v for v in values if isinstance(v, int | float | str))
    return sorted(short(v) for v, n in counted.items() if n > 1)


def suggest(name: str, known: Any) -> str:
    close = get_close_matches(name, list(known), n=1)
    return f" (did you mean {close[0]!r}?)" if close else ""
