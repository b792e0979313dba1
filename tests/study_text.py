"""Text of a small study for the scene tests (one template; each test module sets its defaults)."""

from __future__ import annotations

from studies.plan import plan_text
from studies.runner import evaluate
from studies.scenes import SceneOutput


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
