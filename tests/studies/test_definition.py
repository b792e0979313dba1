"""A malformed study gives one readable message listing every problem, and writes nothing."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from studies.define.definition import StudyFileError
from studies.define.plan import plan_text

GOOD = """
name = "ok"
scene = "cam"
responses = ["max_jerk"]
[design]
type = "L9"
error_columns = ["D"]
[parameters]
base_radius = 20.5
[factors.seg2_width]
levels = [7.0, 9.0, 11.0]
units = "deg"
[factors.seg6_amplitude]
levels = [3.5, 4.5, 5.5]
[factors.seg2_amplitude]
levels = [12.0, 14.0, 16.0]
"""

# (what is wrong, the TOML edit, words the message must contain)
MISTAKES = [
    ("TOML syntax", lambda t: t.replace('type = "L9"', "type = L9"), ["not valid TOML"]),
    ("unknown scene", lambda t: t.replace('"cam"', '"camm"'), ["unknown scene 'camm'", "cam"]),
    (
        "unknown response",
        lambda t: t.replace('"max_jerk"', '"max_jerks"'),
        ["unknown response 'max_jerks'", "did you mean 'max_jerk'"],
    ),
    (
        "unknown factor",
        lambda t: t.replace("factors.seg2_width", "factors.seg2_widht"),
        ["unknown factor 'seg2_widht'", "seg2_width"],
    ),
    (
        "unknown parameter",
        lambda t: t.replace("base_radius", "base_radus"),
        ["unknown parameter 'base_radus'"],
    ),
    (
        "wrong units",
        lambda t: t.replace('units = "deg"', 'units = "mm"'),
        ["units 'mm' measure length", "seg2_width is measured in angle"],
    ),
    (
        "unknown units",
        lambda t: t.replace('units = "deg"', 'units = "degrees"'),
        ["unknown units 'degrees'"],
    ),
    (
        "empty levels",
        lambda t: t.replace("[3.5, 4.5, 5.5]", "[]"),
        ["factor seg6_amplitude has no levels"],
    ),
    (
        "duplicate levels",
        lambda t: t.replace("[12.0, 14.0, 16.0]", "[12.0, 12.0, 16.0]"),
        ["duplicate levels: 12.0"],
    ),
    (
        "levels do not fit the array",
        lambda t: t.replace("[12.0, 14.0, 16.0]", "[12.0, 14.0, 16.0, 18.0]"),
        ["seg2_amplitude", "4 levels"],
    ),
    (
        "negative base radius",
        lambda t: t.replace("base_radius = 20.5", "base_radius = -5.0"),
        ["base_radius = -5 mm is physically impossible", "(0, 500] mm"],
    ),
    ("unknown design", lambda t: t.replace('type = "L9"', 'type = "L7"'), ["unknown design 'L7'"]),
    (
        "fixed and varied",
        lambda t: t.replace("base_radius = 20.5", "base_radius = 20.5\nseg2_width = 9.0"),
        ["seg2_width is both fixed in [parameters] and varied in [factors]"],
    ),
    (
        "string where a number belongs",
        lambda t: t.replace("base_radius = 20.5", 'base_radius = "big"'),
        ["base_radius = 'big' is not a finite number"],
    ),
    (
        "bad choice",
        lambda t: t.replace("[parameters]", '[parameters]\nseg2_shape = "sine"'),
        ["seg2_shape = 'sine' is not allowed", "'sin_full'"],
    ),
    (
        "unknown top-level key",
        lambda t: 'repsonses = ["x"]\n' + t,
        ["unknown top-level key 'repsonses'"],
    ),
    ("missing scene", lambda t: t.replace('scene = "cam"\n', ""), ["missing required key 'scene'"]),
    (
        "pooling an unknown factor",
        lambda t: t.replace(
            'error_columns = ["D"]', 'error_columns = ["D"]\npool = ["seg2_widht"]'
        ),
        ["[design] pool names 'seg2_widht', which is not a factor", "seg2_width"],
    ),
    (
        "pool not a list",
        lambda t: t.replace('error_columns = ["D"]', 'error_columns = ["D"]\npool = "seg2_width"'),
        ["[design] pool = 'seg2_width' must be a list of factor names"],
    ),
    (
        "column twice",
        lambda t: t.replace('units = "deg"', 'units = "deg"\ncolumn = 2').replace(
            "[3.5, 4.5, 5.5]", "[3.5, 4.5, 5.5]\ncolumn = 2"
        ),
        ["both assigned to column 2"],
    ),
    (
        "bad study name",
        lambda t: t.replace('name = "ok"', 'name = "my study/1"'),
        ["may only contain ASCII letters"],
    ),
    (
        "setting out of range",
        lambda t: t + "\n[settings]\nangle_step = 0.0\n",
        ["angle_step = 0 degree is physically impossible"],
    ),
]


def test_good_study_plans() -> None:
    plan = plan_text(GOOD)
    assert plan.runs == 9
    assert plan.design.error_columns == ("D",)


@pytest.mark.parametrize(("what", "edit", "words"), MISTAKES, ids=[m[0] for m in MISTAKES])
def test_mistake_is_reported(what: str, edit, words: list[str]) -> None:
    with pytest.raises(StudyFileError) as info:
        plan_text(edit(GOOD))
    message = str(info.value)
    for w in words:
        assert w in message, f"{what}: {w!r} not in\n{message}"


def test_every_problem_listed_at_once() -> None:
    text = (
        GOOD.replace('"max_jerk"', '"max_jerks"')
        .replace("base_radius = 20.5", "base_radius = -1.0")
        .replace("[12.0, 14.0, 16.0]", "[12.0, 12.0, 16.0]")
        .replace('units = "deg"', 'units = "N"')
    )
    with pytest.raises(StudyFileError) as info:
        plan_text(text)
    assert len(info.value.problems) == 4, info.value.problems


def test_point_check_names_the_design_point() -> None:
    text = GOOD.replace("[parameters]", "[parameters]\nramp_velocity = 0.001")
    with pytest.raises(StudyFileError) as info:
        plan_text(text)
    assert "ramp" in str(info.value)


@pytest.mark.parametrize("index", [0, 3, 9, 10, 17])
def test_cli_prints_message_without_traceback_and_writes_nothing(
    tmp_path: Path, index: int
) -> None:
    study = tmp_path / "bad.toml"
    study.write_text(MISTAKES[index][1](GOOD), encoding="utf-8")
    outputs = tmp_path / "outputs"
    proc = subprocess.run(
        [sys.executable, "-m", "studies", "run", str(study), "--outputs", str(outputs)],
        capture_output=True,
        text=True,
        check=False,
        timeout=300,
    )
    assert proc.returncode == 2
    assert "Traceback" not in proc.stderr
    assert "problem" in proc.stderr
    assert not outputs.exists()


def test_missing_file_is_a_clear_error(tmp_path: Path) -> None:
    from studies.define.plan import plan_study

    with pytest.raises(StudyFileError, match="no such file"):
        plan_study(tmp_path / "nope.toml")
