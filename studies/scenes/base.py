"""What a scene is: documented parameters, settings, responses and curves, and staged kernels.

A scene wraps the compiled kernels of one physical system. It declares

* its **parameters** (name, units, default, allowed range or choices) — the inputs a study can
  fix or vary as factors;
* its **settings** — accuracy knobs (angle step, integrator, smoothing) with the same shape;
* its **responses** (scalar per design point) and **curves** (per design point and angle), each
  naming the *stages* it needs.

A stage is one compiled batch driver (kinematics, contact geometry, loads, dynamics, ...).
:meth:`Scene.stages_for` turns a study's requests into the minimal set of stages, and
:meth:`Scene.evaluate` runs only those: asking for a kinematic response never runs the dynamics.

One protocol for every built-in scene: :meth:`Scene.start` makes the chunk's run state (a
:class:`RunState` dataclass of the scene's own, one typed field per result a stage leaves),
each stage ``stage_<name>(state)`` fills its fields, and :meth:`Scene.finish` turns the state
into the responses and curves. The state has slots: a mistyped field fails at once
(``AttributeError``), and a field no stage filled is unset, so reading it fails too.
"""

from __future__ import annotations

import math
from abc import ABC
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Generic, cast

import numpy as np

from studies.common.errors import StudyError
from studies.common.units import UNITS, to_si
from studies.scenes.state import RunState, State

if TYPE_CHECKING:
    import xarray as xr
    from matplotlib.figure import Figure

    FigureBuilder = Callable[[xr.Dataset], Figure | None]


@dataclass(frozen=True)
class Parameter:
    """An input of a scene, in engineering units (``units``) as written in study files.

    ``minimum``/``maximum`` bound the physically allowed values (``None`` = unbounded); with
    ``exclusive_minimum`` the minimum itself is not allowed (e.g. a radius must be > 0); an
    ``integer`` parameter (a count) takes whole numbers only.
    A parameter with ``choices`` takes one of those strings; a ``vector`` parameter takes a list
    of numbers and a ``text`` parameter a string (a file path); neither can be a factor.
    """

    name: str
    units: str
    default: Any
    long_name: str
    minimum: float | None = None
    maximum: float | None = None
    exclusive_minimum: bool = False
    choices: tuple[str, ...] = ()
    vector: bool = False
    text: bool = False
    source: str = ""
    integer: bool = False

    @property
    def kind(self) -> str:
        if self.choices:
            return "choice"
        if self.text:
            return "text"
        return "vector" if self.vector else "number"

    def allowed(self) -> str:
        """Human description of the allowed values."""
        if self.choices:
            return "one of " + ", ".join(repr(c) for c in self.choices)
        if self.text:
            return "a string"
        lo = "-inf" if self.minimum is None else f"{self.minimum:g}"
        hi = "inf" if self.maximum is None else f"{self.maximum:g}"
        bracket = "(" if self.exclusive_minimum or self.minimum is None else "["
        close = ")" if self.maximum is None else "]"
        if self.vector:
            bounded = self.minimum is not None or self.maximum is not None
            inside = f" in {bracket}{lo}, {hi}{close} {self.units}" if bounded else ""
            return f"a list of finite numbers{inside}"
        kind = "whole number" if self.integer else "number"
        return f"a {kind} in {bracket}{lo}, {hi}{close} {self.units}"

    def check(self, value: Any, units: str | None = None) -> str | None:
        """Return a problem description for ``value`` (given in ``units``), or None if fine."""
        if self.choices:
            if not isinstance(value, str) or value not in self.choices:
                return f"{self.name} = {short(value)} is not allowed: use {self.allowed()}"
            return None
        if self.text:
            if not isinstance(value, str):
                return f"{self.name} = {short(value)} must be a string"
            return (
                None if value.isprintable() else f"{self.name} = {value!r} has control characters"
            )
        if self.vector:
            if not isinstance(value, list):
                return f"{self.name} = {short(value)} is not allowed: use {self.allowed()}"
            if not value:
                return f"{self.name} = [] is empty: give {self.allowed()}"
            bad = next((i for i, v in enumerate(value) if not is_finite_number(v)), None)
            if bad is not None:
                return f"{self.name}[{bad}] = {not_a_number(value[bad])} (use {self.allowed()})"
            bad = next((i for i, v in enumerate(value) if self._outside(v)), None)
            if bad is not None:
                given = f"{value[bad]:g} {self.units}"
                return (
                    f"{self.name}[{bad}] = {given} is physically impossible: use {self.allowed()}"
                )
            return None
        if not is_finite_number(value):
            return f"{self.name} = {not_a_number(value)} (expected {self.allowed()})"
        if self.integer and value != int(value):
            return f"{self.name} = {value!r} is not a whole number (expected {self.allowed()})"
        si = value * UNITS[units or self.units].to_si
        if not math.isfinite(si) or (si == 0.0 and value != 0):
            given = f"{value:g} {units or self.units}"
            limit = "too close to 0 (it is 0 in SI units)" if si == 0 else "too large for SI units"
            return f"{self.name} = {given} is {limit}: expected {self.allowed()}"
        shown = value
        if units is not None and units != self.units:
            shown = value * UNITS[units].to_si / UNITS[self.units].to_si
        if self._outside(shown):
            given = f"{value:g} {units or self.units}"
            return f"{self.name} = {given} is physically impossible: must be {self.allowed()}"
        return None

    def _outside(self, value: float) -> bool:
        """True if ``value`` (in ``units``) is outside the parameter's bounds."""
        too_low = self.minimum is not None and (
            value < self.minimum or (self.exclusive_minimum and value <= self.minimum)
        )
        return too_low or (self.maximum is not None and value > self.maximum)

    def to_si(self, value: float, units: str | None = None) -> float:
        return to_si(float(value), units or self.units)


NONE_MEANINGS = ("best", "worst", "unknown")


NOT_EVALUATED = -1
"""Stored value of a flag or status code where it was not evaluated: at a point that did not
run, or a check whose value could not be computed there (a scene gives NaN)."""


@dataclass(frozen=True)
class Response:
    """A scalar result per design point, in ``units``; ``needs`` lists the stages it uses.

    ``sense`` says which direction is better for range analysis ("smaller" or "larger");
    ``flag`` responses are 0/1 design-criterion verdicts stored beside their margins.
    A status code has the meaning of each value 0, 1, … in ``codes``, a status bit mask the
    meaning of each bit 1, 2, 4, … in ``bits`` (CF flag words: lower case, no spaces); both are
    stored as integers with CF flag attributes and counted, never averaged.
    ``none_means`` says what a design point without a value (NaN: e.g. no resonance crossing
    in the range) means for the analysis (``NONE_MEANINGS``): "best" or "worst" (it counts
    as the best or worst value seen, a bound), or "unknown" (left out, counted per level);
    ``none_label`` says in words what such a point is, for the report (its ``{setting}`` fields
    are filled with the study's settings: "no crossing up to order {max_order:g}").
    ``used_for`` names the parameter whose value this response records as it actually ran,
    where the scene may replace the requested one (``angle_step_used`` of a tolerance run): the
    report then says what ran wherever it names that parameter's level.
    """

    name: str
    units: str
    long_name: str
    needs: tuple[str, ...]
    sense: str = "smaller"
    flag: bool = False
    codes: tuple[str, ...] = ()
    bits: tuple[str, ...] = ()
    none_means: str = "unknown"
    none_label: str = ""
    used_for: str = ""


@dataclass(frozen=True)
class Curve:
    """A result per design point and per angle, stored only when a study asks for it."""

    name: str
    units: str
    long_name: str
    needs: tuple[str, ...]


@dataclass
class SceneOutput:
    """What :meth:`Scene.evaluate` returns for a chunk of design points (response units)."""

    scalars: dict[str, np.ndarray]
    curves: dict[str, np.ndarray] = field(default_factory=dict)


@dataclass(frozen=True)
class WorkEstimate:
    """Memory a scene needs at a study's settings [bytes]: ``fixed`` once per chunk (shared
    tables), ``per_point`` for each design point of a chunk (its grids and curves)."""

    fixed: float = 0.0
    per_point: float = 0.0


@dataclass(frozen=True)
class BenchKit:
    """What the bench command lends a scene's benchmarks: the engine's planner (study text →
    plan) and chunk evaluator ((plan, runs) → evaluation), which the scene layer cannot import."""

    plan: Callable[[str], Any]
    evaluate: Callable[[Any, slice], Any]


SceneBenchmark = Callable[[BenchKit, int, float, int], dict[str, Any]]


@dataclass(frozen=True)
class CurveAxis:
    """The shared angle axis of a scene's curves (name, units, values)."""

    name: str
    units: str
    long_name: str


class Scene(ABC, Generic[State]):
    """Base class: subclasses fill the declarations, make their run state (:meth:`start`),
    implement the stages on it and read the outputs from it (:meth:`finish`)."""

    name: str = ""
    description: str = ""
    parameters: tuple[Parameter, ...] = ()
    settings: tuple[Parameter, ...] = ()
    responses: tuple[Response, ...] = ()
    curves: tuple[Curve, ...] = ()
    curve_axis: CurveAxis | None = None
    stage_order: tuple[str, ...] = ()
    state_type: type[RunState] = RunState  # what :meth:`start` makes; the stages fill it
    # Responses stored whenever the stages they need run, asked for or not: they say why
    # another response is NaN at a design point (no jump at all, or the dynamics never ran).
    status_responses: tuple[str, ...] = ()
    # Compute time per design point [s] for the size guard's estimate: about twice what the
    # scene's catalogue studies and a 2000-point run measured at default settings on 2 cores.
    seconds_per_point: float = 1e-3

    def __init__(self) -> None:
        self.stages: dict[str, Any] = {s: getattr(self, f"stage_{s}") for s in self.stage_order}

    # --- lookups -------------------------------------------------------------------------
    def parameter(self, name: str) -> Parameter | None:
        return next((p for p in self.parameters if p.name == name), None)

    def setting(self, name: str) -> Parameter | None:
        return next((p for p in self.settings if p.name == name), None)

    def response(self, name: str) -> Response | None:
        return next((r for r in self.responses if r.name == name), None)

    def curve(self, name: str) -> Curve | None:
        return next((c for c in self.curves if c.name == name), None)

    def point_seconds(self, settings: dict[str, Any], responses: list[str]) -> float:
        """A conservative compute time of one design point asking ``responses`` at these
        ``settings`` (as the study gives them) [s], for the size guard's time estimate:
        :attr:`seconds_per_point` unless the scene knows its costs better."""
        return self.seconds_per_point

    def stages_for(self, responses: list[str], curves: list[str]) -> list[str]:
        """The stages needed for these responses and curves, in execution order."""
        needed: set[str] = set()
        for r in responses:
            needed.update(self.response(r).needs)  # type: ignore[union-attr]
        for c in curves:
            needed.update(self.curve(c).needs)  # type: ignore[union-attr]
        return [s for s in self.stage_order if s in needed]

    def stored_responses(self, responses: list[str], curves: list[str]) -> list[str]:
        """The study's responses, then each status response whose stages run anyway."""
        stages = set(self.stages_for(responses, curves))
        extra = [
            name
            for name in self.status_responses
            if name not in responses
            and (r := self.response(name)) is not None
            and set(r.needs) <= stages
        ]
        return [*responses, *extra]

    def stages_to_run(
        self, settings: dict[str, Any], responses: list[str], curves: list[str]
    ) -> list[str]:
        """The stages :meth:`evaluate` runs for these requests at these settings (SI): those
        the requests need (:meth:`stages_for`), unless a setting changes which stage answers."""
        return self.stages_for(responses, curves)

    def evaluate(
        self,
        points: dict[str, np.ndarray],
        settings: dict[str, Any],
        responses: list[str],
        curves: list[str],
    ) -> SceneOutput:
        """Evaluate a chunk of design points (SI inputs) running only the needed stages, in
        order, on the run state :meth:`start` makes; :meth:`finish` reads the outputs.

        Stages are called through ``self.stages`` so a test can spy on which ran.
        """
        state = self.start(points, settings, responses, curves)
        for stage in self.stages_to_run(settings, responses, curves):
            self.stages[stage](state)
        return self.finish(state)

    def start(
        self,
        points: dict[str, np.ndarray],
        settings: dict[str, Any],
        responses: list[str],
        curves: list[str],
    ) -> State:
        """The run state of one chunk before any stage ran: a :attr:`state_type` holding the
        request, then :meth:`prepare`."""
        state = cast(State, self.state_type.of(points, settings, responses, curves))
        self.prepare(state)
        return state

    def prepare(self, state: State) -> None:
        """Derive up front what every stage reads (kernel parameter rows, groups of points);
        nothing by default."""

    def finish(self, state: State) -> SceneOutput:
        """The responses and curves asked for, in their declared units, from the run state.

        Every scene defines this or overrides :meth:`evaluate`; a plugin that does neither is
        refused when it is loaded (:func:`studies.scenes.load_plugins`), so this line is
        reached only by a scene class used without the registry."""
        raise NotImplementedError(f"scene {self.name!r} defines neither finish nor evaluate")

    # --- to be provided by each scene ---------------------------------------------------
    def check_points(self, points: Mapping[str, np.ndarray], settings: dict[str, Any]) -> list[str]:
        """Cross-parameter physical checks over all design points (SI values); problems."""
        return []

    def request_problems(
        self, settings: dict[str, Any], responses: list[str], curves: list[str]
    ) -> list[str]:
        """Responses or curves these settings cannot answer (SI settings); problems. None by
        default."""
        return []

    def work_estimate(
        self, settings: dict[str, Any], responses: list[str], curves: list[str]
    ) -> WorkEstimate:
        """Memory these settings (SI) make the scene use, from the settings alone (nothing
        allocated): the engine refuses a study whose single design point would not fit and
        bounds the chunk size by it. Nothing known by default."""
        return WorkEstimate()

    def point_warnings(
        self, points: Mapping[str, np.ndarray], settings: dict[str, Any]
    ) -> list[str]:
        """Design points that will run but give no value (e.g. a concave cam), with advice;
        ``check`` and ``run`` print them. None by default."""
        return []

    def figures(self) -> dict[str, FigureBuilder]:
        """The scene's own figures beside the generic ones, by file stem: each builder draws
        from a results Dataset, or returns None when the Dataset lacks what it needs. None by
        default; :mod:`studies.common.figure_layout` has the helpers."""
        return {}

    def summaries(self, ds: xr.Dataset) -> list[str]:
        """Text blocks for ``analysis.txt`` beside the range analysis and ANOVA (tables a user
        of this scene reads). None by default; :mod:`studies.common.summary_tables` has helpers."""
        return []

    def benchmarks(self) -> dict[str, SceneBenchmark]:
        """The scene's own benchmarks for ``studies bench NAME``, by name: each takes the
        engine's :class:`BenchKit`, the number of cases, the angle step [deg] and the repeats,
        and returns its figures. None by default."""
        return {}

    def curve_coordinate(self, settings: dict[str, Any]) -> np.ndarray:
        """Values of the curve axis (in ``curve_axis.units``) for these settings."""
        raise StudyError(f"scene {self.name!r} stores no curves")


INT64_MAX = 2**63 - 1  # TOML integers are 64-bit; a longer one is a typing slip
SHORT_REPR = 40  # characters of a value shown in a message


def is_finite_number(value: Any) -> bool:
    """A float that is finite or an int that fits in 64 bits (booleans are not numbers)."""
    if isinstance(value, bool):
        return False
    if isinstance(value, int):
        return abs(value) <= INT64_MAX
    return isinstance(value, float) and math.isfinite(value)


def not_a_number(value: Any) -> str:
    """The end of a message for a value that :func:`is_finite_number` refuses."""
    if isinstance(value, int) and not isinstance(value, bool):
        return f"{short(value)} is beyond the 64-bit integers a study file may hold"
    return f"{short(value)} is not a finite number"


def short(value: Any) -> str:
    """``repr(value)``, cut to ``SHORT_REPR`` characters so a message stays one short line."""
    text = repr(value)
    return text if len(text) <= SHORT_REPR else f"{text[: SHORT_REPR - 3]}..."
