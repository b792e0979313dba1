"""Orthogonal-array catalogue: balance, Taguchi's column relations, interaction tables, choice.

Expected values come from the definition of a strength-2 orthogonal array (every level pair of
every column pair equally often), from the GF(q) relations of Taguchi's standard column order,
and from the printed tables (Taguchi 1987; Phadke 1989, appendix C; Minitab's catalogue of
Taguchi designs), quoted 1-based as printed.
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from studies.define.designs.orthogonal_arrays import (
    interaction_columns,
    list_orthogonal_arrays,
    orthogonal_array,
    smallest_array_for,
)

CATALOGUE = list_orthogonal_arrays()
NAMES = [info.name for info in CATALOGUE]

# GF(4) = {0, 1, a, a^2} coded 0, 1, 2, 3 (a^2 = a + 1): addition is XOR, multiplication below.
GF4_MUL = np.array([[0, 0, 0, 0], [0, 1, 2, 3], [0, 2, 3, 1], [0, 3, 1, 2]])


def printed(rows: str) -> np.ndarray:
    """A table as printed (1-based digits, one run per word) → 0-based array."""
    return np.array([[int(c) - 1 for c in row] for row in rows.split()])


@pytest.mark.parametrize("info", CATALOGUE, ids=NAMES)
def test_shape_and_levels_match_the_name(info):
    table = orthogonal_array(info.name)
    assert table.shape == (info.runs, len(info.levels))
    assert tuple(int(v) for v in table.max(axis=0) + 1) == info.levels
    assert table.min() == 0


@pytest.mark.parametrize("info", CATALOGUE, ids=NAMES)
def test_every_column_and_column_pair_is_balanced(info):
    # Definition of a strength-2 orthogonal array.
    table = orthogonal_array(info.name)
    for j, s in enumerate(info.levels):
        assert (np.bincount(table[:, j], minlength=s) == info.runs // s).all(), j
    for a, b in itertools.combinations(range(info.columns), 2):
        sa, sb = info.levels[a], info.levels[b]
        counts = np.bincount(table[:, a] * sb + table[:, b], minlength=sa * sb)
        assert (counts == info.runs // (sa * sb)).all(), (a + 1, b + 1)


@pytest.mark.parametrize("name", ["L4", "L8", "L16", "L32"])
def test_two_level_columns_follow_taguchis_xor_order(name):
    # Taguchi's 2-level order: 1-based column i ⊕ column j is column (i XOR j).
    table = orthogonal_array(name)
    ncols = table.shape[1]
    for i, j in itertools.combinations(range(1, ncols + 1), 2):
        assert (table[:, (i ^ j) - 1] == table[:, i - 1] ^ table[:, j - 1]).all(), (i, j)


def test_l8_relations_as_printed():
    c = orthogonal_array("L8").T
    assert (c[2] == c[0] ^ c[1]).all()
    assert (c[4] == c[0] ^ c[3]).all()
    assert (c[5] == c[1] ^ c[3]).all()
    assert (c[6] == c[0] ^ c[1] ^ c[3]).all()


def test_l9_equals_the_printed_table_and_its_relations():
    # Taguchi's printed L9: column 3 = c1 + c2, column 4 = 2·c1 + c2 (mod 3), e.g. run 4 = 2123.
    c = orthogonal_array("L9")
    assert (c == printed("1111 1222 1333 2123 2231 2312 3132 3213 3321")).all()
    assert (c[:, 2] == (c[:, 0] + c[:, 1]) % 3).all()
    assert (c[:, 3] == (2 * c[:, 0] + c[:, 1]) % 3).all()


def test_l27_relations():
    # Basic columns 1, 2, 5 (A, B, C); the others are A+B, 2A+B, A+C, 2A+C, B+C, A+B+C,
    # 2A+B+C, 2B+C, A+2B+C, 2A+2B+C (mod 3) in the printed order.
    t = orthogonal_array("L27")
    a, b, c = t[:, 0], t[:, 1], t[:, 4]
    coefficients = [
        (1, 0, 0), (0, 1, 0), (1, 1, 0), (2, 1, 0), (0, 0, 1), (1, 0, 1), (2, 0, 1),
        (0, 1, 1), (1, 1, 1), (2, 1, 1), (0, 2, 1), (1, 2, 1), (2, 2, 1),
    ]  # fmt: skip
    for j, (x, y, z) in enumerate(coefficients):
        assert (t[:, j] == (x * a + y * b + z * c) % 3).all(), j + 1
    assert (t[9] == printed("2123123123123")[0]).all()  # run 10 as printed


def test_l25_relations():
    t = orthogonal_array("L25")
    for j in range(1, 5):
        assert (t[:, j + 1] == (j * t[:, 0] + t[:, 1]) % 5).all(), j + 2


def test_l16_four_level_relations_and_printed_rows():
    # Column 3 = c1 + c2, 4 = a·c1 + c2, 5 = a^2·c1 + c2 over GF(4).
    t = orthogonal_array("L16(4^5)")
    for j, m in zip((2, 3, 4), (1, 2, 3), strict=True):
        assert (t[:, j] == GF4_MUL[m, t[:, 0]] ^ t[:, 1]).all(), j + 1
    assert (t[4:8] == printed("21234 22143 23412 24321")).all()


def test_mixed_arrays_keep_their_printed_structure():
    # L18 runs 4 and 10 as printed (Phadke 1989, appendix C; Minitab catalogue).
    l18 = orthogonal_array("L18")
    assert (l18[[3, 9]] == printed("12112233 21133221")).all()
    # L36(2^11 3^12): the 2-level part is L12 with each run used three times.
    assert (orthogonal_array("L36")[:, :11] == np.repeat(orthogonal_array("L12"), 3, 0)).all()
    # L54: the first eight columns are L18 with each run used three times.
    assert (orthogonal_array("L54")[:, :8] == np.repeat(l18, 3, axis=0)).all()
    # L12 is the Plackett-Burman array: its ±1 form has orthogonal columns.
    x = 2 * orthogonal_array("L12") - 1
    assert (x.T @ x == 12 * np.eye(11)).all()


@pytest.mark.parametrize(
    ("name", "shape"),
    [
        ("L9", (9, 4)),
        ("l18", (18, 8)),
        ("L16", (16, 15)),
        ("L16(4^5)", (16, 5)),
        ("L32", (32, 31)),
        ("L32(2^1 4^9)", (32, 10)),
        ("L36", (36, 23)),
        ("L36(2^3 3^13)", (36, 16)),
        ("L36(2^3 x 3^13)", (36, 16)),
        ("L36(2^3 \u00d7 3^13)", (36, 16)),
        ("L54(2^1 3^25)", (54, 26)),
    ],
)
def test_names_are_resolved(name, shape):
    assert orthogonal_array(name).shape == shape


def test_unknown_name_lists_the_catalogue():
    with pytest.raises(ValueError, match="unknown orthogonal array") as err:
        orthogonal_array("L7")
    for name in NAMES:
        assert name in str(err.value)


def test_returned_array_is_a_fresh_copy():
    first = orthogonal_array("L9")
    first[:] = 7
    assert orthogonal_array("L9").max() == 2


def test_interaction_columns_match_the_printed_triangular_tables():
    # Printed tables are 1-based: L8 1x2 → 3, 1x4 → 5, 2x4 → 6, 3x4 → 7, 3x5 → 6;
    # L27 1x2 → 3, 4; 1x5 → 6, 7; 2x5 → 8, 11; 3x5 → 9, 13; 4x5 → 10, 12.
    def one_based(name, a, b):
        return tuple(c + 1 for c in interaction_columns(name, a - 1, b - 1))

    assert one_based("L8", 1, 2) == (3,)
    assert one_based("L8", 1, 4) == (5,)
    assert one_based("L8", 2, 4) == (6,)
    assert one_based("L8", 3, 4) == (7,)
    assert one_based("L8", 3, 5) == (6,)
    assert one_based("L16", 5, 10) == (15,)
    assert one_based("L27", 1, 2) == (3, 4)
    assert one_based("L27", 1, 5) == (6, 7)
    assert one_based("L27", 2, 5) == (8, 11)
    assert one_based("L27", 3, 5) == (9, 13)
    assert one_based("L27", 4, 5) == (10, 12)


@pytest.mark.parametrize("name", ["L8", "L16", "L9", "L27", "L16(4^5)"])
def test_interaction_columns_carry_the_interaction(name):
    # For each column pair (i, j): the interaction columns are other columns, each a function
    # of (column i, column j); for 2-level arrays the column is the XOR.
    table = orthogonal_array(name)
    s = int(table.max()) + 1
    for i, j in itertools.combinations(range(table.shape[1]), 2):
        cols = interaction_columns(name, i, j)
        assert len(cols) == s - 1
        assert not {i, j} & set(cols)
        for w in cols:
            assert len(set(zip(table[:, i], table[:, j], table[:, w], strict=True))) == s * s
        if s == 2:
            assert (table[:, cols[0]] == table[:, i] ^ table[:, j]).all()


def test_interaction_columns_refuse_tabulated_arrays_and_bad_columns():
    with pytest.raises(ValueError, match="no interaction table"):
        interaction_columns("L18", 1, 2)
    with pytest.raises(ValueError, match="not in L8"):
        interaction_columns("L8", 0, 7)
    with pytest.raises(ValueError, match="two different columns"):
        interaction_columns("L8", 2, 2)


@pytest.mark.parametrize(
    ("levels", "interactions", "expected"),
    [
        ([2, 2, 2], 0, "L4(2^3)"),
        ([2, 2, 2, 2], 0, "L8(2^7)"),
        ([3, 3, 3, 3], 0, "L9(3^4)"),
        ([3, 3, 3], 0, "L9(3^4)"),
        ([2, 3, 3, 3, 3, 3, 3, 3], 0, "L18(2^1 3^7)"),
        ([2, 3, 3], 0, "L18(2^1 3^7)"),  # native L18 beats a dummy level in L9
        ([2] * 8, 0, "L12(2^11)"),
        ([4] * 5, 0, "L16(4^5)"),
        ([5, 5, 5], 0, "L25(5^6)"),
        ([3] * 5, 0, "L18(2^1 3^7)"),
        ([3] * 8, 0, "L27(3^13)"),
        ([2] * 12, 0, "L16(2^15)"),
        ([2] + [4] * 9, 0, "L32(2^1 4^9)"),
        ([2] * 2 + [3] * 8, 0, "L36(2^11 3^12)"),
        ([2] * 3 + [3] * 13, 0, "L36(2^3 3^13)"),
        ([2] + [3] * 20, 0, "L54(2^1 3^25)"),
        ([2, 2, 4, 4, 4, 4], 0, "L25(5^6)"),  # only with dummy levels
        ([2, 2] + [4] * 7, 0, "L32(2^1 4^9)"),  # only with a dummy level
        ([2, 5, 5], 0, "L25(5^6)"),  # only with a dummy level
        ([2, 2, 2, 2], 3, "L8(2^7)"),
        ([2] * 5, 3, "L16(2^15)"),
        ([3, 3], 1, "L9(3^4)"),
        ([3, 3, 3], 1, "L27(3^13)"),
    ],
)
def test_smallest_array_for(levels, interactions, expected):
    assert smallest_array_for(levels, interactions).name == expected


@pytest.mark.parametrize(
    ("levels", "interactions", "message"),
    [
        ([6, 6], 0, "no catalogue orthogonal array"),
        ([2] * 40, 0, "no catalogue orthogonal array"),
        ([1, 2], 0, "at least 2 levels"),
        ([], 0, "at least 2 levels"),
        ([2, 3], 1, "one level count"),
        ([2, 2], -1, ">= 0"),
    ],
)
def test_smallest_array_for_refuses(levels, interactions, message):
    with pytest.raises(ValueError, match=message):
        smallest_array_for(levels, interactions)


def hosts(info, levels) -> bool:
    """Brute force: largest factors into largest columns, each column at least as large."""
    columns = sorted(info.levels, reverse=True)
    factors = sorted(levels, reverse=True)
    return len(factors) <= len(columns) and all(
        c >= f for c, f in zip(columns, factors, strict=False)
    )


def hosts_natively(info, levels) -> bool:
    spare = list(info.levels)
    for f in levels:
        if f not in spare:
            return False
        spare.remove(f)
    return True


@given(st.lists(st.sampled_from([2, 3, 4, 5]), min_size=1, max_size=12))
def test_chosen_array_is_the_smallest_that_hosts_every_factor(levels):
    # Law: the choice hosts every factor (natively when any array can), no smaller array
    # hosts them natively, and a refusal means no array hosts them at all.
    try:
        info = smallest_array_for(levels)
    except ValueError:
        assert not any(hosts(other, levels) for other in CATALOGUE)
        return
    assert hosts(info, levels)
    if any(hosts_natively(other, levels) for other in CATALOGUE):
        assert hosts_natively(info, levels)
    assert not any(hosts_natively(o, levels) for o in CATALOGUE if o.runs < info.runs)
