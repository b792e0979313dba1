"""The scene registry: every physical system a study can evaluate.

``SCENES`` maps a scene name to the class implementing it: the built-in scenes (one folder
each under ``studies/scenes/``) and those that installed packages register through the
entry-point group ``engine_studies.scenes`` (name = scene name, value = ``module:Class``, a
subclass of :class:`~studies.scenes.base.Scene`), imported only when a scene that is not built in
is asked for or the scenes are listed. :func:`get_scene` returns the (one, shared)
instance. ``python -m studies scenes`` prints the documentation generated from the
declarations.
"""

from __future__ import annotations

import importlib
import sys
from collections.abc import Iterator, Mapping
from functools import cache
from importlib.metadata import EntryPoint, entry_points
from typing import ClassVar

from studies.common.errors import StudyError
from studies.scenes.base import (
    BenchKit,
    Curve,
    CurveAxis,
    Parameter,
    Response,
    Scene,
    SceneOutput,
    WorkEstimate,
    short,
)
from studies.scenes.state import RunState

ENTRY_POINTS = "engine_studies.scenes"


class BuiltInScenes(Mapping[str, type[Scene]]):
    """The built-in scenes by name, each imported (with its kernels) the first time it is looked
    up: a command that needs no scene (``--help``, ``runs``, ``tag``) imports no Numba."""

    WHERE: ClassVar[dict[str, str]] = {
        "cam": "studies.scenes.cam:CamScene",
        "crank": "studies.scenes.crank:CrankScene",
        "reed": "studies.scenes.reed:ReedScene",
        "luffing": "studies.scenes.luffing:LuffingScene",
        "rocker": "studies.scenes.rocker:RockerScene",
        "valve": "studies.scenes.valve.scene:ValveScene",
        "valve_accuracy": "studies.scenes.valve.accuracy:ValveAccuracyScene",
        "valve_spring_ladder": "studies.scenes.valve.ladder:ValveSpringLadderScene",
    }

    def __getitem__(self, name: str) -> type[Scene]:
        module, attribute = self.WHERE[name].split(":")
        return getattr(importlib.import_module(module), attribute)

    def __contains__(self, name: object) -> bool:
        return name in self.WHERE

    def __iter__(self) -> Iterator[str]:
        return iter(self.WHERE)

    def __len__(self) -> int:
        return len(self.WHERE)


BUILT_IN = BuiltInScenes()


class SceneRegistry(Mapping[str, type[Scene]]):
    """Scene name → class: the built-in scenes at once, the plugins only when asked for.

    Installed packages' entry points are imported the first time a name that is not built in
    is looked up or the scenes are listed, never earlier: a plugin that is slow, broken or
    hostile at import costs only the commands that need a scene of its own or the list of
    them (:func:`load_plugins`)."""

    def __init__(self) -> None:
        self._plugins: dict[str, type[Scene]] | None = None

    def plugins(self) -> dict[str, type[Scene]]:
        """The plugin scenes (loaded on the first call)."""
        if self._plugins is None:
            self._plugins = load_plugins()
        return self._plugins

    def refresh(self) -> None:
        """Forget the loaded plugins: the next lookup finds the installed ones again."""
        self._plugins = None
        get_scene.cache_clear()

    def __getitem__(self, name: str) -> type[Scene]:
        if name in BUILT_IN:
            return BUILT_IN[name]
        return self.plugins()[name]

    def __contains__(self, name: object) -> bool:
        return name in BUILT_IN or name in self.plugins()

    def __iter__(self) -> Iterator[str]:
        return iter([*BUILT_IN, *self.plugins()])  # plugins never reuse a built-in name

    def __len__(self) -> int:
        return len(BUILT_IN) + len(self.plugins())


def load_plugins() -> dict[str, type[Scene]]:
    """Import the scenes installed packages register (entry-point group ``engine_studies.scenes``).

    Each import is guarded: a plugin that fails to import (even by ``sys.exit`` or
    ``KeyboardInterrupt``), is not a Scene, defines neither ``finish`` nor ``evaluate`` (it
    could not answer a single chunk), reuses a built-in name or registers a name another
    package registers too is skipped with one line on stderr naming its package: a broken
    third-party package must not take the engine down."""
    by_name: dict[str, list[EntryPoint]] = {}
    for point in entry_points(group=ENTRY_POINTS):
        same = by_name.setdefault(point.name, [])
        if all(_origin(p) != _origin(point) for p in same):  # one package seen twice on the path
            same.append(point)
    found: dict[str, type[Scene]] = {}
    for name, points in by_name.items():
        if len(points) > 1:
            both = " and ".join(sorted(_origin(p) for p in points))
            _warn(f"scene {short(name)} is registered by {both}: neither is loaded (uninstall one)")
            continue
        (point,) = points
        try:
            loaded = point.load()
        except BaseException as exc:  # noqa: BLE001  (sys.exit, Ctrl-C, any error at import)
            _warn(f"scene plugin {_origin(point)} did not load: {type(exc).__name__}: {exc}")
            continue
        if not (isinstance(loaded, type) and issubclass(loaded, Scene)):
            _warn(f"scene plugin {_origin(point)} is not a Scene subclass: skipped")
        elif loaded.finish is Scene.finish and loaded.evaluate is Scene.evaluate:
            _warn(
                f"scene plugin {_origin(point)} defines neither finish (the stage protocol's "
                "last step) nor evaluate: skipped (see docs/scenes.md)"
            )
        elif name in BUILT_IN or loaded.name != name:
            _warn(
                f"scene plugin {_origin(point)} registers {short(name)}, which is a built-in "
                f"scene or not its class's name {short(loaded.name)}: skipped"
            )
        else:
            found[name] = loaded
    return found


def _origin(point: EntryPoint) -> str:
    """The package and object an entry point names: ``package 'oscillator' (mod:Class)``."""
    dist = getattr(point, "dist", None)
    package = dist.name if dist is not None else "?"
    return f"package {short(package)} ({point.value})"


def _warn(message: str) -> None:
    sys.stderr.write(f"warning: {message}\n")


SCENES = SceneRegistry()


@cache
def get_scene(name: str) -> Scene:
    """The scene called ``name`` (KeyError naming the known scenes otherwise)."""
    try:
        return SCENES[name]()
    except KeyError:
        msg = f"unknown scene {name!r}; known scenes: {', '.join(sorted(SCENES))}"
        raise StudyError(msg) from None


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
    "BenchKit",
    "Curve",
    "CurveAxis",
    "Parameter",
    "Response",
    "RunState",
    "Scene",
    "SceneOutput",
    "WorkEstimate",
    "describe_scene",
    "get_scene",
]
