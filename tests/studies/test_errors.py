"""What the command line does with an error: the user's gets one line and its exit code, the
engine's (or a scene's) own bug its traceback (issue #29 item 4)."""

from __future__ import annotations

from pathlib import Path

import pytest

from studies.cli import BUG, main
from studies.common.errors import EXIT_STUDY_ERROR
from studies.scenes import get_scene

STUDY = """
name = "tiny_cam"
scene = "cam"
responses = ["max_jerk"]
design = "full_factorial"
[factors.seg2_width]
levels = [7.0, 9.0]
"""


def _write_parms(state):  # a scene's bug: "params" spelled "parms" (the state has slots)
    state.parms = state.params


def _read_unfilled(state):  # a scene's bug: reading the loads, which this request never ran
    return state.load


@pytest.mark.parametrize(("bug", "field"), [(_write_parms, "parms"), (_read_unfilled, "load")])
def test_a_mistyped_field_inside_a_scene_is_a_traceback_not_exit_2(
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
    bug,
    field: str,
) -> None:
    study = tmp_path / "tiny_cam.toml"
    study.write_text(STUDY, encoding="utf-8")
    scene = type(get_scene("cam"))
    finish = scene.finish

    def buggy(self, state):
        bug(state)
        return finish(self, state)

    monkeypatch.setattr(scene, "finish", buggy)
    with pytest.raises(AttributeError, match=field):
        main(["run", str(study), "--outputs", str(tmp_path / "out"), "--no-progress"])
    assert BUG in capsys.readouterr().err


def test_the_users_mistake_is_one_line_and_exit_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # the same kind of mistake made by the user: a run id no run has
    assert main(["show", "no-such-run", "--outputs", str(tmp_path)]) == EXIT_STUDY_ERROR
    err = capsys.readouterr().err
    assert err.startswith("error: ")
    assert "no-such-run" in err
    assert "Traceback" not in err
    assert BUG not in err
