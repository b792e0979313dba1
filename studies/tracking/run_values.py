"""A run's queryable values in SI, whatever units its study file wrote.

Every fixed parameter, every parameter left at its default, every setting and every factor
level of a run's ``study.toml``, and the min/mean/max of each response in its ``results.nc``,
as ``(kind, name, text, number, units, declared)``: the number in the SI unit ``units`` of its
dimension (``bore = 86`` and ``bore = {value = 0.086, units = "m"}`` both give 0.086 m, the
same double: :func:`studies.common.units.to_si`), and ``declared`` the unit the scene declares for it,
the unit a bare number in ``runs --where`` is read in. Kinds: ``parameter`` (fixed in the
file), ``default`` (left at the scene's default), ``setting``, ``factor`` (one row per level)
and ``response`` (``<name>.min|mean|max``).
"""

from __future__ import annotations

import json
import math
import tomllib
from pathlib import Path
from typing import Any

from studies.common.blocks import finite_summary
from studies.common.units import UNITS, si_unit, to_si
from studies.define.definition import StudyDefinition, parse_study
from studies.scenes import Parameter, get_scene

SUMMARIES = ("min", "mean", "max")
Value = tuple[
    str, str, str, float | None, str, str
]  # kind, name, text, SI number, SI unit, declared


def value(kind: str, name: str, given: Any, units: str = "", declared: str = "") -> Value:
    """One value row; a number in ``units`` is converted to SI (units not in
    :data:`studies.common.units.UNITS`, e.g. ``%``, are kept as they are)."""
    declared = declared or units
    if isinstance(given, bool) or not isinstance(given, int | float):
        text = given if isinstance(given, str) else json.dumps(given)
        return kind, name, text, None, units, declared
    if units in UNITS:
        si = to_si(float(given), units)
        return kind, name, json.dumps(si), si, si_unit(units), declared
    return kind, name, json.dumps(float(given)), float(given), units, declared


def values_of(folder: Path, status: str) -> list[Value]:
    """A run's queryable values: its definition's from ``study.toml``; the response summaries
    from ``results.nc`` once it is finished."""
    rows = _definition_values(folder / "study.toml")
    if status == "finished":
        rows += response_values(folder / "results.nc")
    return rows


def definition_values(d: StudyDefinition) -> list[Value]:
    """The values of a parsed definition, in SI (its scene declares the units)."""
    scene = get_scene(d.scene)
    factors = {f.name: f for f in d.factors}
    rows: list[Value] = []
    for p in scene.parameters:
        if p.name in factors:
            f = factors[p.name]
            rows += [_parameter("factor", p, level, f.units) for level in f.levels]
        elif p.name in d.parameters:
            rows.append(_parameter("parameter", p, *d.parameters[p.name]))
        else:
            rows.append(_parameter("default", p, p.default, p.units))
    for s in scene.settings:
        rows.append(_parameter("setting", s, d.settings.get(s.name, s.default), s.units))
    return rows


def _parameter(kind: str, p: Parameter, given: Any, units: str) -> Value:
    if p.kind == "number":
        return value(kind, p.name, given, units, p.units)
    if p.kind == "vector" and p.units in UNITS:
        si = [to_si(float(v), units) for v in given]
        return kind, p.name, json.dumps(si), None, si_unit(p.units), p.units
    return value(kind, p.name, given)


def _definition_values(study: Path) -> list[Value]:
    try:
        text = study.read_text(encoding="utf-8")
    except OSError:
        return []
    try:
        definition, _ = parse_study(text, str(study))
    except KeyError:  # its scene is no longer installed
        definition = None
    if definition is None:  # recorded text that no longer validates: keep what TOML gives
        try:
            raw = tomllib.loads(text)
        except tomllib.TOMLDecodeError:
            return []
        return [value("setting", k, v) for k, v in raw.get("settings", {}).items()]
    return definition_values(definition)


def response_values(results: Path) -> list[Value]:
    """min, mean and max of every floating-point response of a results file, in SI: over
    every design point, and under ``[noise]`` every noise case of each."""
    # xarray only when indexing
    from studies.run.results import is_scalar, open_results  # noqa: PLC0415

    try:
        ds = open_results(results)  # lazily, one response at a time: flat memory
    except (OSError, ValueError):
        return []
    with ds:
        names = json.loads(ds.attrs.get("responses", "[]"))
        rows = []
        for name in names:
            if name not in ds or not is_scalar(ds[name]) or ds[name].dtype.kind != "f":
                continue
            seen = finite_summary(ds[name].variable)  # a block of runs at a time
            units = str(ds[name].attrs.get("units", ""))
            summaries = (seen.low, seen.mean, seen.high) if seen.count else (math.nan,) * 3
            for summary, x in zip(SUMMARIES, summaries, strict=True):
                rows.append(value("response", f"{name}.{summary}", float(x), units))
        return rows
