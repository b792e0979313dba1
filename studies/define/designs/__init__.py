"""Experimental designs: which combination of factor levels each run uses.

A :class:`Design` is a table of 0-based level indices, one column per factor plus one per empty
orthogonal-array column (kept as error columns), and one row per run. It knows nothing about
physical values; :mod:`studies.define.plan` maps level indices to the factors' levels.

Designs: :func:`full_factorial` (any level counts), :func:`sweep` (one factor at a time around a
base point) and :func:`orthogonal` (a catalogue array with column assignment; ``"auto"`` picks
the smallest array that fits; requested two-factor interactions reserve their columns from the
triangular tables of the GF(q) arrays, e.g. L8, L16, L27).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from studies.define.designs.assignment import (
    DesignError,
    array_info,
    assign_columns,
    pair_problems,
    smallest_fitting,
)
from studies.define.designs.orthogonal_arrays import (
    OAInfo,
    interaction_columns,
    list_orthogonal_arrays,
    orthogonal_array,
    smallest_array_for,
)


@dataclass(frozen=True)
class Design:
    """Level indices per run: ``levels[name]`` is an int array of length ``runs``.

    Orthogonal designs also hold ``columns`` (name → 1-based array column, for factors,
    interaction and error columns) and ``interactions`` (interaction column name → the two
    factors whose interaction it carries).
    """

    name: str
    factors: tuple[str, ...]
    levels: dict[str, np.ndarray]
    error_columns: tuple[str, ...] = ()
    labels: dict[str, np.ndarray] = field(default_factory=dict)
    columns: dict[str, int] = field(default_factory=dict)
    interactions: dict[str, tuple[str, str]] = field(default_factory=dict)

    @property
    def runs(self) -> int:
        return len(next(iter(self.levels.values())))


def full_factorial(level_counts: dict[str, int], lazy: bool = False) -> Design:
    """Every combination of levels; the last factor varies fastest (C order). Level indices
    are repeated and tiled level ranges in a small integer type (10⁷ runs of four factors:
    80 MB, not a list of tuples); ``lazy``: each factor's codes are a :class:`FactorialCodes`
    that makes the codes of the runs it is indexed with (no memory per run)."""
    names = tuple(level_counts)
    counts = [level_counts[n] for n in names]
    runs = int(np.prod(counts, dtype=np.int64))
    levels: dict[str, np.ndarray] = {}
    stride = runs
    for name, count in zip(names, counts, strict=True):
        stride //= count
        codes = FactorialCodes(count, stride, runs)
        levels[name] = codes if lazy else codes[:]  # type: ignore[assignment]
    return Design("full_factorial", names, levels)


@dataclass(frozen=True)
class FactorialCodes:
    """The level codes of one factor of a full factorial, made for the runs asked for: run i
    is at level (i // stride) mod count. ``codes[part]`` (a slice or an index array) gives an
    int array; ``len`` is the number of runs; ``np.asarray`` makes them all."""

    count: int
    stride: int
    runs: int

    def __len__(self) -> int:
        return self.runs

    def __getitem__(self, index: slice | np.ndarray) -> np.ndarray:
        runs = np.arange(*index.indices(self.runs)) if isinstance(index, slice) else index
        dtype = np.int16 if self.count < 2**15 else np.int32
        return (np.asarray(runs, dtype=np.int64) // self.stride % self.count).astype(dtype)

    def __array__(self, dtype: type | None = None, copy: bool | None = None) -> np.ndarray:
        return self[:] if dtype is None else self[:].astype(dtype)

    def astype(self, dtype: type) -> np.ndarray:
        return self[:].astype(dtype)


def sweep(level_counts: dict[str, int], base: dict[str, int]) -> Design:
    """One factor at a time around a base point.

    Run 0 is the base point (every factor at its base level); then, factor by factor, one run
    per non-base level with the other factors at base. Runs = 1 + Σ(levels − 1). The label
    ``swept_factor`` says which factor each run moves ("base" for run 0).
    """
    names = tuple(level_counts)
    rows = [dict(base)]
    swept = ["base"]
    for n in names:
        for lvl in range(level_counts[n]):
            if lvl != base[n]:
                rows.append({**base, n: lvl})
                swept.append(n)
    levels = {n: np.array([r[n] for r in rows], dtype=int) for n in names}
    return Design("sweep", names, levels, labels={"swept_factor": np.array(swept)})


def orthogonal(
    array: str,
    level_counts: dict[str, int],
    columns: dict[str, int | None],
    error_names: tuple[str, ...] = (),
    interactions: Sequence[Sequence[str]] = (),
) -> Design:
    """Assign factors to columns of a catalogue orthogonal array.

    ``array`` is a catalogue name or ``"auto"`` (smallest array that fits, interaction columns
    included). ``columns`` maps a factor to its 1-based column or None (next free column with a
    matching level count). A factor with fewer levels than its column uses dummy levels (the
    column's extra levels repeat the factor's first levels: level = column level mod the
    factor's level count). ``interactions`` lists pairs of factors whose interaction is to be
    estimated: the pair's columns from the triangular table (:func:`interaction_columns`) are
    kept free of factors and named ``A_x_B`` (then ``A_x_B_2``, ... when q-level columns carry
    an interaction in q - 1 columns); factors without a given column are placed so that every
    interaction gets its own columns. Unassigned columns stay as error columns named from
    ``error_names`` in order, then ``e<column>``.
    """
    pairs = [tuple(p) for p in interactions]
    problems = [
        f"factor {name} has {n} level: an orthogonal array varies every factor over at least "
        "2 levels (fix a single value in [parameters])"
        for name, n in level_counts.items()
        if n < 2
    ]
    problems += pair_problems(pairs, level_counts)
    if problems:
        raise DesignError(problems)
    try:
        info = (
            smallest_fitting(level_counts, columns, pairs) if array == "auto" else array_info(array)
        )
    except ValueError as exc:
        raise DesignError([str(exc)]) from None
    table = orthogonal_array(info.name)
    taken, reserved, problems = assign_columns(info, level_counts, columns, pairs)
    used = set(taken) | {c for cols in reserved.values() for c in cols}
    free = [c for c in range(info.columns) if c not in used]
    if len(error_names) > len(free):
        problems.append(
            f"{len(error_names)} error column names given but {info.name} leaves "
            f"{len(free)} column(s) free"
        )
    if problems:
        raise DesignError(problems)
    levels = {name: table[:, c] % level_counts[name] for c, name in sorted(taken.items())}
    ordered = {name: levels[name] for name in level_counts}
    placed = {name: c + 1 for c, name in taken.items()}
    named: dict[str, tuple[str, str]] = {}
    for (a, b), cols in reserved.items():
        for i, c in enumerate(cols):
            label = f"{a}_x_{b}" + (f"_{i + 1}" if i else "")
            ordered[label] = table[:, c].copy()
            named[label] = (a, b)
            placed[label] = c + 1
    errors: list[str] = []
    for i, c in enumerate(free):
        label = error_names[i] if i < len(error_names) else f"e{c + 1}"
        if label in ordered:
            problems.append(
                f"error column name {label!r} is already the name of a factor or interaction column"
            )
        ordered[label] = table[:, c].copy()
        errors.append(label)
        placed[label] = c + 1
    if problems:
        raise DesignError(problems)
    by_column = dict(sorted(placed.items(), key=lambda item: item[1]))
    return Design(
        info.name,
        tuple(level_counts),
        ordered,
        tuple(errors),
        columns=by_column,
        interactions=named,
    )


def is_orthogonal_array_name(name: str) -> bool:
    try:
        array_info(name)
    except ValueError:
        return False
    return True


__all__ = [
    "Design", "DesignError", "OAInfo", "full_factorial", "interaction_columns",
    "is_orthogonal_array_name", "list_orthogonal_arrays", "orthogonal", "orthogonal_array",
    "smallest_array_for", "sweep",
]  # fmt: skip
