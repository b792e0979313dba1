"""A study made ready to run: validated definition + design + SI inputs per design point.

:func:`plan_study` is the single gate before any computation: it gathers the definition's own
problems, the design-fit problems and the scene's per-point physical checks into one
:class:`~studies.define.definition.StudyFileError`. Nothing is written and no kernel runs unless the
plan is clean.
"""

from __future__ import annotations

import contextlib
import math
import os
import sys
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from engine_kernels._jit import EVALUATIONS, CompilerNeeded, without_compiler
from studies.common.errors import StudyError
from studies.define import designs
from studies.define.definition import (
    StudyDefinition,
    StudyFileError,
    find_study,
    parse_study,
    read_study,
)
from studies.define.noise import noise_needs_stats, noise_table, noisy, range_problems
from studies.define.sampling import SAMPLING_DESIGNS, sample_runs, sampled_levels
from studies.scenes import Scene, get_scene
from studies.scenes.base import short
from studies.scenes.checks import Left, at_nominal_values, each_check_alone, reading
from studies.scenes.design_points import DesignPoints, Factor

BYTES_PER_FACTOR = 8
BYTES_PER_RESPONSE = 4
MEMORY_SHARE = 0.8  # of the available memory a study may plan to use
MAX_POINTS_VARIABLE = "ENGINE_STUDIES_MAX_POINTS"
STATS_COST = "drawing it imports scipy.stats, about 1 s"


@dataclass(frozen=True)
class Plan:
    """Everything the runner needs; ``points`` are SI values per parameter and computed point,
    made when read (a chunk's values: ``points.at(part)``)."""

    definition: StudyDefinition
    scene: Scene
    design: designs.Design
    points: DesignPoints
    settings: dict[str, Any]
    stages: tuple[str, ...]
    responses: tuple[str, ...]  # stored: the study's, then the scene's status responses
    max_chunk: int = sys.maxsize  # design points per chunk that fit the memory (settings)
    noise_cases: int = 1  # noise cases per design point (1 without [noise])
    noise_values: dict[str, np.ndarray] = field(default_factory=dict)  # runs × cases, units
    unchecked: tuple[str, ...] = ()  # what a quick plan left to `run` (plan_study(quick=True))
    drawn: bool = True  # False: a quick plan's sampling design, whose points are placeholders
    nominal: bool = False  # True: a quick plan's noise study, its points the nominal values

    @property
    def runs(self) -> int:
        return self.design.runs

    @property
    def cases(self) -> int:
        """Points computed: design points × noise cases, design point major (the flat index
        of design point i, noise case j is i · noise_cases + j)."""
        return self.design.runs * self.noise_cases

    def factor_values(self, name: str, part: slice = slice(None)) -> np.ndarray:
        """The factor's value (as written in the study) in the runs ``part``."""
        factor = next(f for f in self.definition.factors if f.name == name)
        return np.asarray(factor.levels)[self.design.levels[name][part]]


def plan_study(
    name_or_path: str | Path, *, quick: bool = False, folder: Path | None = None
) -> Plan:
    """Read, validate and plan a catalogue study or a TOML file (StudyError if not runnable).

    ``quick`` (``check`` without ``--full``): draw no sample that needs ``scipy.stats`` (a
    second to import) and start no compiler; what that leaves unchecked is in
    :attr:`Plan.unchecked`, and such a plan is for reporting only, never for running.
    ``folder``: where relative input paths are read (default: the working folder)."""
    definition, problems = read_study(name_or_path, folder)
    return _plan(definition, problems, str(find_study(name_or_path)), quick)


def plan_text(text: str, source: str = "<string>") -> Plan:
    """Like :func:`plan_study` for TOML text."""
    definition, problems = parse_study(text, source)
    return _plan(definition, problems, source)


def _plan(
    definition: StudyDefinition | None, problems: list[str], source: str, quick: bool = False
) -> Plan:
    if definition is None or (problems and not definition.factors):
        raise StudyFileError(source, problems)
    scene = get_scene(definition.scene)
    unchecked: list[str] = []  # quick: whether or not scipy.stats is imported, same answer
    drawn = not (quick and definition.design in SAMPLING_DESIGNS)
    design = None
    try:
        if not drawn:
            design = _undrawn(definition)
            unchecked.append(
                f"the {definition.design} sample of {design.runs} design points ({STATS_COST})"
            )
        elif definition.design in SAMPLING_DESIGNS:
            definition, design = _sampled(definition)
        else:
            design = _design(definition)
    except designs.DesignError as exc:
        problems = problems + exc.problems
    if design is None or problems:
        raise StudyFileError(source, problems)
    draw = not (quick and noise_needs_stats(definition.noise))
    points, cases, noise_values, noise_problems = _noisy_points(
        scene, definition, _points(scene, definition, design), draw
    )
    if noise_problems:
        raise StudyFileError(source, noise_problems)
    if not draw:
        unchecked.append(
            f"the noise cases, a {noise_label(definition)} ({STATS_COST}); the design points "
            "were checked at their nominal values"
        )
    settings = {
        s.name: s.to_si(definition.settings[s.name])
        if s.kind == "number"
        else definition.settings[s.name]
        for s in scene.settings
    }
    asked, curves = list(definition.responses), list(definition.curves)
    max_chunk, work_problem = settings_fit(scene, definition, settings, design.runs * cases)
    if work_problem:
        raise StudyFileError(source, [work_problem])
    point_problems = scene.request_problems(settings, asked, curves)
    if drawn:
        with contextlib.nullcontext() if draw else at_nominal_values():
            found = _checked_points(scene, points, settings, quick, unchecked)
        point_problems = found + point_problems
    if point_problems:
        raise StudyFileError(source, point_problems)
    stages = scene.stages_to_run(settings, asked, curves)
    stored = scene.stored_responses(asked, curves)
    clashes = _name_clashes(definition, scene, design, stored)
    if clashes:
        raise StudyFileError(source, clashes)
    return Plan(
        definition,
        scene,
        design,
        points,
        settings,
        tuple(stages),
        tuple(stored),
        max_chunk,
        cases,
        noise_values,
        tuple(unchecked),
        drawn,
        not draw,
    )


def _checked_points(
    scene: Scene, points: DesignPoints, settings: dict[str, Any], quick: bool, unchecked: list[str]
) -> list[str]:
    """The scene's problems with the points; ``quick``: [] with a line in ``unchecked`` when
    checking them needs the compiler (or more plain-Python work than a quick plan allows)."""
    if not quick:
        return scene.check_points(points, settings)
    whole, each = "the scene's checks of the points", "the scene's checks that read"
    return quickly(lambda: scene.check_points(points, settings), whole, each, unchecked)


def quickly(
    check: Callable[[], list[str]], whole: str, each: str, unchecked: list[str]
) -> list[str]:
    """``check()`` without the compiler: each of its checks that would need it is left out
    alone and named in ``unchecked`` ("``each`` <what it reads> (<cost>)"), or all of it
    ("``whole`` (<cost>)") when the call needing it is outside :func:`on_distinct`."""
    left: Left = []
    try:
        with without_compiler(), each_check_alone(left):
            found = check()
    except CompilerNeeded as exc:
        unchecked.append(f"{whole} ({needs(exc)})")
        return []
    unchecked += [f"{each} {reading(n)} ({needs(e)})" for n, e in left]
    return found


def needs(exc: CompilerNeeded) -> str:
    """What a check left to the compiler would cost, for an ``unchecked`` line."""
    if exc.what == EVALUATIONS and exc.work:
        return f"{exc.work:,} kernel evaluations: they need the compiler, about 1 s"
    if exc.work:
        return f"{exc.work:,} {exc.what}: more than a quick check takes on"
    return "a compiled kernel: it needs the compiler, about 1 s"


def settings_fit(
    scene: Scene, definition: StudyDefinition, settings: dict[str, Any], runs: int
) -> tuple[int, str]:
    """The design points per chunk that fit this machine's memory at the study's settings,
    and why not even one does ("" if it does), with the memory and time estimates."""
    asked, curves = list(definition.responses), list(definition.curves)
    work = scene.work_estimate(settings, asked, curves)
    share = MEMORY_SHARE * available_memory()
    if work.per_point <= 0.0:
        return sys.maxsize, ""
    if work.fixed + work.per_point <= share:
        return max(1, int((share - work.fixed) / work.per_point)), ""
    defaults = {
        s.name: s.to_si(s.default) if s.kind == "number" else s.default for s in scene.settings
    }
    usual = scene.work_estimate(defaults, asked, curves)
    ratio = (work.fixed + work.per_point) / (usual.fixed + usual.per_point)
    seconds = scene.point_seconds(definition.settings, asked) * ratio * runs  # grows with the grids
    changed = ", ".join(
        f"{name} = {value:g}" if isinstance(value, float) else f"{name} = {value!r}"
        for name, value in definition.settings.items()
        if definition.settings[name] != scene.setting(name).default  # type: ignore[union-attr]
    )
    return 0, (
        f"settings {changed or '(defaults)'} need about {(work.fixed + work.per_point) / 1e9:.3g} "
        f"GB for a single design point (the scene's grids and tables) and about "
        f"{duration(seconds)} to compute {runs} points; this machine has "
        f"{available_memory() / 1e9:.3g} GB of memory available: use a coarser setting"
    )


def full_factorial_size_problem(
    counts: dict[str, int], responses: int, seconds_per_point: float = 1e-3
) -> str:
    """Why a full factorial of ``counts`` will not fit this machine's memory, or "".

    Checked from the level counts alone, before anything is allocated. The estimate per design
    point (``BYTES_PER_FACTOR`` per factor for its level codes and per-run coordinates, plus
    ``BYTES_PER_RESPONSE`` per response) is 76 bytes for the valve study of ``bench study``
    (4 factors, 9 responses and 2 status codes): 1.5× what its runs measured on 2026-11-27 at
    b61dd3e (peak 392 MB at 10⁶ points, 853 MB at 10⁷: 51 bytes a point beyond the process's
    own few hundred MB; the analysis holds one response and the compact level codes at a
    time; at 10⁸ points the run peaked at 4.66 GB against the estimate's 7.6 GB).
    ``ENGINE_STUDIES_MAX_POINTS`` overrides the limit. The message also estimates the
    compute time from the scene's ``seconds_per_point``.
    """
    runs = math.prod(counts.values())
    per_point = BYTES_PER_FACTOR * len(counts) + BYTES_PER_RESPONSE * (responses + 2)
    available = available_memory()
    override = os.environ.get(MAX_POINTS_VARIABLE)
    limit = max_points(override) if override else int(MEMORY_SHARE * available / per_point)
    if runs <= limit:
        return ""
    shape = " x ".join(f"{n} {name}" for name, n in counts.items())
    return (
        f"full factorial of {shape} = {runs:.4g} design points needs about "
        f"{runs * per_point / 1e9:.3g} GB to plan, run and analyse and about "
        f"{duration(runs * seconds_per_point)} to compute ({seconds_per_point:g} s per point); "
        + (
            f"the limit is {limit:.4g} points ({MAX_POINTS_VARIABLE}={override})"
            if override
            else f"this machine allows {limit:.4g} points ({available / 1e9:.3g} GB of memory "
            "available)"
        )
        + '. Use fewer levels, an orthogonal array (type = "auto"), or raise the limit '
        f"with the environment variable {MAX_POINTS_VARIABLE}"
    )


DURATION_UNITS = (("years", 365.25 * 86400.0), ("days", 86400.0), ("h", 3600.0), ("min", 60.0))


def duration(seconds: float) -> str:
    """A duration in the largest unit it reaches, to 3 significant digits ("2.3 h")."""
    for name, size in DURATION_UNITS:
        if seconds >= size:
            return f"{seconds / size:.3g} {name}"
    return f"{seconds:.3g} s"


def max_points(text: str) -> int:
    """The value of ``ENGINE_STUDIES_MAX_POINTS`` (ValueError naming it if not a count)."""
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not 1 <= value < math.inf:
        msg = f"{MAX_POINTS_VARIABLE}={text!r} must be a number of design points, e.g. 5e7"
        raise StudyError(msg)
    return int(value)


def available_memory() -> int:
    """Memory the system can give this process now [bytes] (Linux MemAvailable)."""
    meminfo = Path("/proc/meminfo")
    lines = meminfo.read_text(encoding="ascii").splitlines() if meminfo.exists() else []
    for line in lines:
        if line.startswith("MemAvailable:"):
            return int(line.split()[1]) * 1024
    return os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")  # other systems


def _name_clashes(
    d: StudyDefinition, scene: Scene, design: designs.Design, stored: list[str]
) -> list[str]:
    """Names that two variables of ``results.nc`` would share (one message per clash)."""
    owners: dict[str, list[str]] = {}
    named = [("coordinate", "run")]
    for f in d.factors:
        named += [("factor", f.name), ("coordinate", f"{f.name}_level")]
    named += [("array column", f"{e}_level") for e in design.error_columns]
    named += [("interaction column", f"{n}_level") for n in design.interactions]
    named += [("design label", label) for label in design.labels]
    named += [("response", r) for r in stored]
    named += [("curve", c) for c in d.curves]
    if d.curves and scene.curve_axis is not None:
        named.append(("curve axis", scene.curve_axis.name))
    for kind, name in named:
        owners.setdefault(name, []).append(kind)
    return [
        f"{' and '.join(kinds)} share the name {name!r} in results.nc: "
        + (
            f"leave {name!r} out of curves (the factor keeps its value per run)"
            if "curve" in kinds
            else "rename or drop one of them"
        )
        for name, kinds in owners.items()
        if len(kinds) > 1
    ]


def _design(d: StudyDefinition) -> designs.Design:
    counts = {f.name: len(f.levels) for f in d.factors}
    if d.design == "full_factorial":
        size_problem = full_factorial_size_problem(
            counts,
            len(d.responses),
            get_scene(d.scene).point_seconds(d.settings, list(d.responses)),
        )
        if size_problem:
            raise designs.DesignError([size_problem])
        return designs.full_factorial(counts, lazy=True)
    if d.design == "sweep":
        base = {
            f.name: f.levels.index(f.base) if f.base is not None else (len(f.levels) - 1) // 2
            for f in d.factors
        }
        return designs.sweep(counts, base)
    if d.design == "auto" or designs.is_orthogonal_array_name(d.design):
        columns = {f.name: f.column for f in d.factors}
        return designs.orthogonal(d.design, counts, columns, d.error_columns, d.interactions)
    known = ", ".join(i.name.split("(")[0] for i in designs.list_orthogonal_arrays())
    problem = (
        f"unknown design {d.design!r}: use full_factorial, sweep, auto or an orthogonal "
        f"array ({known})"
    )
    raise designs.DesignError([problem])


def _points(scene: Scene, d: StudyDefinition, design: designs.Design) -> DesignPoints:
    """SI values per parameter and run, made when read (:class:`DesignPoints`): a factor's
    levels are converted once and indexed by the design's codes; a fixed parameter is one
    value."""
    factors = {f.name: f for f in d.factors}
    fixed: dict[str, Any] = {}
    varied: dict[str, Factor] = {}
    for p in scene.parameters:
        if p.name in factors:
            f = factors[p.name]
            levels = np.asarray(f.levels)
            if p.kind == "number":
                levels = np.array([p.to_si(v, f.units) for v in f.levels])
            varied[p.name] = Factor(levels, design.levels[p.name])
            continue
        value, units = d.parameters.get(p.name, (p.default, p.units))
        if p.kind == "number":
            fixed[p.name] = p.to_si(value, units)
        elif p.kind == "vector":
            fixed[p.name] = np.asarray(value, dtype=float) * p.to_si(1.0)
        elif p.kind == "text" and value:
            fixed[p.name] = np.array(str(d.input_path(value)), dtype=object)
        else:
            fixed[p.name] = np.array(value, dtype=object)
    order = [p.name for p in scene.parameters]
    return DesignPoints(design.runs, fixed, varied, order=order)


def _sampled(d: StudyDefinition) -> tuple[StudyDefinition, designs.Design]:
    """A sampling design: each factor's sampled values become its levels (the study's
    ``range`` or distribution gives way to them) and each run's level code indexes them."""
    columns = [
        f.distribution.values if f.distribution else _linear(float(f.levels[0]), float(f.levels[1]))
        for f in d.factors
    ]
    levels, codes = sampled_levels(d.design, columns, d.samples, d.seed, d.second_order)
    factors = tuple(
        replace(f, levels=tuple(v.tolist())) for f, v in zip(d.factors, levels, strict=True)
    )
    named = {f.name: c for f, c in zip(d.factors, codes, strict=True)}
    return replace(d, factors=factors), designs.Design(d.design, tuple(named), named)


def _undrawn(d: StudyDefinition) -> designs.Design:
    """A sampling design's size without its sample (a quick plan): every run at level 0 of
    each factor's written levels (a range's ends, a distribution's nominal), values that no
    check reads."""
    runs = sample_runs(d.design, d.samples, len(d.factors), d.second_order)
    zeros = np.broadcast_to(np.int32(0), (runs,))
    return designs.Design(
        d.design, tuple(f.name for f in d.factors), {f.name: zeros for f in d.factors}
    )


def _linear(lo: float, hi: float) -> Callable[[np.ndarray], np.ndarray]:
    """The uniform range [lo, hi] at unit-cube points."""
    return lambda u: lo + (hi - lo) * u


def _noisy_points(
    scene: Scene, d: StudyDefinition, points: DesignPoints, draw: bool = True
) -> tuple[DesignPoints, int, dict[str, np.ndarray], list[str]]:
    """The points of every design point × noise case (design point major), the noise cases
    per design point, the noise factors' values (runs × cases, parameter units) and why the
    noise cannot run ([] if it can). Without [noise], or not ``draw``n (a quick plan's sample
    that needs scipy.stats): the points unchanged, and the noise checked without its values."""
    if d.noise is None:
        return points, 1, {}, []
    if d.design in ("sweep", *SAMPLING_DESIGNS):
        msg = f"[noise] needs an orthogonal array or a full factorial, not a {d.design} design"
        return points, 1, {}, [msg]
    try:
        table = noise_table(d.noise) if draw else {}
    except designs.DesignError as exc:
        return points, 1, {}, [f"[noise] {p}" for p in exc.problems]
    cases = next(iter(table.values())).size if draw else d.noise.samples
    runs = points.runs
    size_problem = full_factorial_size_problem({"design points": runs, "noise cases": cases}, 1)
    if size_problem:
        return points, 1, {}, [size_problem.replace("full factorial of", "noise study of", 1)]
    values, problems = {}, []
    for f in d.noise.factors:
        p = scene.parameter(f.name)
        assert p is not None
        nominal = np.asarray(points[f.name], dtype=float) / p.to_si(1.0)
        problems += range_problems(d.noise, p, np.unique(nominal), p.units)
        if draw:
            values[f.name] = noisy(f, nominal, table[f.name])
    if problems:
        return points, 1, {}, problems
    if not draw:
        return points, cases, {}, []
    noise = {
        name: v.reshape(-1) * scene.parameter(name).to_si(1.0)  # type: ignore[union-attr]
        for name, v in values.items()
    }
    noisy_points = DesignPoints(
        runs, points.fixed, points.factors, noise, cases=cases, order=points.order
    )
    return noisy_points, cases, values, []


def noise_label(d: StudyDefinition) -> str:
    """How a study's noise is covered, for messages ("" without noise)."""
    if d.noise is None:
        return ""
    names = ", ".join(short(f.name) for f in d.noise.factors)
    how = f"{d.noise.type} sample of {d.noise.samples}" if d.noise.sampled else d.noise.type
    return f"{how} over {names}"
