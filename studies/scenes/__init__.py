"""The scene registry: every physical system a study can evaluate.

``SCENES`` maps a scene name to the class implementing it: the built-in scenes (one folder
each under ``studies/scenes/``) and those that installed packages register through the
entry-point group ``engine_studies.scenes`` (name = scene name, value = ``module:Class``, a
subclass of :class:`~studies.scenes.base.Scene`). :func:`get_scene` returns the (one, shared)
instance. ``python -m studies scenes`` prints the documentation generated from the
declarations.
"""

from __future__ import annotations

import sys
from functools import cache
from importlib.metadata import entry_points

from studies.scenes.base import Curve, CurveAxis, Parameter, Response, Scene, SceneOutput
from studies.scenes.cam import CamScene
from studies.scenes.crank import CrankScene
from studies.scenes.luffing import LuffingScene
from studies.scenes.reed import ReedScene
from studies.scenes.rocker import RockerScene
from studies.scenes.valve import ValveAccuracyScene, ValveScene, ValveSpringLadderScene

ENTRY_POINTS = "engine_studies.scenes"
BUILT_IN: dict[str, type[Scene]] = {
    CamScene.name: CamScene,
    CrankScene.name: CrankScene,
    ReedScene.name: ReedScene,
    LuffingScene.name: LuffingScene,
    RockerScene.name: RockerScene,
    ValveScene.name: ValveScene,
    ValveAccuracyScene.name: ValveAccuracyScene,
    ValveSpringLadderScene.name: ValveSpringLadderScene,
}


def plugin_scenes() -> dict[str, type[Scene]]:
    """The scenes installed packages register (entry-point group ``engine_studies.scenes``).

    A plugin that fails to load, is not a Scene, or reuses a built-in name is skipped with one
    line on stderr: a broken third-party package must not take the built-in scenes down."""
    found: dict[str, type[Scene]] = {}
    for point in entry_points(group=ENTRY_POINTS):
        try:
            loaded = point.load()
        except Exception as exc:  # noqa: BLE001  (any import error of a third-party package)
            _warn(f"scene plugin {point.value!r} did not load: {exc}")
            continue
        if not (isinstance(loaded, type) and issubclass(loaded, Scene)):
            _warn(f"scene plugin {point.value!r} is not a Scene subclass")
        elif point.name in BUILT_IN or loaded.name != point.name:
            _warn(
                f"scene plugin {point.value!r} registers {point.name!r}, which is a built-in "
                f"scene or not its class's name {loaded.name!r}: skipped"
            )
        else:
            found[point.name] = loaded
    return found


def _warn(message: str) -> None:
    sys.stderr.write(f"warning: {message}\n")


SCENES: dict[str, type[Scene]] = BUILT_IN | plugin_scenes()


@cache
def get_scene(name: str) -> Scene:
    """The scene called ``name`` (KeyError naming the known scenes otherwise)."""
    try:
        return SCENES[name]()
    except KeyError:
        msg = f"unknown scene {name!r}; known scenes: {', '.join(sorted(SCENES))}"
        raise KeyError(msg) from None


def describe_scene(scene: Scene) -> str:
    """Plain-text documentation of a scene's parameters, settings, responses and curves."""
    origin = "" if scene.name in BUILT_IN else f" (plugin: {type(scene).__module__})"
    lines = [f"scene {scene.name}{origin}: {scene.description}", ""]
    lines.append("  parameters (fix in [parameters] or vary in [factors]):")
    for p in scene.parameters:
        default = p.default if p.kind != "number" else f"{p.default:g}"
        src = f"  [{p.source}]" if p.source else ""
        lines.append(f"    {p.name:<28} {p.units:<9} default {default!s:<12} {p.allowed()}")
        lines.append(f"    {'':<28} {p.long_name}{src}")
    if scene.settings:
        lines.append("  settings ([settings]):")
        for s in scene.settings:
            lines.append(f"    {s.name:<28} {s.units:<9} default {s.default!s:<12} {s.allowed()}")
            lines.append(f"    {'':<28} {s.long_name}")
    lines.append("  responses (scalar per design point; needs = stages that run):")
    for r in scene.responses:
        lines.append(
            f"    {r.name:<34} {r.units:<9} {r.long_name}  "
            f"[needs {', '.join(r.needs)}; {r.sense} is better"
            + (f"; no value counts as {r.none_means}]" if r.none_means != "unknown" else "]")
        )
    if scene.curves:
        axis = scene.curve_axis
        lines.append(
            f"  curves (per design point × {axis.name if axis else 'angle'}; stored only "
            "when listed in 'curves'):"
        )
        for c in scene.curves:
            lines.append(
                f"    {c.name:<34} {c.units:<9} {c.long_name}  [needs {', '.join(c.needs)}]"
            )
    return "\n".join(lines)


__all__ = [
    "BUILT_IN",
    "SCENES",
    "Curve",
    "CurveAxis",
    "Parameter",
    "Response",
    "Scene",
    "SceneOutput",
    "describe_scene",
    "get_scene",
]
