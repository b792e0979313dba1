"""Taguchi's standard orthogonal arrays, in his column order, with 0-based levels.

Arrays with q^k runs (L4, L8, L16, L32 over GF(2); L9, L27 over GF(3); L16(4^5) over GF(4);
L25 over GF(5)) are generated: run r has base-q digits (x1, ..., xk), the first varying
slowest, and a column with coefficient vector c holds c·x over GF(q). Taguchi's order takes the
basic columns x1, x2, ... in turn and, after each basic column xm, the columns xm + a·(x1..x(m-1))
for every earlier combination a, the first coefficient varying fastest. This gives, e.g.,
L8 column 3 = 1 ⊕ 2, 5 = 1 ⊕ 4, 6 = 2 ⊕ 4, 7 = 1 ⊕ 2 ⊕ 4, and L9 column 3 = c1 + c2,
column 4 = 2·c1 + c2 (mod 3), exactly as the printed tables (1-based there).

The other arrays are tabulated: L12 (Plackett-Burman), L18 and L32(2^1 4^9) row by row; the
L36 and L54 arrays by their standard construction from a difference scheme D over GF(3): runs
3i, 3i+1, 3i+2 repeat row i of a small array (L12, L4 x a 3-level block column, or L18) and
carry D[i] + 0, 1, 2 (mod 3) in the remaining 3-level columns. The tables follow the printed
catalogues (G. Taguchi, *System of Experimental Design*, 1987; M. S. Phadke, *Quality
Engineering Using Robust Design*, 1989, appendix C; Minitab's catalogue of Taguchi designs).
Every array is checked for balance of every column pair in the tests.
"""

from __future__ import annotations

import functools
import itertools
import re
from collections import Counter
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from studies.common.errors import StudyError


@dataclass(frozen=True)
class OAInfo:
    """One catalogue array: canonical name, number of runs, level count of each column."""

    name: str
    runs: int
    levels: tuple[int, ...]

    @property
    def columns(self) -> int:
        return len(self.levels)


_L12 = """
00000000000 00000111111 00111000111 01011011001 01101101010 01110110100
10110011010 10101110001 10011101100 11100001101 11010100011 11001010110
"""

_L18 = """
00000000 00111111 00222222 01001122 01112200 01220011 02010212 02121020 02202101
10022110 10100221 10211002 11012021 11120102 11201210 12021201 12102012 12210120
"""

_L32_2_4 = """
0000000000 0011111111 0022222222 0033333333 0100112233 0111003322 0122330011 0133221100
0201230123 0210321032 0223012301 0232103210 0301322310 0310233201 0323100132 0332011023
1003031212 1012120303 1021213030 1030302121 1103123021 1112032130 1121301203 1130210312
1202201331 1213310220 1220023113 1231132002 1302313102 1313202013 1320131320 1331020231
"""

# Difference scheme D(12, 12, 3) of both L36 arrays (rows i = 0..11).
_D12 = """
000000000000 000011112222 001201220112 002102121021 012021022101 012100212210
010222011012 011220100221 021012202011 021110021202 022212110100 020121201120
"""

# Difference scheme D(18, 18, 3) of L54 (rows i = 0..17).
_D18 = """
000000000000000000 000000121212121212 000000212121212121 001122000012122121
001122121221210000 001122212100001212 010212001200211221 010212122112002100
010212210021120012 022110002121121200 022110120000212112 022110211212000021
012021001221002112 012021122100120021 012021210012211200 021201002112210012
021201120021001221 021201211200122100
"""

_GF4_MUL = np.array([[0, 0, 0, 0], [0, 1, 2, 3], [0, 2, 3, 1], [0, 3, 1, 2]])


def _digits(text: str) -> np.ndarray:
    return np.array([[int(c) for c in row] for row in text.split()], dtype=np.int64)


def _gf_tables(q: int) -> tuple[np.ndarray, np.ndarray]:
    """Addition and multiplication tables of GF(q), q in {2, 3, 4, 5}; GF(4) = {0, 1, a, a^2}."""
    r = np.arange(q)
    if q == 4:
        return np.bitwise_xor.outer(r, r), _GF4_MUL
    return np.add.outer(r, r) % q, np.multiply.outer(r, r) % q


def _column_vectors(q: int, k: int) -> np.ndarray:
    """Coefficient vectors of the (q^k - 1)/(q - 1) columns, in Taguchi's order."""
    vectors = [
        (*earlier[::-1], 1) + (0,) * (k - m - 1)
        for m in range(k)
        for earlier in itertools.product(range(q), repeat=m)
    ]
    return np.array(vectors, dtype=np.int64)


def _linear_array(q: int, k: int) -> np.ndarray:
    add, mul = _gf_tables(q)
    x = np.array(list(itertools.product(range(q), repeat=k)), dtype=np.int64)
    vectors = _column_vectors(q, k)
    table = np.zeros((q**k, len(vectors)), dtype=np.int64)
    for i in range(k):
        table = add[table, mul[x[:, i][:, None], vectors[:, i][None, :]]]
    return table


def _from_difference_scheme(head: np.ndarray, scheme: np.ndarray) -> np.ndarray:
    """Runs 3i + s = (head[i], (scheme[i] + s) mod 3) for s = 0, 1, 2."""
    rows = [
        np.concatenate([h, (d + s) % 3])
        for h, d in zip(head, scheme, strict=True)
        for s in range(3)
    ]
    return np.array(rows, dtype=np.int64)


def _l36_3_13_head() -> np.ndarray:
    """L4 in columns 1-3 repeated over a 3-level column 4 (the block)."""
    l4 = _linear_array(2, 2)
    return np.array([[*l4[i % 4], i // 4] for i in range(12)], dtype=np.int64)


# GF(q) arrays (which also have interaction tables): canonical name → (q, k), runs = q^k.
_LINEAR: dict[str, tuple[int, int]] = {
    "L4(2^3)": (2, 2),
    "L8(2^7)": (2, 3),
    "L9(3^4)": (3, 2),
    "L16(2^15)": (2, 4),
    "L16(4^5)": (4, 2),
    "L25(5^6)": (5, 2),
    "L27(3^13)": (3, 3),
    "L32(2^31)": (2, 5),
}

_TABULATED: dict[str, Callable[[], np.ndarray]] = {
    "L12(2^11)": lambda: _digits(_L12),
    "L18(2^1 3^7)": lambda: _digits(_L18),
    "L32(2^1 4^9)": lambda: _digits(_L32_2_4),
    "L36(2^11 3^12)": lambda: _from_difference_scheme(_digits(_L12), _digits(_D12)),
    "L36(2^3 3^13)": lambda: _from_difference_scheme(_l36_3_13_head(), _digits(_D12)),
    "L54(2^1 3^25)": lambda: _from_difference_scheme(_digits(_L18), _digits(_D18)),
}

_CATALOGUE_ORDER = (
    "L4(2^3)", "L8(2^7)", "L9(3^4)", "L12(2^11)", "L16(2^15)", "L16(4^5)", "L18(2^1 3^7)",
    "L25(5^6)", "L27(3^13)", "L32(2^31)", "L32(2^1 4^9)", "L36(2^11 3^12)", "L36(2^3 3^13)",
    "L54(2^1 3^25)",
)  # fmt: skip

# Bare run counts that name more than one array mean the first of them in Taguchi's usage.
_BARE_DEFAULT = {"L16": "L16(2^15)", "L32": "L32(2^31)", "L36": "L36(2^11 3^12)"}


def _normalise(name: str) -> str:
    return re.sub(r"[\s,\u00d7x*]", "", name.strip().lower())


def _levels_from_name(name: str) -> tuple[int, ...]:
    """'L18(2^1 3^7)' → (2, 3, 3, 3, 3, 3, 3, 3)."""
    parts = re.findall(r"(\d+)\^(\d+)", name[name.index("(") :])
    return tuple(int(s) for s, n in parts for _ in range(int(n)))


_INFO = {n: OAInfo(n, int(n[1 : n.index("(")]), _levels_from_name(n)) for n in _CATALOGUE_ORDER}

_ALIASES: dict[str, str] = {_normalise(n): n for n in _CATALOGUE_ORDER}
_ALIASES |= {_normalise(n[: n.index("(")]): n for n in _CATALOGUE_ORDER}
_ALIASES |= {_normalise(bare): n for bare, n in _BARE_DEFAULT.items()}


def _canonical(name: str) -> str:
    key = _ALIASES.get(_normalise(name))
    if key is None:
        known = ", ".join(_CATALOGUE_ORDER)
        msg = (
            f"unknown orthogonal array {name!r}; known arrays: {known} "
            "(bare L16, L32 and L36 mean L16(2^15), L32(2^31) and L36(2^11 3^12))"
        )
        raise StudyError(msg)
    return key


@functools.cache
def _base(name: str) -> np.ndarray:
    table = _linear_array(*_LINEAR[name]) if name in _LINEAR else _TABULATED[name]()
    table.setflags(write=False)
    return table


def orthogonal_array(name: str) -> np.ndarray:
    """The array ``name`` as an int array of shape (runs, columns), levels 0..s-1.

    ``name`` is a canonical name such as ``"L18(2^1 3^7)"`` or a bare ``"L9"``; bare ``"L16"``,
    ``"L32"`` and ``"L36"`` mean L16(2^15), L32(2^31) and L36(2^11 3^12). Spaces, case and
    ``x``/``x`` separators are ignored. Returns a fresh, writable copy.
    """
    return _base(_canonical(name)).copy()


def list_orthogonal_arrays() -> list[OAInfo]:
    """Every catalogue array, smallest first."""
    return [_INFO[n] for n in _CATALOGUE_ORDER]


def _describe(level_counts: Sequence[int]) -> str:
    counts = sorted(Counter(level_counts).items())
    return " and ".join(f"{n} factor(s) at {s} levels" for s, n in counts)


def _fits_native(info: OAInfo, needed: Counter[int]) -> bool:
    have = Counter(info.levels)
    return all(have[s] >= n for s, n in needed.items())


def _fits_with_dummy(info: OAInfo, needed: Counter[int]) -> bool:
    """A factor may take a column with more levels (dummy levels); Hall's condition."""
    return all(
        sum(n for s2, n in needed.items() if s2 >= s) <= sum(1 for t in info.levels if t >= s)
        for s in needed
    )


def smallest_array_for(level_counts: Sequence[int], interactions: int = 0) -> OAInfo:
    """The smallest catalogue array with a column for every factor.

    ``level_counts`` holds the number of levels of each factor. Arrays where every factor finds
    a column with its own level count are preferred; only when none exists may a factor take a
    column with more levels (dummy levels, e.g. a 2-level factor in a 3-level column).
    ``interactions`` two-factor interactions need s - 1 extra columns each; they are supported
    for factors of one level count s in the arrays with interaction tables (see
    :func:`interaction_columns`). The column count is necessary, not sufficient: check the
    assignment with :func:`interaction_columns`. Raises ValueError when nothing fits.
    """
    counts = [int(c) for c in level_counts]
    if not counts or min(counts) < 2:
        msg = f"every factor needs at least 2 levels, got {counts}"
        raise StudyError(msg)
    if interactions < 0:
        msg = f"interactions must be >= 0, got {interactions}"
        raise StudyError(msg)
    catalogue = list_orthogonal_arrays()
    needed = Counter(counts)
    if interactions:
        if len(needed) != 1:
            msg = (
                "interaction columns are defined only for factors with one level count, "
                f"got {_describe(counts)}"
            )
            raise StudyError(msg)
        (s,) = needed
        needed = Counter({s: len(counts) + interactions * (s - 1)})
        catalogue = [i for i in catalogue if i.name in _LINEAR]
    native = [i for i in catalogue if _fits_native(i, needed)]
    if native:
        return min(native, key=lambda i: i.runs)
    dummy = [] if interactions else [i for i in catalogue if _fits_with_dummy(i, needed)]
    if dummy:
        return min(dummy, key=lambda i: i.runs)
    extra = f" plus {interactions} interaction(s)" if interactions else ""
    msg = (
        f"no catalogue orthogonal array has columns for {_describe(counts)}{extra}; "
        f"the catalogue holds {', '.join(_CATALOGUE_ORDER)}; use a full factorial or fewer "
        "factors/levels"
    )
    raise StudyError(msg)


def interaction_columns(name: str, col_a: int, col_b: int) -> tuple[int, ...]:
    """0-based columns that carry the interaction of columns ``col_a`` and ``col_b``.

    Taguchi's triangular tables, from the GF(q) construction: the interaction of columns with
    coefficient vectors u and v lies in the columns proportional to u + c·v, c = 1..q-1 (one
    column for 2-level arrays, two for L9/L27, ...). E.g. L8 (0-based) (0, 1) → (2,);
    L27 (1, 4) → (7, 10), which is 2 x 5 → 8, 11 in the printed 1-based table.
    """
    canonical = _canonical(name)
    if canonical not in _LINEAR:
        msg = (
            f"{canonical} has no interaction table (its interactions are spread over "
            f"several columns); arrays with one: {', '.join(_LINEAR)}"
        )
        raise StudyError(msg)
    q, k = _LINEAR[canonical]
    vectors = _column_vectors(q, k)
    ncols = len(vectors)
    for col in (col_a, col_b):
        if not 0 <= col < ncols:
            msg = f"column {col} is not in {canonical} (0-based columns 0..{ncols - 1})"
            raise StudyError(msg)
    if col_a == col_b:
        msg = f"an interaction needs two different columns, got {col_a} twice"
        raise StudyError(msg)
    add, mul = _gf_tables(q)
    by_multiple = {tuple(mul[scale, v]): j for j, v in enumerate(vectors) for scale in range(1, q)}
    u, v = vectors[col_a], vectors[col_b]
    return tuple(sorted(by_multiple[tuple(add[u, mul[c, v]])] for c in range(1, q)))
