"""Plugins cannot take the engine down (issue 25, item 6): scene plugins are imported only when a
scene that is not built in is asked for or the scenes are listed; an import that raises
``SystemExit``, ``KeyboardInterrupt`` or any error costs one warning naming the package; two
packages registering one scene name are both refused, both named.

The plugins are fake installed distributions (a ``*.dist-info`` folder with the entry point and
a module beside it) on a temporary ``sys.path`` entry: no pip, no network."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from studies.cli import main
from studies.common.errors import StudyError
from studies.scenes import BUILT_IN, SCENES, get_scene

SCENE_CLASS = """
from studies.scenes import Response, Scene, SceneOutput, Parameter
import numpy as np

class {cls}(Scene):
    name = "{scene}"
    description = "a test plugin"
    parameters = (Parameter("x", "1", 1.0, "x"),)
    responses = (Response("y", "1", "y", ("s",)),)
    stage_order = ("s",)

    def stage_s(self, ctx):
        pass  # never run: these tests only load the plugin

    def evaluate(self, points, settings, responses, curves):
        return SceneOutput({{"y": np.asarray(points["x"], dtype=float)}})
"""
CHECKED = 'name = "plain"\nscene = "cam"\nresponses = ["max_jerk"]\n'
CHECKED += "[factors.cam_speed]\nlevels = [1000.0, 1300.0]\n"


def install(site: Path, package: str, module: str, body: str, scene: str = "") -> None:
    """A fake installed distribution ``package`` whose entry point ``scene`` (default: the
    package name) is ``module:Plugin``, the module's text being ``body``."""
    info = site / f"{package}-0.1.dist-info"
    info.mkdir(parents=True)
    (info / "METADATA").write_text(f"Metadata-Version: 2.1\nName: {package}\nVersion: 0.1\n")
    (info / "entry_points.txt").write_text(
        f"[engine_studies.scenes]\n{scene or package} = {module}:Plugin\n"
    )
    (site / f"{module}.py").write_text(body)


@pytest.fixture
def site(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """A folder on sys.path for fake plugins; the registry forgets them afterwards."""
    folder = tmp_path / "site"
    folder.mkdir()
    monkeypatch.syspath_prepend(str(folder))
    SCENES.refresh()
    yield folder
    SCENES.refresh()


def marker_plugin(site: Path, marker: Path, package: str = "marks") -> None:
    """A working plugin that leaves ``marker`` behind when (and only when) it is imported."""
    body = f"from pathlib import Path\nPath({str(marker)!r}).touch()\n"
    body += SCENE_CLASS.format(cls="Plugin", scene=package)
    install(site, package, f"{package}_mod", body)


@pytest.mark.parametrize(
    ("raises", "shown"),
    [
        ("import sys\nsys.exit(3)\n", "SystemExit: 3"),
        ("raise KeyboardInterrupt\n", "KeyboardInterrupt"),
        ("raise ImportError('no module named frobnicate')\n", "ImportError: no module named"),
        ("raise BaseException('odd')\n", "BaseException: odd"),
    ],
    ids=["sys.exit", "KeyboardInterrupt", "ImportError", "BaseException"],
)
def test_a_plugin_that_dies_at_import_costs_one_warning(
    site: Path, capsys: pytest.CaptureFixture[str], raises: str, shown: str
) -> None:
    install(site, "deadly", "deadly_mod", raises)
    assert main(["scenes"]) == 0
    captured = capsys.readouterr()
    for name in BUILT_IN:
        assert f"scene {name}:" in captured.out
    (warning,) = captured.err.splitlines()
    assert warning.startswith(
        "warning: scene plugin package 'deadly' (deadly_mod:Plugin) did not load: "
    )
    assert shown in warning


def test_plugins_are_not_imported_by_commands_that_need_no_plugin_scene(
    site: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    marker = tmp_path / "imported"
    marker_plugin(site, marker)
    study = tmp_path / "plain.toml"
    study.write_text(CHECKED)
    outputs = tmp_path / "outputs"
    assert main(["check", str(study)]) == 0
    assert main(["list"]) == 0
    assert main(["scenes", "cam"]) == 0
    assert main(["runs", "--outputs", str(outputs)]) == 0
    assert get_scene("valve").name == "valve"
    assert not marker.exists()  # a slow plugin would have cost none of these anything
    assert main(["scenes"]) == 0  # listing needs every scene
    assert marker.exists()
    assert "scene marks (plugin: marks_mod): a test plugin" in capsys.readouterr().out


def test_a_plugin_scene_name_imports_the_plugins(site: Path, tmp_path: Path) -> None:
    marker = tmp_path / "imported"
    marker_plugin(site, marker, "named")
    assert get_scene("named").name == "named"
    assert marker.exists()


def test_two_packages_registering_one_scene_are_both_refused_and_named(
    site: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    for package in ("first", "second"):
        body = SCENE_CLASS.format(cls="Plugin", scene="twin")
        install(site, package, f"{package}_mod", body, scene="twin")
    study = tmp_path / "twin.toml"
    study.write_text(
        'name = "t"\nscene = "twin"\nresponses = ["y"]\n[factors.x]\nlevels = [1, 2]\n'
    )
    assert main(["check", str(study)]) == 2
    err = capsys.readouterr().err
    assert (
        "warning: scene 'twin' is registered by package 'first' (first_mod:Plugin) and "
        "package 'second' (second_mod:Plugin): neither is loaded (uninstall one)"
    ) in err
    assert "unknown scene 'twin'" in err
    assert "Traceback" not in err


def test_a_plugin_that_exits_at_import_does_not_change_the_exit_code_of_a_real_process(
    tmp_path: Path,
) -> None:
    """The reproduction of the issue, in a process of its own: before, every command exited 3
    silently."""
    site = tmp_path / "site"
    install(site, "exits", "exits_mod", "import sys\nsys.exit(3)\n")
    env = os.environ | {"PYTHONPATH": str(site)}
    done = subprocess.run(
        [sys.executable, "-m", "studies", "scenes"],
        env=env,
        capture_output=True,
        text=True,
        check=False,
    )
    assert done.returncode == 0, done.stderr
    assert "scene cam:" in done.stdout
    assert done.stderr.splitlines() == [
        "warning: scene plugin package 'exits' (exits_mod:Plugin) did not load: SystemExit: 3"
    ]


def test_a_plugin_that_can_answer_no_chunk_is_refused_when_loaded(
    site: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A Scene subclass with neither ``finish`` nor ``evaluate`` would fail on its first chunk,
    after the study was planned and its folder made: it is refused at load, in one line."""
    body = SCENE_CLASS.format(cls="Plugin", scene="halfway")
    body = body[: body.index("    def evaluate")]
    install(site, "halfway", "halfway_mod", body)
    assert "halfway" not in SCENES
    (warning,) = capsys.readouterr().err.splitlines()
    assert warning == (
        "warning: scene plugin package 'halfway' (halfway_mod:Plugin) defines neither finish "
        "(the stage protocol's last step) nor evaluate: skipped (see docs/scenes.md)"
    )
    with pytest.raises(StudyError, match="unknown scene 'halfway'"):
        get_scene("halfway")
