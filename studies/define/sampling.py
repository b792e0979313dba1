"""Sampling designs of the control factors: Saltelli's design for Sobol' indices, and scrambled
Sobol' or Latin-hypercube samples for moments, quantiles and rank correlations.

Every factor gives ``range = [lo, hi]`` (uniform) or a distribution
(:mod:`studies.define.distributions`) instead of levels; ``samples`` and ``seed`` are in
``[design]``::

    [design]
    type = "saltelli"            # | "sobol" | "lhs"
    samples = 4096               # saltelli, sobol: a power of two; lhs: any count ≥ 2
    seed = 1
    second_order = true          # saltelli only: also the second-order indices S2

    [factors.x1]
    range = [-3.141592653589793, 3.141592653589793]

``sobol``: N points of a scrambled Sobol' sequence (balanced at N = 2^m); ``lhs``: N points of
a Latin hypercube (scipy.stats.qmc, McKay et al. 1979). ``saltelli`` (Saltelli et al. 2010,
Comput. Phys. Commun. 181, 259): two independent N × D matrices A and B (the two halves of a
scrambled Sobol' sequence in 2D dimensions) and, for each factor i, A_B^(i) = A with column i
from B; with ``second_order``, also B_A^(i) = B with column i from A (Saltelli 2002). The runs
are ordered as SALib orders them: for each base row j, A_j, A_B^(1)_j … A_B^(D)_j, then
B_A^(1)_j … B_A^(D)_j when asked, then B_j — N (D + 2), or N (2D + 2), runs.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from studies.common.design_kinds import SAMPLING_DESIGNS
from studies.scenes.base import short

POWER_OF_TWO = ("saltelli", "sobol")
DEFAULT_SEED = 1
MAX_BASE_SAMPLES = 1 << 20


def parse_sampling(design: Any, kind: str, problems: list[str]) -> tuple[int, int, bool]:
    """``samples``, ``seed`` and ``second_order`` of a ``[design]`` table (problems appended)."""
    table = design if isinstance(design, dict) else {}
    samples, seed = table.get("samples"), table.get("seed", DEFAULT_SEED)
    second = table.get("second_order", False)
    if kind not in SAMPLING_DESIGNS:
        for key in ("samples", "seed", "second_order"):
            if key in table:
                problems.append(
                    f"[design] {key} applies to the sampling types "
                    f"{', '.join(repr(s) for s in SAMPLING_DESIGNS)}, not {kind!r}"
                )
        return 0, DEFAULT_SEED, False
    if (
        not isinstance(samples, int)
        or isinstance(samples, bool)
        or (
            kind in POWER_OF_TWO
            and (not 2 <= samples <= MAX_BASE_SAMPLES or samples & (samples - 1))
        )
        or not 2 <= samples <= MAX_BASE_SAMPLES
    ):
        samples = _bad_samples(kind, samples, problems)
    if not isinstance(seed, int) or isinstance(seed, bool) or seed < 0:
        problems.append(f"[design] seed = {short(seed)} must be a whole number ≥ 0")
        seed = DEFAULT_SEED
    if not isinstance(second, bool):
        problems.append(f"[design] second_order = {short(second)} must be true or false")
        second = False
    elif second and kind != "saltelli":
        problems.append(f'[design] second_order applies to type = "saltelli", not {kind!r}')
        second = False
    return samples, seed, second


def _bad_samples(kind: str, samples: Any, problems: list[str]) -> int:
    if kind == "saltelli":
        what = (
            "a power of two in [2, {}] (Saltelli's base sample N; the study runs "
            "N (factors + 2) points, N (2 factors + 2) with second_order)"
        )
    elif kind == "sobol":
        what = "a power of two in [2, {}] (a Sobol' sequence is balanced at 2^m points), e.g. 256"
    else:
        what = "a whole number of points in [2, {}]"
    problems.append(f"[design] samples = {short(samples)} must be {what.format(MAX_BASE_SAMPLES)}")
    return 0


def sample_runs(kind: str, n: int, d: int, second_order: bool = False) -> int:
    """The runs of a ``kind`` design of ``n`` (base) samples over ``d`` factors."""
    if kind == "saltelli":
        return n * (2 * d + 2 if second_order else d + 2)
    return n


def saltelli_unit(n: int, d: int, seed: int, second_order: bool = False) -> np.ndarray:
    """Saltelli's N (D + 2) (or N (2D + 2)) × D points in the unit cube, in SALib's order
    (module docstring)."""
    from scipy.stats import qmc  # noqa: PLC0415  (on use: reading a study must not import scipy)

    base = qmc.Sobol(2 * d, scramble=True, rng=np.random.default_rng(seed)).random(n)
    a, b = base[:, :d], base[:, d:]
    step = sample_runs("saltelli", 1, d, second_order)
    out = np.empty((n, step, d))
    out[:, 0] = a
    for i in range(d):
        out[:, i + 1] = a
        out[:, i + 1, i] = b[:, i]
        if second_order:
            out[:, d + i + 1] = b
            out[:, d + i + 1, i] = a[:, i]
    out[:, step - 1] = b
    return out.reshape(n * step, d)


def unit_sample(kind: str, n: int, d: int, seed: int, second_order: bool = False) -> np.ndarray:
    """The design's points in the unit cube (runs × D)."""
    from scipy.stats import qmc  # noqa: PLC0415  (on use, as above)

    if kind == "saltelli":
        return saltelli_unit(n, d, seed, second_order)
    rng = np.random.default_rng(seed)
    if kind == "sobol":
        return qmc.Sobol(d, scramble=True, rng=rng).random(n)
    return qmc.LatinHypercube(d, rng=rng).random(n)


def sampled_levels(
    kind: str,
    columns: list[Callable[[np.ndarray], np.ndarray]],
    n: int,
    seed: int,
    second_order: bool = False,
) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """Per factor: its distinct sampled values (as levels) and each run's level code;
    ``columns`` map a factor's unit-cube coordinates to its values (a range's linear map or a
    distribution's inverse CDF)."""
    unit = unit_sample(kind, n, len(columns), seed, second_order)
    levels, codes = [], []
    for j, column in enumerate(columns):
        values, code = np.unique(column(unit[:, j]), return_inverse=True)
        levels.append(values)
        codes.append(code.astype(np.int32))
    return levels, codes
