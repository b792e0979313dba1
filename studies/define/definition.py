"""Study definitions: TOML text → a validated :class:`StudyDefinition`.

A study is data first. This module reads the TOML file and checks everything that can be
checked without the design (names, units, types, ranges, empty or duplicate levels), collecting
*every* problem; :mod:`studies.define.plan` adds the design-fit and per-point physical checks and raises
one :class:`StudyFileError` listing them all before anything runs.

File layout (see ``studies/catalog/*.toml`` and the README)::

    name = "isac_l9"                 # ASCII letters, digits, _ and -
    scene = "cam"
    description = "..."
    responses = ["max_contact_stress", "max_jerk"]
    curves = ["lift"]                # optional: per-angle results to store

    [design]
    type = "L9"                      # full_factorial | sweep | auto | an orthogonal array name
    error_columns = ["D"]            # names of the array's unassigned columns (optional)
    interactions = [["A", "B"]]      # factor pairs whose interaction columns are kept (optional)
    pool = ["B"]                     # factors pooled into the ANOVA error (optional; default:
                                     # the smallest factor only when the error has no dof)

    [sense]                          # optional: which direction is better, per response
    max_jerk = "smaller"             # (default: the scene's declaration)

    [none_means]                     # optional: what a design point without a value means,
    max_jerk = "worst"               # "best" | "worst" | "unknown" (default: the scene's)

    [settings]
    angle_step = 0.1                 # accuracy settings of the scene, in its units

    [parameters]                     # fixed values, in the scene's units ...
    base_radius = 20.5
    cam_width = { value = 0.02, units = "m" }   # ... or with explicit units

    [factors.seg2_width]
    levels = [7, 9, 11]
    units = "deg"                    # optional, defaults to the scene's units (deg = degree)
    column = 1                       # optional orthogonal-array column (1-based)
    base = 9                         # optional base level of a sweep (default: middle level)
    role = "control"                 # optional: "control" (a design choice, the default) or
                                     # "operating" (a condition such as engine speed that the
                                     # design must meet at every level: never chosen as "best")
"""

from __future__ import annotations

import re
import tomllib
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from studies.common.bounded_files import (
    STUDY_FILE_BYTES,
    UTF8_BOM,
    InputFileError,
    read_bounded_text,
)
from studies.common.errors import StudyFileError
from studies.define.noise import Noise, parse_limits, parse_noise
from studies.define.sampling import parse_sampling
from studies.define.values import Factor, ValueParser, suggest
from studies.scenes import SCENES, Scene, get_scene
from studies.scenes.base import NONE_MEANINGS, short

CATALOG = Path(__file__).resolve().parents[1] / "catalog"
TOP_LEVEL_KEYS = {
    "name", "scene", "description", "responses", "curves", "design", "settings", "parameters",
    "factors", "sense", "none_means", "noise", "limits",
}  # fmt: skip
DESIGN_KEYS = {"type", "error_columns", "interactions", "pool", "samples", "seed", "second_order"}
NAME_PATTERN = re.compile(r"[A-Za-z0-9_-]+")  # whole names only: used with fullmatch
MAX_NAME_LENGTH = 64  # the name is a folder name; file systems allow 255 bytes
MAX_NESTING = 10  # arrays/tables inside each other; a study needs 4 (factors.x.levels = [...])
SHORT_KEY = 60  # characters of a key path shown in a message


@dataclass(frozen=True)
class StudyDefinition:
    """A parsed study. Values are in the units written in the file (``units`` alongside)."""

    name: str
    scene: str
    description: str
    design: str
    responses: tuple[str, ...]
    curves: tuple[str, ...]
    parameters: dict[str, tuple[Any, str]]
    factors: tuple[Factor, ...]
    settings: dict[str, Any]
    error_columns: tuple[str, ...] = ()
    sense: dict[str, str] = field(default_factory=dict)
    text: str = ""
    source: str = "<string>"
    interactions: tuple[tuple[str, str], ...] = ()
    pool: tuple[str, ...] | None = None
    none_means: dict[str, str] = field(default_factory=dict)
    noise: Noise | None = None  # [noise]: see studies.define.noise
    limits: dict[str, dict[str, float]] = field(default_factory=dict)  # [limits]
    samples: int = 0  # a sampling design's base sample (studies.define.sampling)
    seed: int = 1
    second_order: bool = False  # a saltelli design's second-order indices
    folder: Path | None = None  # where relative input paths are read (None: the working folder)

    def input_files(self) -> tuple[tuple[Path, Path], ...]:
        """The files the study reads (its text parameters, e.g. ``lift_table``), in order: each
        path as written and the file it names (:meth:`input_path`)."""
        scene = get_scene(self.scene)
        return tuple(
            (Path(value), self.input_path(value))
            for name, (value, _) in self.parameters.items()
            if (p := scene.parameter(name)) is not None and p.kind == "text" and value
        )

    def input_path(self, value: str) -> Path:
        """The file an input path names: a relative one in :attr:`folder`."""
        return (self.folder or Path()) / value


def find_study(name_or_path: str | Path) -> Path:
    """A study file by catalogue name (``isac_l9``) or by path."""
    path = Path(name_or_path)
    if path.exists():
        return path
    candidate = CATALOG / f"{name_or_path}.toml"
    if candidate.exists():
        return candidate
    known = ", ".join(catalog_names()) or "none"
    problem = (
        f"no study named {str(name_or_path)!r} in the catalogue (known: {known}) and no such file"
    )
    raise StudyFileError(str(name_or_path), [problem])


def catalog_names() -> list[str]:
    return sorted(p.stem for p in CATALOG.glob("*.toml"))


def read_study(
    name_or_path: str | Path, folder: Path | None = None
) -> tuple[StudyDefinition | None, list[str]]:
    """Parse a study file; return the definition (None if unusable) and the problems found.
    The file must be a regular file of at most ``STUDY_FILE_BYTES`` (StudyFileError otherwise).
    ``folder``: where its relative input paths are read (default: the working folder)."""
    path = find_study(name_or_path)
    try:
        text = read_bounded_text(path, "study file", STUDY_FILE_BYTES)
    except InputFileError as exc:
        raise StudyFileError(str(path), [str(exc)]) from None
    return parse_study(text, str(path), folder)


def parse_study(
    text: str, source: str = "<string>", folder: Path | None = None
) -> tuple[StudyDefinition | None, list[str]]:
    """Parse TOML text; return the definition (None if unusable) and every problem found.
    ``folder``: where its relative input paths are read (default: the working folder).
    A leading UTF-8 byte-order mark is dropped; arrays and tables nested deeper than
    ``MAX_NESTING`` are refused before anything looks at the values."""
    text = text.removeprefix(UTF8_BOM)
    if len(text) > STUDY_FILE_BYTES:  # characters ≤ bytes: a cheap bound before parsing
        return None, [f"has {len(text)} characters: a study file holds at most {STUDY_FILE_BYTES}"]
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        return None, [f"is not valid TOML: {exc}"]
    except RecursionError:
        return None, [f"nests arrays or inline tables too deeply to read (at most {MAX_NESTING})"]
    deep = _too_deep(data)
    if deep:
        return None, [deep]
    return _Parser(data, text, source, folder).parse()


def _too_deep(data: dict[str, Any]) -> str:
    """A sentence naming the first key whose value nests more than ``MAX_NESTING`` arrays or
    tables inside each other, or "" (walked without recursion: any depth is safe; only
    containers are visited, so a long level list costs one pass over its items)."""
    stack: list[tuple[Any, str, int]] = [(data, "", 0)]
    while stack:
        value, where, depth = stack.pop()
        if depth > MAX_NESTING:
            shown = where if len(where) <= SHORT_KEY else where[: SHORT_KEY - 3] + "..."
            return (
                f"{shown} nests arrays or tables more than {MAX_NESTING} deep: a study file "
                "needs at most 4 (e.g. factors.x.levels = [...])"
            )
        items = value.items() if isinstance(value, dict) else enumerate(value)
        for key, item in items:
            if isinstance(item, dict | list):
                path = f"{where}.{key}" if isinstance(key, str) else f"{where}[{key}]"
                stack.append((item, path.removeprefix("."), depth + 1))
    return ""


class _Parser(ValueParser):
    def __init__(self, data: dict[str, Any], text: str, source: str, folder: Path | None) -> None:
        super().__init__()
        self.data, self.text, self.source, self.folder = data, text, source, folder

    def parse(self) -> tuple[StudyDefinition | None, list[str]]:
        d = self.data
        for key in sorted(set(d) - TOP_LEVEL_KEYS):
            self.problem(f"unknown top-level key {key!r}{suggest(key, TOP_LEVEL_KEYS)}")
        name = self._string("name", required=True)
        if name and not NAME_PATTERN.fullmatch(name):
            self.problem(
                f"name = {short(name)} may only contain ASCII letters (A-Z, a-z), digits, '_' and '-'"
            )
        elif name and len(name) > MAX_NAME_LENGTH:
            self.problem(
                f"name = {short(name)} has {len(name)} characters: at most {MAX_NAME_LENGTH} "
                "(it names the run folder)"
            )
        scene_name = self._string("scene", required=True)
        scene = None
        if scene_name:
            if scene_name in SCENES:
                scene = get_scene(scene_name)
            else:
                known = ", ".join(sorted(SCENES))
                self.problem(f"unknown scene {scene_name!r} (known scenes: {known})")
        design, error_columns = self._design()
        responses = self._names("responses", required=True)
        curves = self._names("curves", required=False)
        params = self._table("parameters")
        factors_raw = self._table("factors")
        settings_raw = self._table("settings")
        sense = self._table("sense")
        none_means = self._table("none_means")
        if scene is None:
            return None, self.problems
        self._check_responses(scene, responses, curves, sense)
        self._check_none_means(responses, none_means)
        parameters = self._parameters(scene, params)
        factors = self._factors(scene, factors_raw, design)
        for f in factors:
            if f.name in parameters:
                self.problem(f"{f.name} is both fixed in [parameters] and varied in [factors]")
        settings = self._settings(scene, settings_raw)
        noise = parse_noise(d.get("noise"), scene, factors, self.problems)
        limits = parse_limits(d.get("limits"), responses, scene, self.problems)
        samples, seed, second_order = parse_sampling(d.get("design"), design, self.problems)
        interactions = self._interactions([f.name for f in factors], design)
        pool = self._pool([f.name for f in factors], design)
        if not factors and not self.problems:
            self.problem("no [factors]: a study needs at least one varied parameter")
        definition = StudyDefinition(
            name=name or "",
            scene=scene.name,
            description=self._string("description") or "",
            design=design,
            responses=tuple(responses),
            curves=tuple(curves),
            parameters=parameters,
            factors=tuple(factors),
            settings=settings,
            error_columns=tuple(error_columns),
            sense=dict(sense),
            text=self.text,
            source=self.source,
            interactions=tuple(interactions),
            pool=pool,
            none_means=dict(none_means),
            noise=noise,
            limits=limits,
            samples=samples,
            seed=seed,
            second_order=second_order,
            folder=self.folder,
        )
        return definition, self.problems

    # --- pieces ---------------------------------------------------------------------------
    def _string(self, key: str, required: bool = False) -> str | None:
        value = self.data.get(key)
        if value is None:
            if required:
                self.problem(f"missing required key {key!r}")
            return None
        if not isinstance(value, str) or not value.strip():
            self.problem(f"{key} = {short(value)} must be a non-empty string")
            return None
        return value

    def _names(self, key: str, required: bool) -> list[str]:
        value = self.data.get(key, [] if not required else None)
        if value is None:
            self.problem(f"missing required key {key!r} (a list of names)")
            return []
        if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
            self.problem(f"{key} = {short(value)} must be a list of names")
            return []
        if required and not value:
            self.problem(f"{key} is empty: name at least one")
        for dup in sorted(name for name, n in Counter(value).items() if n > 1):
            self.problem(f"{key} lists {short(dup)} more than once")
        return list(dict.fromkeys(value))

    def _table(self, key: str) -> dict[str, Any]:
        value = self.data.get(key, {})
        if not isinstance(value, dict):
            self.problem(f"[{key}] must be a table, got {short(value)}")
            return {}
        return value

    def _design(self) -> tuple[str, list[str]]:
        design = self.data.get("design", {"type": "full_factorial"})
        if isinstance(design, str):
            design = {"type": design}
        if not isinstance(design, dict):
            self.problem(f"design = {short(design)} must be a string or a [design] table")
            return "full_factorial", []
        for key in sorted(set(design) - DESIGN_KEYS):
            self.problem(f"unknown key {key!r} in [design]{suggest(key, DESIGN_KEYS)}")
        kind = design.get("type", "full_factorial")
        if not isinstance(kind, str):
            self.problem(f"design type = {short(kind)} must be a string")
            kind = "full_factorial"
        errors = design.get("error_columns", [])
        if not isinstance(errors, list) or not all(
            isinstance(e, str) and NAME_PATTERN.fullmatch(e) for e in errors
        ):
            self.problem(f"[design] error_columns = {short(errors)} must be a list of simple names")
            errors = []
        return kind, errors

    def _interactions(self, factors: list[str], design: str) -> list[tuple[str, str]]:
        table = self.data.get("design")
        pairs = table.get("interactions", []) if isinstance(table, dict) else []
        if not isinstance(pairs, list) or not all(
            isinstance(p, list) and len(p) == 2 and all(isinstance(n, str) for n in p)
            for p in pairs
        ):
            self.problem(
                f"[design] interactions = {short(pairs)} must be a list of factor pairs, "
                'e.g. [["seg2_width", "seg2_amplitude"]]'
            )
            return []
        if pairs and design in ("full_factorial", "sweep"):
            self.problem(
                f"[design] interactions only apply to orthogonal-array designs, not {design}"
            )
        for name in dict.fromkeys(n for p in pairs for n in p):
            if name not in factors:
                self.problem(
                    f"[design] interactions name {name!r}, which is not a factor"
                    f"{suggest(name, factors)}"
                )
        return [(a, b) for a, b in pairs if a in factors and b in factors]

    def _pool(self, factors: list[str], design: str) -> tuple[str, ...] | None:
        table = self.data.get("design")
        if not isinstance(table, dict) or "pool" not in table:
            return None
        names = table["pool"]
        if not isinstance(names, list) or not all(isinstance(n, str) for n in names):
            self.problem(
                f'[design] pool = {short(names)} must be a list of factor names, e.g. ["D"]'
            )
            return None
        if design == "sweep":
            self.problem("[design] pool applies to the ANOVA, which a sweep does not have")
        for name in names:
            if name not in factors:
                self.problem(
                    f"[design] pool names {name!r}, which is not a factor{suggest(name, factors)}"
                )
        return tuple(names)

    def _check_responses(
        self, scene: Scene, responses: list[str], curves: list[str], sense: dict[str, Any]
    ) -> None:
        names = [r.name for r in scene.responses]
        for r in responses:
            if scene.response(r) is None:
                self.problem(f"unknown response {r!r} for scene {scene.name!r}{suggest(r, names)}")
        curve_names = [c.name for c in scene.curves]
        for c in curves:
            if scene.curve(c) is None:
                allowed = ", ".join(curve_names) or "none"
                self.problem(f"unknown curve {c!r} for scene {scene.name!r} (allowed: {allowed})")
        for r, s in sense.items():
            if r not in responses:
                self.problem(f"[sense] names {r!r}, which is not in responses")
            if s not in ("smaller", "larger", "none"):
                self.problem(
                    f"[sense] {r} = {short(s)} must be 'smaller', 'larger' or 'none' (not ranked)"
                )

    def _check_none_means(self, responses: list[str], none_means: dict[str, Any]) -> None:
        for r, meaning in none_means.items():
            if r not in responses:
                self.problem(f"[none_means] names {r!r}, which is not in responses")
            if meaning not in NONE_MEANINGS:
                allowed = ", ".join(repr(m) for m in NONE_MEANINGS)
                self.problem(
                    f"[none_means] {r} = {short(meaning)} must be one of {allowed} (what a design "
                    "point without a value means for the analysis)"
                )
