"""Text of a small study for the scene tests (one template; each test module sets its defaults)."""

from __future__ import annotations


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
