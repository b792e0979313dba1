"""What to run next, as a ready-to-run study file built from the run's own study text.

* The confirmation run of an orthogonal array: the chosen control levels (a full factorial of
  one point per operating condition: operating factors keep all their levels).
* The refinement of a full factorial, whose best point was computed and needs no confirmation:
  a finer grid around it, ``REFINEMENT_LEVELS`` levels of each numeric control factor between
  its neighbouring levels, text levels at the chosen one, operating factors at all their
  levels. At the edge of the grid the better value may lie beyond it, so the grid reaches one
  step past the edge (the spacing of the levels: a constant ratio of three or more levels is
  kept, e.g. 1, 0.5, 0.25 → 0.125, and such a factor gets no levels in between; else the last
  difference), as far as the scene's parameter allows (a length stays positive); each such
  step is noted in the file."""

from __future__ import annotations

import json
import math
import re
import tomllib
from collections.abc import Collection, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import xarray as xr

from studies.analysis.taguchi import factor_names, level_values, plain
from studies.scenes import get_scene

_BARE_KEY = re.compile(r"^[A-Za-z0-9_-]+$")
REFINEMENT_LEVELS = 5
SIGNIFICANT = 6  # digits of a refined level


def operating_factors(ds: xr.Dataset) -> list[str]:
    return list(json.loads(ds.attrs.get("operating_factors", "[]")))


def confirmation_values(ds: xr.Dataset, levels: Mapping[str, int]) -> dict[str, list[Any]]:
    """Factor → its physical values: the chosen level of a control factor, every level of an
    operating one (plain Python types)."""
    return {
        f: [level_values(ds, f)[int(levels[f])]] if f in levels else _all(ds, f)
        for f in factor_names(ds)
    }


def _all(ds: xr.Dataset, factor: str) -> list[Any]:
    values = level_values(ds, factor)
    return [values[i] for i in sorted(values)]


def confirmation_toml(ds: xr.Dataset, levels: Mapping[str, int]) -> str:
    """A study file that runs the chosen levels once (in every operating condition): the
    original study (attribute ``study_toml``) with ``design = "full_factorial"`` and one level
    per control factor.

    Without the original text, only the ``[factors]`` tables are written.
    """
    what = "every control factor at its chosen level"
    return _study(ds, confirmation_values(ds, levels), "confirmation", "Confirmation run", what)


@dataclass(frozen=True)
class Refinement:
    """The refinement grid: factor → levels, and one note per factor extended past the edge
    of the grid (or held at it by its allowed range)."""

    values: dict[str, list[Any]]
    notes: list[str] = field(default_factory=list)


def refinement(ds: xr.Dataset, levels: Mapping[str, int], hold: Collection[str] = ()) -> Refinement:
    """The levels of the refinement grid (see the module docstring); factors in ``hold``
    (e.g. without any effect) stay at their chosen level."""
    values = confirmation_values(ds, levels)
    notes = []
    for f, level in levels.items():
        chosen = values[f][0]
        known = level_values(ds, f)
        if isinstance(chosen, str | bool) or f in hold or len(known) < 2:
            continue
        geometric = _geometric([float(known[i]) for i in sorted(known)])
        whole = isinstance(chosen, int) or _whole(ds, f)
        if level - 1 in known and level + 1 in known:
            ends = [float(known[level - 1]), float(known[level + 1])]
        else:  # at the edge of the grid: one step past it
            inner = float(known[level - 1] if level - 1 in known else known[level + 1])
            beyond, note = _beyond(ds, f, float(chosen), inner, geometric, whole)
            notes.append(note)
            ends = [inner, beyond]
        low, high = min(ends), max(ends)
        # Levels at a constant ratio (halved steps) keep it: the refinement is the sequence's
        # own next member, not points in between (a step of 0.0884 deg would not divide the
        # others' grids).
        grid = (
            np.array(sorted({low, float(chosen), high}))
            if geometric
            else np.linspace(low, high, REFINEMENT_LEVELS)
        )
        if whole:
            refined: list[Any] = sorted({round(float(v)) for v in grid})
        else:
            refined = sorted({float(f"{v:.{SIGNIFICANT}g}") for v in grid} | {float(chosen)})
        values[f] = refined
    return Refinement(values, notes)


def refinement_values(
    ds: xr.Dataset, levels: Mapping[str, int], hold: Collection[str] = ()
) -> dict[str, list[Any]]:
    """Factor → the levels of the refinement grid (:func:`refinement`)."""
    return refinement(ds, levels, hold).values


def _geometric(values: list[float]) -> bool:
    """Three or more levels of one sign at a constant ratio (not 1)."""
    if len(values) < 3 or (not all(v > 0 for v in values) and not all(v < 0 for v in values)):
        return False
    ratios = np.asarray(values[1:]) / np.asarray(values[:-1])
    return bool(np.allclose(ratios, ratios[0], rtol=1e-9) and not np.isclose(ratios[0], 1.0))


def _beyond(
    ds: xr.Dataset, factor: str, edge: float, inner: float, geometric: bool, whole: bool
) -> tuple[float, str]:
    """One step past ``edge`` away from ``inner`` and the note on it; ``edge`` itself when the
    factor's allowed range ends there."""
    step = edge * edge / inner if geometric else edge + (edge - inner)
    step = float(round(step)) if whole else float(f"{step:.{SIGNIFICANT}g}")
    units = str(ds[factor].attrs.get("units", "")) if factor in ds.coords else ""
    shown = f"{step:g}" + (f" {units}" if units not in ("", "1") else "")
    problem = _problem(ds, factor, step, units)
    if problem is None:
        return (
            step,
            f"{factor}: the best level is at the edge of the grid; refined past it to {shown}",
        )
    return edge, (
        f"{factor}: the best level is at the edge of the grid, but one step past it is not "
        f"allowed ({problem}): refined towards the inside only"
    )


def _problem(ds: xr.Dataset, factor: str, value: float, units: str) -> str | None:
    """Why ``value`` is not an allowed value of ``factor`` (its scene's parameter; without the
    scene: a quantity whose levels are all positive stays positive)."""
    try:
        parameter = get_scene(str(ds.attrs.get("scene", ""))).parameter(factor)
    except (KeyError, ValueError):
        parameter = None
    if parameter is not None:
        return parameter.check(value, units or None)
    levels = [float(v) for v in level_values(ds, factor).values()]
    if all(v > 0 for v in levels) and value <= 0:
        return f"{factor} = {value:g}: its levels are all positive"
    return None


def _whole(ds: xr.Dataset, factor: str) -> bool:
    """Whether the study file wrote the factor's levels as whole numbers (a count)."""
    original = tomllib.loads(ds.attrs["study_toml"]) if ds.attrs.get("study_toml") else {}
    written = original.get("factors", {}).get(factor, {}).get("levels", [])
    return bool(written) and all(isinstance(v, int) for v in written)


def refinement_toml(ds: xr.Dataset, levels: Mapping[str, int], hold: Collection[str] = ()) -> str:
    """A finer full factorial around the chosen levels ("" when no numeric control factor
    has a neighbouring level to refine towards); a comment line per note of
    :func:`refinement`."""
    found = refinement(ds, levels, hold)
    if all(len(found.values[f]) < 2 for f in levels):
        return ""
    what = "a finer grid between the neighbours of the best computed point"
    text = _study(ds, found.values, "refinement", "Refinement", what)
    head, rest = text.split("\n", 1)
    notes = "".join(f"# {' '.join(n.splitlines())}.\n" for n in found.notes)
    return f"{head}\n{notes}{rest}"


def _study(
    ds: xr.Dataset, values: Mapping[str, list[Any]], kind: str, title: str, what: str
) -> str:
    original = tomllib.loads(ds.attrs["study_toml"]) if ds.attrs.get("study_toml") else {}
    study = {k: v for k, v in original.items() if k not in ("design", "factors")}
    name = str(original.get("name", ds.attrs.get("study_name", "study")))
    if original:
        study["name"] = f"{name}_{kind}"
        study["description"] = f"{title} of {name}: {what}"
        study["design"] = {"type": "full_factorial"}
    factors = {}
    for f, shown in values.items():
        units = ds[f].attrs.get("units", "") if f in ds.coords else ""
        table: dict[str, Any] = {"levels": shown}
        if units:
            table["units"] = str(units)
        if f in operating_factors(ds):
            models = json.loads(ds.attrs.get("model_factors", "[]"))
            table["role"] = "model" if f in models else "operating"
        factors[f] = table
    study["factors"] = factors
    run = ds.attrs.get("run_id", "")
    source = " ".join(f"{name}{f' (run {run})' if run else ''}".splitlines())  # one comment line
    header = f"# {title} of {source}: {what}.\n"
    return header + _toml(study)


def _toml_value(value: Any) -> str:
    value = plain(value)
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if math.isfinite(value):
            return repr(value)
        return "nan" if math.isnan(value) else ("inf" if value > 0 else "-inf")
    if isinstance(value, str):
        return json.dumps(value, ensure_ascii=False)
    if isinstance(value, list):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    if isinstance(value, dict):
        return "{ " + ", ".join(f"{_key(k)} = {_toml_value(v)}" for k, v in value.items()) + " }"
    msg = f"cannot write {value!r} ({type(value).__name__}) as TOML"
    raise TypeError(msg)


def _key(key: str) -> str:
    return key if _BARE_KEY.match(key) else json.dumps(key, ensure_ascii=False)


def _toml(data: Mapping[str, Any]) -> str:
    """TOML text of a study dict: top-level values, then tables (a table of tables as
    ``[name.sub]`` sections)."""
    lines = [f"{_key(k)} = {_toml_value(v)}" for k, v in data.items() if not isinstance(v, dict)]
    for key, table in data.items():
        if not isinstance(table, dict):
            continue
        if table and all(isinstance(v, dict) for v in table.values()):
            for sub, inner in table.items():
                lines += ["", f"[{_key(key)}.{_key(sub)}]"]
                lines += [f"{_key(k)} = {_toml_value(v)}" for k, v in inner.items()]
        else:
            lines += ["", f"[{_key(key)}]"]
            lines += [f"{_key(k)} = {_toml_value(v)}" for k, v in table.items()]
    return "\n".join(lines) + "\n"
