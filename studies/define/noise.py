"""Noise factors and response limits of a study file: the ``[noise]`` and ``[limits]`` tables.

A noise factor is a scene parameter the engineer cannot hold exactly (a tolerance, wear, a
condition). Every design point is run at every noise case, so a study of ``runs`` design points
and ``cases`` noise cases computes ``runs × cases`` points in the same chunks::

    [noise]
    type = "L9"                  # an orthogonal array (outer array) | "sobol" | "lhs" | "random"
    samples = 64                 # sampling types only: noise cases per design point
    seed = 1                     # sampling types only (default DEFAULT_SEED)

    [noise.spring_rate]          # a tolerance about the nominal (the control level when the
    distribution = "normal"      # parameter is a factor, else its [parameters] value or default)
    sd = 5                       # normal: standard deviation; uniform/triangular: half_width
    relative = true              # sd in % of the nominal (default: in the parameter's units)

    [noise.lash]
    levels = [0.05, 0.10, 0.15]  # explicit values (parameter units); not for a factor

    [limits]
    jump_speed = { min = 9000 }  # the response's allowed range, in its units: min, max or both

An outer array places a distribution at Taguchi's levels μ ± σ (2-level columns) or μ and
μ ± σ·√(3/2) (3-level columns), σ the distribution's standard deviation (uniform: a/√3,
symmetric triangular: a/√6 for half width a) [Phadke 1989, §8.4]. A sample draws the
distributions by their inverse CDF from scrambled Sobol', Latin hypercube or pseudo-random
points (scipy.stats.qmc), explicit levels uniformly.

A distribution must stay inside the parameter's valid range: it is refused, never truncated
(Dakota samples the declared distribution; a silent truncation would change its moments). The
support of a uniform or triangular distribution, and μ ± ``NORMAL_REACH`` σ of a normal one,
at every nominal value, must lie in the range.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from studies.define.designs import orthogonal
from studies.define.designs.assignment import DesignError, array_info
from studies.define.distributions import DISTRIBUTIONS, NORMAL_REACH, deviation
from studies.define.values import Factor, duplicates, suggest
from studies.scenes import Scene
from studies.scenes.base import Parameter, is_finite_number, short

NOISE_KEYS = ("type", "samples", "seed")
NOISE_FACTOR_KEYS = {"distribution", "sd", "half_width", "relative", "levels"}
SAMPLINGS = ("sobol", "lhs", "random")
LIMIT_KEYS = ("min", "max")
DEFAULT_SEED = 1
MAX_SAMPLES = 1 << 20  # noise cases per design point
SIGMA_PER_HALF_WIDTH = {"uniform": 1.0 / math.sqrt(3.0), "triangular": 1.0 / math.sqrt(6.0)}
TAGUCHI_LEVELS = {2: (-1.0, 1.0), 3: (-math.sqrt(1.5), 0.0, math.sqrt(1.5))}  # in σ


@dataclass(frozen=True)
class NoiseFactor:
    """One noise factor: a distribution about the nominal (``spread`` is the sd or the half
    width, in % of the nominal when ``relative``, else in the parameter's units) or explicit
    ``levels`` (parameter units)."""

    name: str
    distribution: str = ""
    spread: float = 0.0
    relative: bool = False
    levels: tuple[float, ...] = ()

    @property
    def sigma(self) -> float:
        """Standard deviation [% or parameter units]."""
        return self.spread * SIGMA_PER_HALF_WIDTH.get(self.distribution, 1.0)

    @property
    def reach(self) -> float:
        """The largest deviation from the nominal that the range check allows for."""
        return self.spread * (NORMAL_REACH if self.distribution == "normal" else 1.0)


@dataclass(frozen=True)
class Noise:
    """The ``[noise]`` table: how the noise is covered and its factors."""

    type: str
    factors: tuple[NoiseFactor, ...]
    samples: int = 0
    seed: int = DEFAULT_SEED

    @property
    def sampled(self) -> bool:
        return self.type in SAMPLINGS


def parse_noise(raw: Any, scene: Scene, factors: list[Factor], problems: list[str]) -> Noise | None:
    """The ``[noise]`` table (None when absent or unusable); problems are appended."""
    if raw is None:
        return None
    if not isinstance(raw, dict):
        problems.append(f"[noise] must be a table, got {short(raw)}")
        return None
    kind = raw.get("type")
    sampled = kind in SAMPLINGS
    if not isinstance(kind, str) or not (sampled or _is_array(kind)):
        problems.append(
            f'[noise] type = {short(kind)} must be an orthogonal array name (e.g. "L4", '
            f'"L9") or one of {", ".join(repr(s) for s in SAMPLINGS)}'
        )
    samples = raw.get("samples", 0)
    if sampled and not (isinstance(samples, int) and 2 <= samples <= MAX_SAMPLES):
        problems.append(
            f"[noise] samples = {short(samples)} must be a whole number of noise cases per "
            f"design point in [2, {MAX_SAMPLES}]"
        )
    elif kind == "sobol" and samples & (samples - 1):
        problems.append(
            f'[noise] samples = {samples} must be a power of two for type = "sobol" '
            "(a Sobol' sequence is balanced at 2^m points), e.g. 64"
        )
    elif not sampled and "samples" in raw:
        problems.append(f"[noise] samples applies to sampling types, not to the array {kind!r}")
    seed = raw.get("seed", DEFAULT_SEED)
    if not isinstance(seed, int) or isinstance(seed, bool) or seed < 0:
        problems.append(f"[noise] seed = {short(seed)} must be a whole number ≥ 0")
    elif not sampled and "seed" in raw:
        problems.append(f"[noise] seed applies to sampling types, not to the array {kind!r}")
    noise = [
        one
        for name, spec in raw.items()
        if name not in NOISE_KEYS
        and (one := _noise_factor(name, spec, scene, factors, problems)) is not None
    ]
    if not noise and not any(k not in NOISE_KEYS for k in raw):
        problems.append("[noise] names no noise factor: add a table [noise.<parameter>]")
    if not isinstance(kind, str) or not noise:
        return None
    return Noise(kind, tuple(noise), int(samples) if sampled else 0, seed)


def _is_array(name: str) -> bool:
    try:
        array_info(name)
    except ValueError:
        return False
    return True


def _noise_factor(
    name: str, spec: Any, scene: Scene, factors: list[Factor], problems: list[str]
) -> NoiseFactor | None:
    param = scene.parameter(name)
    where = f"[noise.{name}]"
    if param is None:
        known = [p.name for p in scene.parameters]
        allowed = ", ".join(NOISE_KEYS)
        problems.append(
            f"{where}: scene {scene.name!r} has no parameter {name!r}{suggest(name, known)} "
            f"(the keys of [noise] are {allowed} and noise factors)"
        )
        return None
    if not isinstance(spec, dict):
        problems.append(f"{where} must be a table with a distribution or levels, got {short(spec)}")
        return None
    for key in sorted(set(spec) - NOISE_FACTOR_KEYS):
        problems.append(f"unknown key {key!r} in {where}{suggest(key, NOISE_FACTOR_KEYS)}")
    if param.kind != "number":
        problems.append(f"{where}: {name} is a {param.kind} parameter and cannot be noise")
        return None
    factor = next((f for f in factors if f.name == name), None)
    if "levels" in spec:
        return _levels(name, spec, param, factor, problems)
    if param.integer:
        problems.append(
            f"{where}: {name} is a whole number (a count): give explicit levels, not a distribution"
        )
        return None
    distribution = spec.get("distribution")
    if distribution not in DISTRIBUTIONS:
        problems.append(
            f"{where} distribution = {short(distribution)} must be one of "
            f"{', '.join(repr(d) for d in DISTRIBUTIONS)}, or give explicit levels"
        )
        return None
    key = "sd" if distribution == "normal" else "half_width"
    spread: Any = spec.get(key)
    if not is_finite_number(spread) or spread <= 0:
        problems.append(
            f"{where} {key} = {short(spread)} must be a number > 0 (the {distribution} "
            f"distribution's {'standard deviation' if key == 'sd' else 'half width'})"
        )
        return None
    relative = spec.get("relative", False)
    if not isinstance(relative, bool):
        problems.append(f"{where} relative = {short(relative)} must be true or false")
        return None
    return NoiseFactor(name, distribution, float(spread), relative)


def _levels(
    name: str, spec: dict[str, Any], param: Parameter, factor: Factor | None, problems: list[str]
) -> NoiseFactor | None:
    where = f"[noise.{name}]"
    if factor is not None:
        problems.append(
            f"{where}: {name} is also a factor in [factors]; noise on a factor is a tolerance "
            "about its level (distribution with sd or half_width), not explicit levels"
        )
        return None
    extra = sorted(set(spec) & {"distribution", "sd", "half_width", "relative"})
    if extra:
        problems.append(f"{where}: give either levels or a distribution, not both ({extra[0]})")
    levels = spec["levels"]
    if not isinstance(levels, list) or len(levels) < 2:
        problems.append(f"{where} levels = {short(levels)} must list at least 2 values")
        return None
    refused = [p for v in levels if (p := param.check(v))]
    problems += [f"{where}: {p}" for p in refused[:3]]
    dups = duplicates(levels)
    if dups:
        problems.append(f"{where} has duplicate levels: {', '.join(dups)}")
    if refused or dups:
        return None
    return NoiseFactor(name, "levels", levels=tuple(float(v) for v in levels))


def parse_limits(raw: Any, responses: list[str], scene: Scene, problems: list[str]) -> dict:
    """The ``[limits]`` table: response → {"min": …, "max": …} in the response's units."""
    if raw is None:
        return {}
    if not isinstance(raw, dict):
        problems.append(f"[limits] must be a table, got {short(raw)}")
        return {}
    out = {}
    for name, spec in raw.items():
        response = scene.response(name)
        if name not in responses or response is None:
            problems.append(f"[limits] names {name!r}, which is not in responses")
            continue
        if response.flag or response.codes or response.bits:
            problems.append(f"[limits] {name} is a flag or status code: it has no limit")
            continue
        if not isinstance(spec, dict) or not spec or set(spec) - set(LIMIT_KEYS):
            problems.append(
                f"[limits] {name} = {short(spec)} must be a table with min, max or both, "
                f"e.g. {{ min = 9000 }} ({response.units})"
            )
            continue
        bad = [k for k, v in spec.items() if not is_finite_number(v)]
        if bad:
            problems.append(f"[limits] {name} {bad[0]} = {short(spec[bad[0]])} must be a number")
            continue
        if "min" in spec and "max" in spec and spec["min"] >= spec["max"]:
            problems.append(
                f"[limits] {name} min = {spec['min']} must be below max = {spec['max']}"
            )
            continue
        out[name] = {k: float(v) for k, v in spec.items()}
    return out


# --- the cases ------------------------------------------------------------------------------
def noise_table(noise: Noise) -> dict[str, np.ndarray]:
    """Per noise factor, its deviation from the nominal in each noise case (% or parameter
    units; for explicit levels the value itself). Raises DesignError when the outer array does
    not fit the factors."""
    if noise.sampled:
        return _sampled(noise)
    counts = {
        f.name: len(f.levels) if f.levels else _array_levels(noise.type) for f in noise.factors
    }
    design = orthogonal(noise.type, counts, dict.fromkeys(counts))
    out = {}
    for f in noise.factors:
        codes = design.levels[f.name]
        if f.levels:
            out[f.name] = np.asarray(f.levels)[codes]
            continue
        if counts[f.name] not in TAGUCHI_LEVELS:
            msg = f"[noise] type = {noise.type!r} has {counts[f.name]}-level columns: use 2 or 3"
            raise DesignError([msg])
        out[f.name] = np.asarray(TAGUCHI_LEVELS[counts[f.name]])[codes] * f.sigma
    return out


def noise_needs_stats(noise: Noise | None) -> bool:
    """Whether drawing the noise cases imports scipy.stats: a Sobol' or Latin hypercube sample,
    or a normal or triangular distribution's inverse CDF."""
    if noise is None or not noise.sampled:
        return False
    return noise.type != "random" or any(
        f.distribution in ("normal", "triangular") for f in noise.factors if not f.levels
    )


def _array_levels(name: str) -> int:
    """The level count of a distribution's column in ``name``: 3 when the array has 3-level
    columns (L9, L18, L27), else its most common level count."""
    levels = array_info(name).levels
    return 3 if 3 in levels else max(set(levels), key=levels.count)


def _sampled(noise: Noise) -> dict[str, np.ndarray]:
    # scipy on use: reading a study (and every light command) must not import it
    from scipy.stats import qmc  # noqa: PLC0415

    d, n = len(noise.factors), noise.samples
    rng = np.random.default_rng(noise.seed)
    if noise.type == "sobol":
        u = qmc.Sobol(d, scramble=True, rng=rng).random(n)
    elif noise.type == "lhs":
        u = qmc.LatinHypercube(d, rng=rng).random(n)
    else:
        u = rng.random((n, d))
    out = {}
    for j, f in enumerate(noise.factors):
        if f.levels:
            picks = np.minimum((u[:, j] * len(f.levels)).astype(np.int64), len(f.levels) - 1)
            out[f.name] = np.asarray(f.levels)[picks]
        else:
            out[f.name] = deviation(f.distribution, f.spread, u[:, j])
    return out


def noisy(f: NoiseFactor, nominal: np.ndarray, deviation: np.ndarray) -> np.ndarray:
    """Values (runs × cases) of ``f`` about the nominal per run: explicit levels as given,
    else nominal + deviation (or nominal · (1 + deviation/100) when relative)."""
    if f.levels:
        return np.broadcast_to(deviation, (nominal.size, deviation.size))
    if f.relative:
        return nominal[:, None] * (1.0 + deviation[None, :] / 100.0)
    return nominal[:, None] + deviation[None, :]


def range_problems(noise: Noise, param: Parameter, nominal: np.ndarray, units: str) -> list[str]:
    """Why the noise on ``param`` could leave its valid range at some nominal (``units``)."""
    f = next(x for x in noise.factors if x.name == param.name)
    if f.levels or nominal.size == 0:
        return []
    lo, hi = float(nominal.min()), float(nominal.max())
    reach = f.reach / 100.0 if f.relative else f.reach
    low = lo * (1.0 - reach) if f.relative else lo - reach
    high = hi * (1.0 + reach) if f.relative else hi + reach
    sd_or_width = "sd" if f.distribution == "normal" else "half_width"
    spread = f"{f.spread:g}{' %' if f.relative else ' ' + units}"
    span = f" ± {NORMAL_REACH:g} sd" if f.distribution == "normal" else ""
    out = []
    for value, nom in ((low, lo), (high, hi)):
        problem = param.check(value, units)
        if problem:
            out.append(
                f"[noise.{param.name}] {f.distribution} {sd_or_width} = {spread} about "
                f"{nom:g} {units} reaches {value:g} {units}{span}, outside the valid range: "
                f"{param.name} allows {param.allowed()} (noise is refused, never truncated: "
                "use a smaller spread)"
            )
    return out
