"""Sampling designs of the control factors: Saltelli's design for Sobol' indices.

``[design] type = "saltelli"`` with ``samples = N`` (the base sample, a power of two) and
``seed``; every factor gives ``range = [lo, hi]`` (uniform) instead of levels::

    [design]
    type = "saltelli"
    samples = 4096
    seed = 1

    [factors.x1]
    range = [-3.141592653589793, 3.141592653589793]

Saltelli et al. 2010 (Comput. Phys. Commun. 181, 259): two independent N × D matrices A and B
(here the two halves of a scrambled Sobol' sequence in 2D dimensions, scipy.stats.qmc) and,
for each factor i, A_B^(i) = A with column i from B. The runs are ordered as SALib orders
them: for each base row j, A_j, A_B^(1)_j … A_B^(D)_j, B_j — N (D + 2) runs.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from studies.scenes.base import short

SAMPLING_DESIGNS = ("saltelli",)
DEFAULT_SEED = 1
MAX_BASE_SAMPLES = 1 << 20


def parse_sampling(design: Any, kind: str, problems: list[str]) -> tuple[int, int]:
    """``samples`` and ``seed`` of a ``[design]`` table (problems appended)."""
    table = design if isinstance(design, dict) else {}
    samples, seed = table.get("samples"), table.get("seed", DEFAULT_SEED)
    if kind not in SAMPLING_DESIGNS:
        for key in ("samples", "seed"):
            if key in table:
                problems.append(f'[design] {key} applies to type = "saltelli", not {kind!r}')
        return 0, DEFAULT_SEED
    if (
        not isinstance(samples, int)
        or isinstance(samples, bool)
        or not 2 <= samples <= MAX_BASE_SAMPLES
        or samples & (samples - 1)
    ):
        problems.append(
            f"[design] samples = {short(samples)} must be a power of two in [2, "
            f"{MAX_BASE_SAMPLES}] (Saltelli's base sample N; the study runs N (factors + 2) "
            "points)"
        )
        samples = 0
    if not isinstance(seed, int) or isinstance(seed, bool) or seed < 0:
        problems.append(f"[design] seed = {short(seed)} must be a whole number ≥ 0")
        seed = DEFAULT_SEED
    return samples, seed


def saltelli_unit(n: int, d: int, seed: int) -> np.ndarray:
    """Saltelli's N (D + 2) × D points in the unit cube, in SALib's order (module docstring)."""
    from scipy.stats import qmc  # noqa: PLC0415  (on use: reading a study must not import scipy)

    base = qmc.Sobol(2 * d, scramble=True, rng=np.random.default_rng(seed)).random(n)
    a, b = base[:, :d], base[:, d:]
    out = np.empty((n, d + 2, d))
    out[:, 0] = a
    for i in range(d):
        out[:, i + 1] = a
        out[:, i + 1, i] = b[:, i]
    out[:, d + 1] = b
    return out.reshape(n * (d + 2), d)


def sampled_levels(
    ranges: list[tuple[float, float]], n: int, seed: int
) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """Per factor: its distinct sampled values (as levels) and each run's level code."""
    unit = saltelli_unit(n, len(ranges), seed)
    levels, codes = [], []
    for j, (lo, hi) in enumerate(ranges):
        values, code = np.unique(lo + (hi - lo) * unit[:, j], return_inverse=True)
        levels.append(values)
        codes.append(code.astype(np.int32))
    return levels, codes
