"""Helpers of the scene tests: the text of a small study (one template; each test module sets
its defaults), the README's own example study, evaluating a study, and recording which stages
of a scene run."""

from __future__ import annotations

import re
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from studies.define.plan import plan_text
from studies.run.runner import evaluate
from studies.scenes import SceneOutput

README = Path(__file__).resolve().parents[1] / "README.md"


def readme_study() -> str:
    """The TOML block of the README's "Writing a study" section, exactly as written."""
    section = README.read_text(encoding="utf-8").split("## Writing a study", 1)[1]
    match = re.search(r"```toml\n(.*?)```", section, re.DOTALL)
    assert match, "the README's 'Writing a study' section has no TOML example"
    return match.group(1)


def scene_study(
    scene: str,
    *,
    responses: str,
    factors: str,
    parameters: str = "",
    curves: str = "[]",
    settings: str = "",
) -> str:
    """A study of ``scene`` named ``<scene>_test``; arguments are TOML fragments."""
    return f"""
name = "{scene}_test"
scene = "{scene}"
responses = {responses}
curves = {curves}
[settings]
{settings}
[parameters]
{parameters}
{factors}
"""


def run(text: str) -> SceneOutput:
    """Plan and evaluate a study text in memory (no run folder), without progress output."""
    return evaluate(plan_text(text), progress=False)


@contextmanager
def recorded_stages(scene: Any) -> Iterator[list[str]]:
    """Within the block, the names of the scene's stages in the order they are called."""
    calls: list[str] = []
    original = dict(scene.stages)

    def spy(name: str, fn: Any) -> Any:
        def wrapped(*args: Any, **kwargs: Any) -> Any:
            calls.append(name)
            return fn(*args, **kwargs)

        return wrapped

    try:
        for name, fn in original.items():
            scene.stages[name] = spy(name, fn)
        yield calls
    finally:
        scene.stages.update(original)


CAM_NOISE = """
name = "cam_noise"
scene = "cam"
responses = ["max_contact_stress", "max_jerk"]
design = "full_factorial"
[parameters]
cam_speed = {cam_speed}
[factors.base_radius]
levels = [30.0, 35.0]
units = "mm"
[noise]
type = "L4"
[noise.spring_rate]
distribution = "uniform"
half_width = 5
relative = true
"""
"""A small cam study under [noise] (format ``cam_speed`` [rpm]): 2 design points x 4 cases."""
