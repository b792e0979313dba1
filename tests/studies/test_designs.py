"""Full factorial, one-factor sweep and orthogonal-array assignment."""

from __future__ import annotations

import itertools
import json
import re

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from studies.define import designs


def test_full_factorial_is_every_combination() -> None:
    d = designs.full_factorial({"a": 2, "b": 3, "c": 4})
    rows = set(zip(d.levels["a"], d.levels["b"], d.levels["c"], strict=True))
    assert rows == set(itertools.product(range(2), range(3), range(4)))
    assert d.runs == 24


def test_sweep_moves_one_factor_at_a_time() -> None:
    d = designs.sweep({"a": 3, "b": 5}, base={"a": 1, "b": 2})
    assert d.runs == 1 + 2 + 4
    moved = (np.c_[d.levels["a"] != 1, d.levels["b"] != 2]).sum(axis=1)
    assert moved[0] == 0
    assert np.all(moved[1:] == 1)
    assert list(d.labels["swept_factor"]) == ["base", "a", "a", "b", "b", "b", "b"]


def test_l9_assignment_keeps_empty_column_as_error() -> None:
    d = designs.orthogonal("L9", {"A": 3, "B": 3, "C": 3}, {"A": 1, "B": 2, "C": 3}, ("D",))
    assert d.error_columns == ("D",)
    table = designs.orthogonal_array("L9")
    for i, name in enumerate(["A", "B", "C", "D"]):
        np.testing.assert_array_equal(d.levels[name], table[:, i])


def test_columns_are_taken_in_order_when_not_given() -> None:
    d = designs.orthogonal("L9", {"A": 3, "B": 3}, {"A": None, "B": 3}, ())
    table = designs.orthogonal_array("L9")
    np.testing.assert_array_equal(d.levels["A"], table[:, 0])
    np.testing.assert_array_equal(d.levels["B"], table[:, 2])
    assert d.error_columns == ("e2", "e4")


def test_auto_picks_l9_for_four_three_level_factors() -> None:
    d = designs.orthogonal("auto", dict.fromkeys("ABCD", 3), dict.fromkeys("ABCD"), ())
    assert d.name.startswith("L9")


@pytest.mark.parametrize(
    ("counts", "columns", "words"),
    [
        ({"A": 4}, {"A": 1}, "has 4 levels but column 1"),
        ({"A": 3, "B": 3}, {"A": 2, "B": 2}, "both assigned to column 2"),
        ({"A": 3}, {"A": 7}, "column 7 does not exist"),
        (dict.fromkeys("ABCDE", 3), dict.fromkeys("ABCDE"), "no free column"),
    ],
)
def test_misfits_are_reported(counts, columns, words) -> None:
    with pytest.raises(designs.DesignError, match=words):
        designs.orthogonal("L9", counts, columns, ())


# --- auto choice, interaction columns and dummy levels ---------------------------------------
# Expected columns come from Taguchi's printed triangular tables (Phadke 1989, appendix C;
# 1-based): L8 1x2 → 3, 1x4 → 5; L9 1x2 → 3, 4; L27 1x2 → 3, 4 and 1x5 → 6, 7. The interaction
# column contents are the closed forms of the GF(q) construction: a 2-level interaction column
# is A XOR B; L9/L27 columns 3 and 4 are (c1 + c2) mod 3 and (2·c1 + c2) mod 3.


def test_auto_picks_l4_for_three_two_level_factors() -> None:
    d = designs.orthogonal("auto", dict.fromkeys("ABC", 2), dict.fromkeys("ABC"), ())
    assert d.name == "L4(2^3)"
    assert d.error_columns == ()


@pytest.mark.parametrize("n3", range(1, 8))
def test_auto_picks_l18_for_one_two_level_and_up_to_seven_three_level(n3) -> None:
    counts = {"A": 2} | {f"B{i}": 3 for i in range(n3)}
    d = designs.orthogonal("auto", counts, dict.fromkeys(counts), ())
    assert d.name == "L18(2^1 3^7)"
    assert d.columns["A"] == 1  # the one 2-level column of L18
    assert len(d.error_columns) == 7 - n3


def test_auto_with_interactions_picks_l9_then_l27() -> None:
    d = designs.orthogonal("auto", dict.fromkeys("AB", 3), dict.fromkeys("AB"), (), [("A", "B")])
    assert d.name == "L9(3^4)"
    assert d.columns == {"A": 1, "B": 2, "A_x_B": 3, "A_x_B_2": 4}
    counts = dict.fromkeys("ABCD", 3)
    d = designs.orthogonal("auto", counts, dict.fromkeys(counts), (), [("A", "B"), ("A", "C")])
    assert d.name == "L27(3^13)"
    assert d.interactions == {
        "A_x_B": ("A", "B"), "A_x_B_2": ("A", "B"), "A_x_C": ("A", "C"), "A_x_C_2": ("A", "C"),
    }  # fmt: skip
    assert [d.columns[n] for n in ["A", "B", "A_x_B", "A_x_B_2", "C", "A_x_C", "A_x_C_2"]] == [
        1, 2, 3, 4, 5, 6, 7,
    ]  # fmt: skip
    assert d.columns["D"] == 8
    assert d.error_columns == ("e9", "e10", "e11", "e12", "e13")
    a, b, c = d.levels["A"], d.levels["B"], d.levels["C"]
    np.testing.assert_array_equal(d.levels["A_x_B"], (a + b) % 3)
    np.testing.assert_array_equal(d.levels["A_x_B_2"], (2 * a + b) % 3)
    # x5 + x1 and x5 + 2·x1 (Taguchi's order after basic column 5 = x3)
    np.testing.assert_array_equal(d.levels["A_x_C"], (a + c) % 3)
    np.testing.assert_array_equal(d.levels["A_x_C_2"], (2 * a + c) % 3)


def test_l8_interaction_columns_follow_the_triangular_table() -> None:
    d = designs.orthogonal("L8", dict.fromkeys("ABC", 2), dict.fromkeys("ABC"), (),
                           [("A", "B"), ("A", "C")])  # fmt: skip
    assert d.columns == {"A": 1, "B": 2, "A_x_B": 3, "C": 4, "A_x_C": 5, "e6": 6, "e7": 7}
    assert d.error_columns == ("e6", "e7")
    np.testing.assert_array_equal(d.levels["A_x_B"], d.levels["A"] ^ d.levels["B"])
    np.testing.assert_array_equal(d.levels["A_x_C"], d.levels["A"] ^ d.levels["C"])
    assert list(d.levels)[:3] == ["A", "B", "C"]  # factors first, in the study's order


def test_given_columns_are_kept_and_interactions_placed_around_them() -> None:
    # A in 1, B in 4 → A x B in 1 XOR 4 = 5; C takes the first free column, 2.
    d = designs.orthogonal("L8", dict.fromkeys("ABC", 2), {"A": 1, "B": 4, "C": None}, (),
                           [("A", "B")])  # fmt: skip
    assert d.columns["A_x_B"] == 5
    assert d.columns["C"] == 2


@settings(max_examples=25, deadline=None)
@given(
    st.integers(2, 5).flatmap(
        lambda n: st.tuples(
            st.just(n),
            st.lists(st.sampled_from(list(itertools.combinations(range(n), 2))),
                     max_size=3, unique=True),
        )
    )
)  # fmt: skip
def test_two_level_interaction_columns_are_xor_and_never_shared(case) -> None:
    # Law (GF(2) construction): wherever the search places the factors, each interaction
    # column is the XOR of its two factor columns and no array column serves two purposes.
    n, picks = case
    names = "ABCDE"[:n]
    pairs = [(names[i], names[j]) for i, j in picks]
    d = designs.orthogonal("auto", dict.fromkeys(names, 2), dict.fromkeys(names), (), pairs)
    assert sorted(d.columns.values()) == list(range(1, len(d.columns) + 1))
    for column, (a, b) in d.interactions.items():
        np.testing.assert_array_equal(d.levels[column], d.levels[a] ^ d.levels[b])
    assert set(d.interactions.values()) == set(pairs)


def test_dummy_level_for_a_two_level_factor_in_a_three_level_array() -> None:
    # Dummy-level rule: column levels 1, 2, 3 → factor levels 1, 2, 1 (level 3 repeats level 1).
    d = designs.orthogonal("L9", {"A": 2, "B": 3, "C": 3}, dict.fromkeys("ABC"), ())
    column = designs.orthogonal_array("L9")[:, 0]
    np.testing.assert_array_equal(d.levels["A"], np.array([0, 1, 0])[column])
    assert np.bincount(d.levels["A"]).tolist() == [6, 3]
    for other in ["B", "C"]:  # proportional balance: at every level of B, A is 1, 2, 1
        for lv in range(3):
            assert np.bincount(d.levels["A"][d.levels[other] == lv]).tolist() == [2, 1]
    assert d.columns == {"A": 1, "B": 2, "C": 3, "e4": 4}


def test_dummy_factor_beside_interactions() -> None:
    # A, B, A x B fill L9; the 2-level C then needs L27 and takes a 3-level column as dummy.
    counts = {"A": 3, "B": 3, "C": 2}
    d = designs.orthogonal("auto", counts, dict.fromkeys(counts), (), [("A", "B")])
    assert d.name == "L27(3^13)"
    assert d.columns["C"] == 5
    assert np.bincount(d.levels["C"]).tolist() == [18, 9]


@pytest.mark.parametrize(
    ("array", "counts", "columns", "pairs", "words"),
    [
        ("L8", dict.fromkeys("ABC", 2), {"A": 1, "B": 2, "C": 3}, [("A", "B")],
         "interaction A x B falls in column 3 of L8.*, which factor C takes"),
        ("L8", dict.fromkeys("ABCD", 2), dict.fromkeys("ABCD"), [("A", "B"), ("C", "D")],
         "no assignment of the factors to columns of L8"),
        ("L18", dict.fromkeys("AB", 3), dict.fromkeys("AB"), [("A", "B")],
         "L18.* has no interaction table"),
        ("L27", {"A": 2, "B": 3}, dict.fromkeys("AB"), [("A", "B")],
         "factor A has 2 levels but its interactions in L27"),
        ("L9", dict.fromkeys("AB", 3), dict.fromkeys("AB"), [("A", "Z")], "Z is not a factor"),
        ("L9", dict.fromkeys("AB", 3), dict.fromkeys("AB"), [("A", "A")], "two different"),
        ("L9", dict.fromkeys("AB", 3), dict.fromkeys("AB"), [("A", "B"), ("B", "A")],
         "requested twice"),
        ("auto", {"A": 2, "B": 3}, dict.fromkeys("AB"), [("A", "B")], "one level count"),
        ("auto", dict.fromkeys("ABCD", 3), dict.fromkeys("ABCD"), [("A", "B"), ("C", "D")],
         "no catalogue array with an interaction table fits"),
    ],
)  # fmt: skip
def test_interaction_misfits_are_reported(array, counts, columns, pairs, words) -> None:
    with pytest.raises(designs.DesignError, match=words):
        designs.orthogonal(array, counts, columns, (), pairs)


INTERACTION_STUDY = """
name = "with_interaction"
scene = "cam"
responses = ["max_jerk"]
[design]
type = "{design}"
interactions = {interactions}
[factors.seg2_width]
levels = [7.0, 9.0, 11.0]
units = "deg"
[factors.seg6_amplitude]
levels = [3.5, 4.5, 5.5]
[factors.seg2_amplitude]
levels = [12.0, 14.0, 16.0]
"""


def test_study_interactions_reach_the_design_and_the_dataset() -> None:
    from studies.define.plan import plan_text
    from studies.run.results import build_dataset
    from studies.run.runner import Evaluation

    text = INTERACTION_STUDY.format(design="auto",
                                    interactions='[["seg2_width", "seg2_amplitude"]]')  # fmt: skip
    plan = plan_text(text)
    assert plan.definition.interactions == (("seg2_width", "seg2_amplitude"),)
    # 3 factors + 2 interaction columns > 4 columns of L9 → L27. The interacting factors are
    # placed first (columns 1 and 2, interaction 1 x 2 → 3, 4 in the printed triangular
    # table); seg6_amplitude takes the next free column, 5.
    design = plan.design
    assert design.name == "L27(3^13)"
    assert [design.columns[f] for f in ["seg2_width", "seg2_amplitude", "seg6_amplitude"]] == [
        1, 2, 5,
    ]  # fmt: skip
    assert design.columns["seg2_width_x_seg2_amplitude"] == 3
    assert design.columns["seg2_width_x_seg2_amplitude_2"] == 4
    jerk = np.arange(float(design.runs))
    ds = build_dataset(plan, Evaluation({"max_jerk": jerk}, {}), {})
    assert json.loads(ds.attrs["interaction_columns"]) == {
        "seg2_width_x_seg2_amplitude": ["seg2_width", "seg2_amplitude"],
        "seg2_width_x_seg2_amplitude_2": ["seg2_width", "seg2_amplitude"],
    }
    assert json.loads(ds.attrs["array_columns"]) == design.columns
    a, c = ds["seg2_width_level"].values, ds["seg2_amplitude_level"].values
    np.testing.assert_array_equal(ds["seg2_width_x_seg2_amplitude_level"], (a + c) % 3)


@pytest.mark.parametrize(
    ("design", "interactions", "words"),
    [
        ("L9", '[["seg2_width", "seg2_widht"]]', "not a factor (did you mean 'seg2_width'?)"),
        ("full_factorial", '[["seg2_width", "seg2_amplitude"]]', "only apply to orthogonal"),
        ("L9", '["seg2_width"]', "must be a list of factor pairs"),
        ("L9", '[["seg2_width", "seg2_amplitude"]]', "no free column left in L9"),
    ],
)
def test_study_interaction_mistakes_are_reported(design, interactions, words) -> None:
    from studies.define.definition import StudyFileError
    from studies.define.plan import plan_text

    with pytest.raises(StudyFileError, match=re.escape(words)):
        plan_text(INTERACTION_STUDY.format(design=design, interactions=interactions))
