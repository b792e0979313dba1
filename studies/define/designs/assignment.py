"""Column assignment in an orthogonal array: which column each factor takes, which columns the
requested two-factor interactions reserve (from the triangular tables of the GF(q) arrays),
and the smallest catalogue array that fits (``"auto"``)."""

from __future__ import annotations

import functools
from collections.abc import Iterator

from studies.common.errors import StudyError
from studies.define.designs.orthogonal_arrays import (
    OAInfo,
    interaction_columns,
    list_orthogonal_arrays,
    orthogonal_array,
    smallest_array_for,
)


class DesignError(StudyError):
    """Factors that do not fit the requested design; ``problems`` lists every reason."""

    def __init__(self, problems: list[str]) -> None:
        self.problems = problems
        super().__init__("; ".join(problems))


# Column placements tried when searching for room for the interaction columns.
INTERACTION_SEARCH_LIMIT = 20_000


Pair = tuple[str, ...]


def pair_problems(pairs: list[Pair], level_counts: dict[str, int]) -> list[str]:
    problems = []
    seen: set[frozenset[str]] = set()
    for pair in pairs:
        if len(pair) != 2:
            problems.append(f"interaction {list(pair)} must name exactly two factors")
            continue
        unknown = [f for f in pair if f not in level_counts]
        if unknown:
            problems.append(
                f"interaction {pair[0]} x {pair[1]}: {', '.join(unknown)} is not a "
                f"factor (factors: {', '.join(level_counts)})"
            )
        if pair[0] == pair[1]:
            problems.append(f"interaction {pair[0]} x {pair[1]} needs two different factors")
        if frozenset(pair) in seen:
            problems.append(f"interaction {pair[0]} x {pair[1]} is requested twice")
        seen.add(frozenset(pair))
    return problems


@functools.cache
def _interaction_table(name: str) -> dict[tuple[int, int], tuple[int, ...]]:
    """Every column pair of ``name`` → its interaction columns; empty without a table."""
    ncols = orthogonal_array(name).shape[1]
    try:
        interaction_columns(name, 0, 1)
    except ValueError:
        return {}
    return {
        (a, b): interaction_columns(name, a, b)
        for a in range(ncols)
        for b in range(ncols)
        if a != b
    }


def _has_interaction_table(name: str) -> bool:
    return bool(_interaction_table(name))


def smallest_fitting(
    level_counts: dict[str, int], columns: dict[str, int | None], pairs: list[Pair]
) -> OAInfo:
    """The smallest catalogue array that fits the factors and leaves room for the interactions."""
    if not pairs:
        return smallest_array_for(list(level_counts.values()))
    involved = sorted({f for p in pairs for f in p})
    counts = sorted({level_counts[f] for f in involved})
    if len(counts) > 1:
        msg = (
            f"interacting factors {', '.join(involved)} must have one level count for an "
            f"interaction table, got {counts}"
        )
        raise StudyError(msg)
    q = counts[0]
    needed = len(level_counts) + len(pairs) * (q - 1)
    candidates = [
        info for info in list_orthogonal_arrays()
        if set(info.levels) == {q} and info.columns >= needed
        and max(level_counts.values()) <= q and _has_interaction_table(info.name)
    ]  # fmt: skip
    for info in candidates:
        if not assign_columns(info, level_counts, columns, pairs)[2]:
            return info
    tried = ", ".join(i.name for i in candidates) or "none has enough columns"
    msg = (
        f"no catalogue array with an interaction table fits {len(level_counts)} factor(s) "
        f"and {len(pairs)} interaction(s) of {q}-level factors ({needed} columns; tried: "
        f"{tried}); use fewer interactions or factors"
    )
    raise StudyError(msg)


def assign_columns(
    info: OAInfo, level_counts: dict[str, int], columns: dict[str, int | None], pairs: list[Pair]
) -> tuple[dict[int, str], dict[Pair, tuple[int, ...]], list[str]]:
    """Column (0-based) → factor, interaction pair → its columns, and the problems found."""
    ncols = info.columns
    problems: list[str] = []
    taken: dict[int, str] = {}
    for name, col in columns.items():
        if col is None:
            continue
        if col > ncols:
            problems.append(
                f"factor {name}: column {col} does not exist in {info.name} (columns 1-{ncols})"
            )
        elif col - 1 in taken:
            problems.append(
                f"factors {taken[col - 1]} and {name} are both assigned to column {col}"
            )
        else:
            taken[col - 1] = name
    reserved: dict[Pair, tuple[int, ...]] = {}
    if pairs:
        layout_problems = _interaction_problems(info, level_counts, pairs)
        layout_problems = layout_problems or _fixed_reservations(info.name, taken, pairs)[2]
        if layout_problems:
            return taken, reserved, problems + layout_problems
        failure = None
        budget = [INTERACTION_SEARCH_LIMIT]
        for placed, reserved in _layouts(info, level_counts, taken, pairs, budget):
            rest, failure = _place_rest(info, level_counts, columns, taken | placed, reserved)
            if not failure:
                taken = rest
                break
        else:
            stopped = (
                f" (search stopped after {INTERACTION_SEARCH_LIMIT} placements)"
                if budget[0] <= 0
                else ""
            )
            listed = ", ".join(f"{a} x {b}" for a, b in pairs)
            problems += failure or [
                (
                    f"no assignment of the factors to columns of {info.name} leaves the "
                    f"interactions {listed} columns of their own{stopped}: use a larger array, "
                    "other columns or fewer interactions"
                )
            ]
            return taken, {}, problems
    else:
        taken, failure = _place_rest(info, level_counts, columns, taken, {})
        problems += failure
    for c, name in taken.items():
        if level_counts[name] > info.levels[c]:
            problems.append(
                f"factor {name} has {level_counts[name]} levels but column {c + 1} of "
                f"{info.name} has {info.levels[c]}: use {info.levels[c]} levels or "
                "another array"
            )
    return taken, reserved, problems


def _place_rest(
    info: OAInfo,
    level_counts: dict[str, int],
    columns: dict[str, int | None],
    taken: dict[int, str],
    reserved: dict[Pair, tuple[int, ...]],
) -> tuple[dict[int, str], list[str]]:
    """Give each factor still without a column the next free one (own level count first)."""
    taken = dict(taken)
    placed = set(taken.values())
    blocked = {c for cols in reserved.values() for c in cols}
    problems = []
    for name, col in columns.items():
        if col is not None or name in placed:
            continue
        free = [c for c in range(info.columns) if c not in taken and c not in blocked]
        fit = [c for c in free if info.levels[c] == level_counts[name]]
        fit = fit or [c for c in free if info.levels[c] > level_counts[name]]
        if fit:
            taken[fit[0]] = name
        else:
            problems.append(
                f"factor {name} ({level_counts[name]} levels) has no free column "
                f"left in {info.name}"
            )
    return taken, problems


def _interaction_problems(
    info: OAInfo, level_counts: dict[str, int], pairs: list[Pair]
) -> list[str]:
    if not _has_interaction_table(info.name):
        msg = (
            f"{info.name} has no interaction table: interactions need one of the arrays "
            'L4, L8, L9, L16, L16(4^5), L25, L27, L32(2^31) (or design = "auto")'
        )
        return [msg]
    q = info.levels[0]
    involved = dict.fromkeys(f for p in pairs for f in p)
    return [
        f"factor {f} has {level_counts[f]} levels but its interactions in {info.name} need "
        f"{q}-level factors (dummy levels cannot carry an interaction)"
        for f in involved
        if level_counts[f] != q
    ]


def _layouts(
    info: OAInfo,
    level_counts: dict[str, int],
    taken: dict[int, str],
    pairs: list[Pair],
    budget: list[int],
) -> Iterator[tuple[dict[int, str], dict[Pair, tuple[int, ...]]]]:
    """Placements of the interacting factors where no column serves two purposes.

    Depth-first over the free columns in order, so the first placement is the textbook one
    (e.g. L8: A, B in columns 1, 2 → A x B in 3; C in 4 → A x C in 5). ``budget`` counts down
    the placements tried. Nothing is yielded when the given columns already collide.
    """
    table = _interaction_table(info.name)
    fixed = {name: c for c, name in taken.items()}
    todo = [f for f in dict.fromkeys(f for p in pairs for f in p) if f not in fixed]
    used, reserved, clashes = _fixed_reservations(info.name, taken, pairs)
    if clashes:
        return

    def search(
        i: int, where: dict[str, int], used: set[int], reserved: dict[Pair, tuple[int, ...]]
    ) -> Iterator[tuple[dict[int, str], dict[Pair, tuple[int, ...]]]]:
        if budget[0] <= 0:
            return
        budget[0] -= 1
        if i == len(todo):
            yield {where[f]: f for f in todo}, reserved
            return
        f = todo[i]
        for c in range(info.columns):
            if c in used or info.levels[c] != level_counts[f]:
                continue
            now_used, now_reserved = used | {c}, dict(reserved)
            for pair in pairs:
                other = pair[1] if pair[0] == f else pair[0] if pair[1] == f else None
                if other not in where:
                    continue
                cols = table[c, where[other]] if pair[0] == f else table[where[other], c]
                if now_used & set(cols):
                    break
                now_used |= set(cols)
                now_reserved[pair] = cols
            else:
                yield from search(i + 1, where | {f: c}, now_used, now_reserved)

    yield from search(0, fixed, used, reserved)


def _fixed_reservations(
    name: str, taken: dict[int, str], pairs: list[Pair]
) -> tuple[set[int], dict[Pair, tuple[int, ...]], list[str]]:
    """Columns used by the placed factors and by the interactions of placed pairs; clashes."""
    table = _interaction_table(name)
    where = {factor: c for c, factor in taken.items()}
    used = set(taken)
    owner = {c: f"factor {factor}" for c, factor in taken.items()}
    reserved: dict[Pair, tuple[int, ...]] = {}
    clashes = []
    for a, b in pairs:
        if a in where and b in where:
            cols = table[where[a], where[b]]
            for c in cols:
                if c in owner:
                    clashes.append(
                        f"interaction {a} x {b} falls in column {c + 1} of {name}, "
                        f"which {owner[c]} takes"
                    )
                owner[c] = f"interaction {a} x {b}"
            used |= set(cols)
            reserved[(a, b)] = cols
    return used, reserved, clashes


def array_info(name: str) -> OAInfo:
    runs, cols = orthogonal_array(name).shape
    levels = tuple(int(v) for v in orthogonal_array(name).max(axis=0) + 1)
    canonical = next(
        (i for i in list_orthogonal_arrays() if i.runs == runs and i.levels == levels), None
    )
    if canonical is None:
        msg = f"orthogonal array {name!r} ({runs} runs, {cols} columns) is not in the catalogue"
        raise StudyError(msg)
    return canonical
