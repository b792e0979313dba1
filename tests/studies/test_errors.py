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


def test_a_mistyped_key_inside_a_scene_is_a_traceback_not_exit_2(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    study = tmp_path / "tiny_cam.toml"
    study.write_text(STUDY, encoding="utf-8")
    scene = type(get_scene("cam"))
    stages = scene.run_stages

    def mistyped(self, ctx, responses, curves):  # a scene's bug: "params" spelled "parms"
        stages(self, ctx, responses, curves)
        return ctx["parms"]

    monkeypatch.setattr(scene, "run_stages", mistyped)
    with pytest.raises(KeyError, match="parms"):
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
