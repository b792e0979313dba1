"""The complete example of docs/scenes.md (a stage on a typed run state, a curve on its own
axis, ``curve_coordinate`` and ``request_problems``) runs as written: the code block is taken
from the page, registered as a scene, and a study runs through the engine. The curve is checked
against the closed form x(t) = x0 cos(√(k/m) t)."""

from __future__ import annotations

import math
import re
from collections.abc import Iterator
from pathlib import Path
from types import ModuleType

import numpy as np
import pytest

from studies import scenes
from studies.define.definition import StudyFileError
from studies.define.plan import plan_text
from studies.run.results import build_dataset
from studies.run.runner import evaluate

DOCS = Path(__file__).resolve().parents[2] / "docs" / "scenes.md"
STUDY = """
name = "free_vibration_test"
scene = "free_vibration"
responses = ["natural_frequency", "max_speed"]
curves = ["displacement"]
[settings]
time_step = 0.5
duration = 20.0
[factors.stiffness]
levels = [1000.0, 4000.0]
[factors.mass]
levels = [1.0, 2.5]
"""


@pytest.fixture
def scene_class(monkeypatch: pytest.MonkeyPatch) -> Iterator[type[scenes.Scene]]:
    section = DOCS.read_text(encoding="utf-8").split("## A complete example", 1)[1]
    match = re.search(r"```python\n(.*?)```", section, re.DOTALL)
    assert match, "docs/scenes.md has no python example"
    module = ModuleType("docs_free_vibration")
    exec(compile(match.group(1), str(DOCS), "exec"), module.__dict__)  # noqa: S102
    cls = module.FreeVibrationScene
    found = scenes.SCENES.plugins() | {cls.name: cls}  # as if installed as a plugin
    monkeypatch.setattr(scenes.SCENES, "plugins", lambda: found)
    scenes.get_scene.cache_clear()
    yield cls
    scenes.get_scene.cache_clear()


def test_the_documented_scene_runs_and_its_curve_is_the_closed_form(scene_class) -> None:
    plan = plan_text(STUDY)
    ds = build_dataset(plan, evaluate(plan, progress=False), {})
    assert ds["displacement"].dims == ("run", "time")
    assert ds["displacement"].attrs["units"] == "mm"
    t_ms = ds["time"].values
    assert ds["time"].attrs["units"] == "ms"
    np.testing.assert_allclose(t_ms, np.arange(41) * 0.5)  # 0 … 20 ms every 0.5 ms
    for run in range(ds.sizes["run"]):
        k, m = float(ds["stiffness"].values[run]), float(ds["mass"].values[run])
        omega = math.sqrt(k / m)
        expected = 5.0 * np.cos(omega * t_ms * 1e-3)  # release 5 mm (the default)
        np.testing.assert_allclose(ds["displacement"].values[run], expected, atol=1e-12)
        assert float(ds["natural_frequency"].values[run]) == pytest.approx(omega / (2 * math.pi))
        assert float(ds["max_speed"].values[run]) == pytest.approx(5e-3 * omega)


def test_request_problems_refuse_a_curve_too_long(scene_class) -> None:
    text = STUDY.replace("time_step = 0.5", "time_step = 1e-4")  # 200 001 values per point
    with pytest.raises(StudyFileError, match=r"curve displacement would hold 2e\+05 values"):
        plan_text(text)
    plan_text(text.replace('curves = ["displacement"]', "curves = []"))  # no curve: no problem
