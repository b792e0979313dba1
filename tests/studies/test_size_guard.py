"""A design too large for the machine is refused at planning, from its level counts alone,
with the size and the memory and time estimates; a 10⁷-point study passes."""

from __future__ import annotations

import time
import tracemalloc

import pytest

from studies.define import plan as planning
from studies.define.definition import StudyFileError
from studies.define.plan import full_factorial_size_problem, plan_text

FACTORS = ("cam_speed", "spring_preload", "spring_rate", "drive_stiffness")
GB = 1e9


def huge_study(levels: int) -> str:
    values = ", ".join(str(1000.0 + i) for i in range(levels))
    text = 'name = "huge"\nscene = "valve"\nresponses = ["max_lift"]\n'
    return text + "".join(f"[factors.{f}]\nlevels = [{values}]\n" for f in FACTORS)


def test_a_trillion_point_design_is_refused_before_anything_is_allocated(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.setattr(planning, "available_memory", lambda: 24 * GB)
    text = huge_study(1000)  # four factors of 1000 levels: 10¹² points
    tracemalloc.start()
    start = time.perf_counter()
    with pytest.raises(StudyFileError) as refused:
        plan_text(text)
    seconds = time.perf_counter() - start
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    assert peak < 50e6  # nothing the size of the design was allocated
    assert seconds < 5  # about 0.05 s here; generous for a loaded machine under tracemalloc
    message = str(refused.value)
    assert "= 1e+12 design points" in message
    assert "GB to plan, run and analyse" in message
    # 10¹² points x 1e-5 s per point of the valve's fixed-step dynamics = 1e7 s = 115.7 days
    assert "about 116 days to compute (1e-05 s per point)" in message
    assert "24 GB of memory available" in message
    assert "orthogonal array" in message
    assert "ENGINE_STUDIES_MAX_POINTS" in message


def test_a_ten_million_point_design_passes(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(planning, "available_memory", lambda: 24 * GB)
    counts = dict(zip(FACTORS, (100, 40, 50, 50), strict=True))
    assert full_factorial_size_problem(counts, responses=9) == ""
    # the estimate (76 bytes per point here) scales with the machine: 0.5 GB is too little
    monkeypatch.setattr(planning, "available_memory", lambda: GB // 2)
    assert "= 1e+07 design points" in full_factorial_size_problem(counts, responses=9)


def test_the_limit_can_be_raised_or_lowered(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("ENGINE_STUDIES_MAX_POINTS", "1e3")
    counts = dict(zip(FACTORS, (10, 10, 10, 2), strict=True))
    assert "ENGINE_STUDIES_MAX_POINTS=1e3" in full_factorial_size_problem(counts, responses=1)
    monkeypatch.setenv("ENGINE_STUDIES_MAX_POINTS", "1e13")
    monkeypatch.setattr(planning, "available_memory", lambda: 1 * GB)
    assert full_factorial_size_problem({"a": 10**6, "b": 10**6}, responses=1) == ""


def test_a_limit_set_by_the_user_is_stated_without_the_memory_it_does_not_depend_on(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """The quick and the full check print the same refusal: with the limit set by the user, the
    machine's free memory (which changes between two calls) is not part of the message."""
    monkeypatch.setenv("ENGINE_STUDIES_MAX_POINTS", "1e3")
    counts = dict(zip(FACTORS, (10, 10, 10, 2), strict=True))
    answers = set()
    for free in (1 * GB, 3 * GB):
        monkeypatch.setattr(planning, "available_memory", lambda free=free: free)
        answers.add(full_factorial_size_problem(counts, responses=1))
    (message,) = answers
    assert "the limit is 1000 points (ENGINE_STUDIES_MAX_POINTS=1e3)" in message
    assert "memory available" not in message


def test_a_bad_limit_names_the_variable(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("ENGINE_STUDIES_MAX_POINTS", "lots")
    with pytest.raises(ValueError, match="ENGINE_STUDIES_MAX_POINTS='lots' must be a number"):
        full_factorial_size_problem({"a": 2}, responses=1)


@pytest.mark.parametrize(
    ("seconds", "shown"),
    [(59.0, "59 s"), (90.0, "1.5 min"), (7200.0, "2 h"), (3 * 86400.0, "3 days")],
)
def test_durations_are_shown_in_the_largest_unit_reached(seconds: float, shown: str) -> None:
    assert planning.duration(seconds) == shown


@pytest.mark.parametrize(
    ("extra", "shown"),
    [
        ("", "(1e-05 s per point)"),
        ('responses = ["jump_speed"]\n', "(0.001 s per point)"),
        ('[settings]\nintegrator = "dopri"\n', "(0.001 s per point)"),
        ("[settings]\ntolerance = 1e-3\n", "(0.01 s per point)"),
    ],
)
def test_the_time_estimate_follows_what_a_point_computes(
    extra: str, shown: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    # The valve's costs per design point (measured, see ValveScene): fixed-step dynamics
    # 2.8 µs on 2 cores, the jump-speed search 0.29 ms, dopri and the tolerance ladder more.
    monkeypatch.setattr(planning, "available_memory", lambda: 24 * GB)
    text = huge_study(1000)
    if extra.startswith("responses"):
        text = text.replace('responses = ["max_lift"]\n', extra)
    else:
        text = text.replace("[factors.", extra + "[factors.", 1)
    with pytest.raises(StudyFileError) as refused:
        plan_text(text)
    assert shown in str(refused.value)
