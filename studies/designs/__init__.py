"""Experimental designs: which combination of factor levels each run uses.

A :class:`Design` is a table of 0-based level indices, one column per factor plus one per empty
orthogonal-array column (kept as error columns), and one row per run. It knows nothing about
physical values; :mod:`studies.plan` maps level indices to the factors' levels.

Designs: :func:`full_factorial` (any level counts), :func:`sweep` (one factor at a time around a
base point) and :func:`orthogonal` (a catalogue array with column assignment; ``"auto"`` picks
the smallest array that fits).
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass, field

import numpy as np

from studies.designs.orthogonal_arrays import (
    OAInfo,
    interaction_columns,
    list_orthogonal_arrays,
    orthogonal_array,
    smallest_array_for,
)


class DesignError(ValueError):
    """Factors that do not fit the requested design; ``problems`` lists every reason."""

    def __init__(self, problems: list[str]) -> None:
        self.problems = problems
        super().__init__("; ".join(problems))


@dataclass(frozen=True)
class Design:
    """Level indices per run: ``levels[name]`` is an int array of length ``runs``."""

    name: str
    factors: tuple[str, ...]
    levels: dict[str, np.ndarray]
    error_columns: tuple[str, ...] = ()
    labels: dict[str, np.ndarray] = field(default_factory=dict)

    @property
    def runs(self) -> int:
        return len(next(iter(self.levels.values())))


def full_factorial(level_counts: dict[str, int]) -> Design:
    """Every combination of levels; the last factor varies fastest."""
    names = tuple(level_counts)
    grid = np.array(list(itertools.product(*(range(level_counts[n]) for n in names))), dtype=int)
    return Design("full_factorial", names, {n: grid[:, i] for i, n in enumerate(names)})


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
) -> Design:
    """Assign factors to columns of a catalogue orthogonal array.

    ``array`` is a catalogue name or ``"auto"`` (smallest array that fits). ``columns`` maps a
    factor to its 1-based column or None (next free column with a matching level count).
    A factor with fewer levels than its column uses dummy levels (the column's extra levels
    repeat the factor's first levels). Unassigned columns stay as error columns named from
    ``error_names`` in order, then ``e<column>``.
    """
    problems: list[str] = []
    if array == "auto":
        try:
            info = smallest_array_for(list(level_counts.values()))
        except ValueError as exc:
            raise DesignError([str(exc)]) from None
    else:
        try:
            info = _info(array)
        except ValueError as exc:
            raise DesignError([str(exc)]) from None
    table = orthogonal_array(info.name)
    ncols = table.shape[1]
    taken: dict[int, str] = {}
    for name, col in columns.items():
        if col is None:
            continue
        if col > ncols:
            problems.append(f"factor {name}: column {col} does not exist in {info.name} "
                            f"(columns 1–{ncols})")
        elif col - 1 in taken:
            problems.append(f"factors {taken[col - 1]} and {name} are both assigned to column {col}")
        else:
            taken[col - 1] = name
    for name, col in columns.items():
        if col is not None:
            continue
        free = [c for c in range(ncols) if c not in taken]
        fit = [c for c in free if info.levels[c] == level_counts[name]]
        fit = fit or [c for c in free if info.levels[c] > level_counts[name]]
        if fit:
            taken[fit[0]] = name
        else:
            problems.append(f"factor {name} ({level_counts[name]} levels) has no free column "
                            f"left in {info.name}")
    for c, name in taken.items():
        if level_counts[name] > info.levels[c]:
            problems.append(f"factor {name} has {level_counts[name]} levels but column {c + 1} of "
                            f"{info.name} has {info.levels[c]}: use {info.levels[c]} levels or "
                            "another array")
    free = [c for c in range(ncols) if c not in taken]
    if len(error_names) > len(free):
        problems.append(f"{len(error_names)} error column names given but {info.name} leaves "
                        f"{len(free)} column(s) free")
    if problems:
        raise DesignError(problems)
    levels = {name: table[:, c] % level_counts[name] for c, name in sorted(taken.items())}
    ordered = {name: levels[name] for name in level_counts}
    errors: list[str] = []
    for i, c in enumerate(free):
        label = error_names[i] if i < len(error_names) else f"e{c + 1}"
        ordered[label] = table[:, c].copy()
        errors.append(label)
    return Design(info.name, tuple(level_counts), ordered, tuple(errors))


def is_orthogonal_array_name(name: str) -> bool:
    try:
        _info(name)
    except ValueError:
        return False
    return True


def _info(name: str) -> OAInfo:
    runs, cols = orthogonal_array(name).shape
    levels = tuple(int(v) for v in orthogonal_array(name).max(axis=0) + 1)
    canonical = next(
        (i for i in list_orthogonal_arrays() if i.runs == runs and i.levels == levels), None
    )
    if canonical is None:
        msg = f"orthogonal array {name!r} ({runs} runs, {cols} columns) is not in the catalogue"
        raise ValueError(msg)
    return canonical


__all__ = [
    "Design", "DesignError", "OAInfo", "full_factorial", "interaction_columns",
    "is_orthogonal_array_name", "list_orthogonal_arrays", "orthogonal", "orthogonal_array",
    "smallest_array_for", "sweep",
]
