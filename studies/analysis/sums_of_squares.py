"""Sums of squares of categorical terms, exact and O(N): level sums, never a dense design matrix.

Every term is a vector of 0-based level codes on the runs (a factor, an array column, an
interaction column). The response is centred first by a two-pass mean, so a large constant
part (10¹² Pa + a small effect) costs no digits.

* Balanced designs (complete full factorials and orthogonal arrays: every pair of terms has
  proportional frequencies, n_ij = n_i n_j / N) have orthogonal terms, so each term's sum of
  squares is Taguchi's level-sum formula Σ n_i (k_i - ȳ)², one ``bincount`` per term.
* Otherwise (runs dropped for NaN) the type I (sequential) sums of squares, as statsmodels'
  ``anova_lm(typ=1)``, come from one solve: the normal equations of the treatment-coded terms
  are assembled from pairwise level counts (``bincount`` of combined codes, O(N) per pair,
  p × p with p = Σ (levels - 1) + 1) and factored once by a rank-revealing Cholesky; the squared
  entries of the triangular solve, grouped by term, are the sequential sums of squares.
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator, Sequence
from typing import Any

import numpy as np

from studies.common.blocks import Values, code_range, level_count, run_slices, values_of

RANK_TOLERANCE = 1e-9  # relative pivot below which a dummy column counts as dependent
# A sum of squares below this fraction of the total is round-off of a zero effect (an effect
# the response does not have still leaves ~ε² of the total from the centred sums): reported 0.
ROUND_OFF = 1e-12


def round_off_of(values: np.ndarray) -> float:
    """The round-off level of ``values``: ``ROUND_OFF`` of their largest finite magnitude (0
    when none is finite); values closer than this are equal in exact arithmetic."""
    finite = np.abs(values[np.isfinite(values)])
    return ROUND_OFF * float(finite.max()) if finite.size else 0.0


def without_round_off(ss: np.ndarray, total: float) -> np.ndarray:
    """``ss`` with the entries at round-off level of ``total`` set to exactly zero."""
    return np.where(np.abs(ss) <= ROUND_OFF * total, 0.0, ss)


def centred(y: np.ndarray) -> np.ndarray:
    """``y`` minus its mean, by two passes (the second corrects the first mean's rounding),
    in one new array (the second pass in place: the same numbers, half the memory)."""
    d = y - y.mean()
    d -= d.mean()
    return d


class Centred:
    """:func:`centred` of ``y`` a block of runs at a time (:mod:`studies.common.blocks`): the
    two means over the blocks, then each block's values ``(y - m1) - m2`` on request — the
    numbers of :func:`centred` bit for bit when ``y`` is one block (else its means differ in
    the last bits), without an array as large as ``y``."""

    def __init__(self, y: Values) -> None:
        self.y, self.size = y, y.size
        self.first = _block_sum(y[part] for part in run_slices(y.size)) / y.size
        self.second = _block_sum(y[part] - self.first for part in run_slices(y.size)) / y.size

    def block(self, part: slice) -> np.ndarray:
        d = self.y[part] - self.first
        d -= self.second
        return d

    def blocks(self) -> Iterator[tuple[slice, np.ndarray]]:
        for part in run_slices(self.size):
            yield part, self.block(part)

    def sum(self) -> float:
        return _block_sum(d for _, d in self.blocks())

    def dot(self) -> float:
        """Σ d² as ``d @ d`` (a block at a time)."""
        return sum((float(d @ d) for _, d in self.blocks()), 0.0)

    def squares(self) -> float:
        """Σ d² as ``np.sum(d ** 2)`` (a block at a time)."""
        return _block_sum(d**2 for _, d in self.blocks())


def _block_sum(parts: Iterable[np.ndarray]) -> float:
    return sum((float(np.sum(p)) for p in parts), 0.0)


def level_sums(
    codes: np.ndarray, y: np.ndarray, levels: int, finite: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """Count and sum of ``y`` at each level 0…levels-1 of ``codes``, over the runs where
    ``finite`` (all when None) — by weights, without copying out the finite runs."""
    if finite is None or finite.all():
        n = np.bincount(codes, minlength=levels).astype(float)
        return n, np.bincount(codes, weights=y, minlength=levels)
    n = np.bincount(codes, weights=finite, minlength=levels)
    return n, np.bincount(codes, weights=np.where(finite, y, 0.0), minlength=levels)


def level_sums_in_blocks(
    codes: Any, y: Values, levels: int, finite: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """:func:`level_sums` a block of runs at a time (``codes`` may be read lazily): the
    same numbers for one block, the blocks' sums added for more."""
    n, s = np.zeros(levels), np.zeros(levels)
    for part in run_slices(len(codes)):
        n_part, s_part = level_sums(
            np.asarray(codes[part]), y[part], levels, None if finite is None else finite[part]
        )
        n += n_part
        s += s_part
    return n, s


def is_balanced(terms: Sequence[Any]) -> bool:
    """True if every pair of terms has proportional frequencies (orthogonal main effects).
    Counts accumulated over blocks of runs (exact; the codes may be read lazily)."""
    total = len(terms[0]) if terms else 0
    widths = [level_count(t) for t in terms]
    counts = [np.zeros(w, dtype=np.int64) for w in widths]
    pairs = [(a, b) for a in range(len(terms)) for b in range(a + 1, len(terms))]
    joints = {(a, b): np.zeros(widths[a] * widths[b], dtype=np.int64) for a, b in pairs}
    for part in run_slices(total):
        codes = [np.asarray(t[part]) for t in terms]
        for i, c in enumerate(codes):
            counts[i] += np.bincount(c, minlength=widths[i])
        for a, b in pairs:
            joints[a, b] += np.bincount(
                codes[a].astype(np.int64) * widths[b] + codes[b], minlength=joints[a, b].size
            )
    for a, b in pairs:
        expected = np.outer(counts[a], counts[b]) / total
        if not np.array_equal(joints[a, b].reshape(widths[a], widths[b]), expected):
            return False
    return True


def term_sums_of_squares(
    y: Values, terms: Sequence[Any], balanced: bool | None = None
) -> tuple[np.ndarray, np.ndarray, float]:
    """Type I sums of squares and dof of ``terms`` in order, and the total SS of ``y``.

    ``y`` holds finite values only; each term is an integer code vector of the same length
    (an array, or a variable read lazily: balanced terms are read a block of runs at a time).
    The centred response is made a block of runs at a time (:class:`Centred`). ``balanced``:
    known (e.g. a complete full factorial), else None: :func:`is_balanced` counts it.
    """
    d = Centred(values_of(y))
    total = d.dot()
    codes = list(terms)
    if is_balanced(codes) if balanced is None else balanced:
        ss, dof = _balanced(d, codes)
    else:
        ss, dof = _sequential(d, codes)
    return without_round_off(ss, total), dof, total


def _balanced(d: Centred, terms: list[np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    ss, dof = np.zeros(len(terms)), np.zeros(len(terms), dtype=np.int64)
    for i, t in enumerate(terms):
        levels = level_count(t)
        n, s = np.zeros(levels), np.zeros(levels)
        for part, block in d.blocks():
            n_part, s_part = level_sums(np.asarray(t[part]), block, levels)
            n += n_part
            s += s_part
        seen = n > 0
        ss[i] = float(np.sum(s[seen] ** 2 / n[seen]))
        dof[i] = int(seen.sum()) - 1
    return ss, dof


def _dummies(terms: Sequence[Any]) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """Per term: the levels present but the first (treatment coding) and the lookup from a
    level to its dummy column (-1 for the reference level and for absent levels); the codes
    read a block of runs at a time."""
    present, lookups = [], []
    for t in terms:
        low, high = code_range(t)
        seen = np.zeros(high - min(low, 0) + 1, dtype=bool)
        for part in run_slices(len(t)):
            seen[np.asarray(t[part]) - min(low, 0)] = True
        levels = np.flatnonzero(seen)
        lookup = np.full(int(levels.max()) + 1, -1, dtype=np.int32)
        lookup[levels[1:]] = np.arange(levels.size - 1)
        present.append(levels[1:])
        lookups.append(lookup)
    return present, lookups


def normal_equations(d: Centred, terms: Sequence[Any]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Gram matrix XᵀX, Xᵀd and the term of each column for intercept + treatment dummies,
    from level counts and level sums (O(N) per pair of terms), accumulated over blocks of
    :data:`studies.common.blocks.BLOCK` runs so that the dummy codes of one block are held at a time."""
    present, lookups = _dummies(terms)
    shifts = [min(code_range(t)[0], 0) for t in terms]
    widths = [p.size for p in present]
    starts = np.concatenate([[1], 1 + np.cumsum(widths)])
    p = int(starts[-1])
    gram, rhs = np.zeros((p, p)), np.zeros(p)
    gram[0, 0], rhs[0] = d.size, d.sum()
    owner = np.concatenate([[-1], np.repeat(np.arange(len(terms)), widths)])
    for part, block in d.blocks():
        recoded = [
            lookup[t[part] - shift] for lookup, t, shift in zip(lookups, terms, shifts, strict=True)
        ]
        _add_block(gram, rhs, block, recoded, widths, starts)
    return gram, rhs, owner


def _add_block(
    gram: np.ndarray,
    rhs: np.ndarray,
    d: np.ndarray,
    recoded: list[np.ndarray],
    widths: list[int],
    starts: np.ndarray,
) -> None:
    """Add one block's level counts, level sums and joint counts to ``gram`` and ``rhs``."""
    for a, (ca, wa) in enumerate(zip(recoded, widths, strict=True)):
        if wa == 0:
            continue
        sa = slice(starts[a], starts[a] + wa)
        keep = ca >= 0
        n_a, s_a = level_sums(ca[keep], d[keep], wa)
        gram[0, sa] += n_a
        gram[sa, 0] += n_a
        gram[sa, sa] += np.diag(n_a)
        rhs[sa] += s_a
        for b in range(a + 1, len(recoded)):
            cb, wb = recoded[b], widths[b]
            if wb == 0:
                continue
            both = keep & (cb >= 0)
            combined = ca[both].astype(np.int64) * wb + cb[both]
            joint = np.bincount(combined, minlength=wa * wb).reshape(wa, wb)
            sb = slice(starts[b], starts[b] + wb)
            gram[sa, sb] += joint
            gram[sb, sa] += joint.T


def _sequential(d: Centred, terms: Sequence[Any]) -> tuple[np.ndarray, np.ndarray]:
    gram, rhs, owner = normal_equations(d, terms)
    z, independent = _cholesky_solve(gram, rhs)
    ss = np.array([float(np.sum(z[owner == i] ** 2)) for i in range(len(terms))])
    dof = np.array([int(np.sum(independent[owner == i])) for i in range(len(terms))])
    return ss, dof


def _cholesky_solve(gram: np.ndarray, rhs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """z = R⁻ᵀ rhs for gram = RᵀR, columns in order; a column whose pivot falls below
    ``RANK_TOLERANCE`` of its own norm depends on the earlier ones and gets z = 0."""
    p = gram.shape[0]
    r = np.zeros_like(gram)
    z = np.zeros(p)
    independent = np.zeros(p, dtype=bool)
    for j in range(p):
        column = gram[j, j:] - r[:j, j] @ r[:j, j:]
        pivot = column[0]
        if pivot <= RANK_TOLERANCE * gram[j, j]:
            continue
        independent[j] = True
        root = np.sqrt(pivot)
        r[j, j:] = column / root
        z[j] = (rhs[j] - r[:j, j] @ z[:j]) / root
    return z, independent
