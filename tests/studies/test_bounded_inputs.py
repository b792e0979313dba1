"""Inputs that would read forever, recurse or overflow are refused in one line (issue 25,
"Unbounded work"): study files and tables must be regular files under a size cap (``/dev/zero``,
a FIFO, a folder, a file past the cap), nesting is bounded, a byte-order mark is accepted, level
lists are checked in linear time, and out-of-range command values give a message, not an
``OverflowError``. ``check`` times are printed for the record, never asserted."""

from __future__ import annotations

import os
import time
from pathlib import Path

import pytest

from studies.cli import main
from studies.common.bounded_files import STUDY_FILE_BYTES
from studies.define.definition import MAX_NESTING, parse_study
from studies.define.plan import plan_text

HEAD = 'name = "bounded"\nscene = "cam"\nresponses = ["max_jerk"]\n'
SPEED = "[factors.cam_speed]\nlevels = [1000.0, 1300.0]\n"


def one_line(capsys: pytest.CaptureFixture[str], code: int, expected: int = 2) -> str:
    """The single problem (or error) line of a command that exited ``expected``."""
    assert code == expected
    err = capsys.readouterr().err
    assert "Traceback" not in err
    problems = [line.removeprefix("  - ") for line in err.splitlines() if line.startswith("  - ")]
    if problems:
        (problem,) = problems
        return problem
    (line,) = err.strip().splitlines()
    return line.removeprefix("error: ")


def timed_check(path: Path | str) -> tuple[int, float]:
    start = time.perf_counter()
    code = main(["check", str(path)])
    return code, time.perf_counter() - start


@pytest.mark.parametrize("command", ["check", "run"])
def test_a_character_device_is_not_a_study_file(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], command: str
) -> None:
    extra = ["--outputs", str(tmp_path / "out"), "--no-progress"] if command == "run" else []
    code = main([command, "/dev/zero", *extra])
    assert one_line(capsys, code) == (
        "study file /dev/zero is a character device, not a regular file"
    )
    assert not (tmp_path / "out").exists()


def test_a_fifo_is_refused_without_waiting_for_a_writer(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    fifo = tmp_path / "study.toml"
    os.mkfifo(fifo)
    code, seconds = timed_check(fifo)
    assert one_line(capsys, code) == f"study file {fifo} is a FIFO (named pipe), not a regular file"
    print(f"check of a FIFO answered in {seconds:.3f} s")


def test_a_folder_is_not_a_study_file(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    code = main(["check", str(tmp_path)])
    assert one_line(capsys, code) == f"study file {tmp_path} is a folder, not a regular file"


def test_two_factors_of_a_million_levels_are_refused_at_once(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The issue's reproduction (no answer in 180 s before): the file is ~14 MB."""
    levels = "[" + ", ".join(str(i + 1) for i in range(10**6)) + "]"
    study = tmp_path / "huge.toml"
    study.write_text(
        f"{HEAD}[factors.cam_speed]\nlevels = {levels}\n[factors.base_radius]\nlevels = {levels}\n"
    )
    size = study.stat().st_size
    code, seconds = timed_check(study)
    assert one_line(capsys, code) == (
        f"study file {study} has {size} bytes: at most {STUDY_FILE_BYTES} bytes are read"
    )
    print(f"check of two factors of 10^6 levels ({size} bytes) answered in {seconds:.3f} s")


def test_the_same_text_through_the_api_is_refused_before_parsing() -> None:
    levels = "[" + ", ".join(str(i + 1) for i in range(10**5)) + "]"
    text = f"{HEAD}[factors.cam_speed]\nlevels = {levels}\n"
    definition, problems = parse_study(text)
    assert definition is None
    assert problems == [
        f"has {len(text)} characters: a study file holds at most {STUDY_FILE_BYTES}"
    ]


def test_duplicate_levels_in_the_largest_file_under_the_cap_are_found_in_linear_time(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Before: ``levels.count(v)`` for every level, quadratic (10^6 levels: hours)."""
    count = (STUDY_FILE_BYTES - 200) // 6  # "1000, " is 6 characters
    study = tmp_path / "dups.toml"
    study.write_text(f"{HEAD}[factors.cam_speed]\nlevels = [{', '.join(['1000'] * count)}]\n")
    code, seconds = timed_check(study)
    assert one_line(capsys, code) == "factor cam_speed has duplicate levels: 1000"
    print(f"check of {count} equal levels answered in {seconds:.3f} s")


def test_refused_levels_are_listed_three_times_then_counted(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    study = tmp_path / "range.toml"
    levels = ", ".join(str(40000 + i) for i in range(5000))  # above the 30 000 rpm limit
    study.write_text(f"{HEAD}[factors.cam_speed]\nlevels = [{levels}]\n")
    assert main(["check", str(study)]) == 2
    err = capsys.readouterr().err
    problems = [line for line in err.splitlines() if line.startswith("  - ")]
    assert len(problems) == 4
    assert problems[0].startswith("  - factor cam_speed: cam_speed = 40000 rpm is physically")
    assert problems[3] == "  - factor cam_speed: 4997 more of its levels are refused likewise"


@pytest.mark.parametrize(
    ("body", "where"),
    [
        (f"{SPEED}[parameters]\nbase_radius = " + "[" * 5000 + "]" * 5000 + "\n", "tomllib"),
        ("[parameters]\n" + ".".join(["a"] * 3000) + f" = 1\n{SPEED}", "parameters.a.a"),
        (SPEED.replace("[1000.0, 1300.0]", "[" * 40 + "1000.0" + "]" * 40), "factors.cam_speed"),
        ("[design]\ntype = " + "{a = " * 100 + "1" + "}" * 100 + f"\n{SPEED}", "design.type.a"),
    ],
    ids=["levels-5000-deep", "dotted-key-3000-deep", "levels-40-deep", "inline-tables-100"],
)
@pytest.mark.parametrize("command", ["check", "run"])
def test_deep_nesting_is_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], body: str, where: str, command: str
) -> None:
    study = tmp_path / "deep.toml"
    study.write_text(HEAD + body)
    extra = ["--outputs", str(tmp_path / "out"), "--no-progress"] if command == "run" else []
    problem = one_line(capsys, main([command, str(study), *extra]))
    if where == "tomllib":
        assert problem == (
            f"nests arrays or inline tables too deeply to read (at most {MAX_NESTING})"
        )
    else:
        assert problem.startswith(where)
        assert problem.endswith(
            f"nests arrays or tables more than {MAX_NESTING} deep: a study file needs at most 4 "
            "(e.g. factors.x.levels = [...])"
        )
        assert len(problem) < 200
    assert not (tmp_path / "out").exists()


def test_a_utf8_byte_order_mark_is_accepted(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    study = tmp_path / "bom.toml"
    study.write_bytes(b"\xef\xbb\xbf" + (HEAD + SPEED).encode())
    assert main(["check", str(study)]) == 0
    assert "bounded: OK — scene cam" in capsys.readouterr().out
    assert plan_text("\ufeff" + HEAD + SPEED).definition.name == "bounded"


def test_a_study_file_that_is_not_utf8_is_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    study = tmp_path / "latin1.toml"
    study.write_bytes((HEAD + SPEED).encode() + b'description = "caf\xe9"\n')
    problem = one_line(capsys, main(["check", str(study)]))
    assert problem.startswith(f"study file {study} is not UTF-8 text (byte ")


@pytest.mark.parametrize("table", ["/dev/zero", "fifo"])
def test_a_lift_table_that_is_not_a_regular_file_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], table: str
) -> None:
    if table == "fifo":
        table = str(tmp_path / "fifo.csv")
        os.mkfifo(table)
    study = tmp_path / "table.toml"
    study.write_text(f'{HEAD}[parameters]\nlaw = "table"\nlift_table = "{table}"\n{SPEED}')
    problem = one_line(capsys, main(["check", str(study)]))
    assert problem == f"design points 0–1: lift_table = {table!r}: no such file"


def test_a_huge_lift_table_is_refused_by_its_cap(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    from studies.scenes.cam import lift_tables

    monkeypatch.setattr(lift_tables, "TABLE_FILE_BYTES", 1000)
    table = tmp_path / "lift.csv"
    table.write_text("".join(f"{-60 + i * 0.01:.2f}, 0.0\n" for i in range(200)))
    study = tmp_path / "table.toml"
    study.write_text(f'{HEAD}[parameters]\nlaw = "table"\nlift_table = "{table}"\n{SPEED}')
    problem = one_line(capsys, main(["check", str(study)]))
    size = table.stat().st_size
    assert problem.endswith(f"lift_table {table} has {size} bytes: at most 1000 bytes are read")


def test_an_unused_lift_table_naming_dev_zero_does_not_hang_a_run(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The cache key hashes every file a study names, read under the same cap."""
    study = tmp_path / "unused.toml"
    study.write_text(f'{HEAD}[parameters]\nlift_table = "/dev/zero"\n{SPEED}')
    outputs = tmp_path / "out"
    assert main(["run", str(study), "--outputs", str(outputs), "--no-progress"]) == 0
    assert "Traceback" not in capsys.readouterr().err


def test_regress_tolerances_from_dev_zero_is_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    code = main(["regress", "a", "b", "--tolerances", "/dev/zero", "--outputs", str(tmp_path)])
    assert one_line(capsys, code) == (
        "--tolerances /dev/zero is a character device, not a regular file"
    )


def test_a_max_points_of_1e400_is_a_message(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    monkeypatch.setenv("ENGINE_STUDIES_MAX_POINTS", "1e400")
    study = tmp_path / "s.toml"
    study.write_text(HEAD + SPEED)
    assert one_line(capsys, main(["check", str(study)])) == (
        "ENGINE_STUDIES_MAX_POINTS='1e400' must be a number of design points, e.g. 5e7"
    )


def test_gc_older_than_beyond_the_calendar_is_a_message(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    code = main(["gc", "--older-than", "99999999999w", "--outputs", str(tmp_path)])
    assert one_line(capsys, code) == (
        "--older-than 99999999999w is more than 1000 years: give a shorter age"
    )
