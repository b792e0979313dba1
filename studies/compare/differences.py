"""What differs between the definitions, code and versions of recorded runs.

Values are compared as the registry holds them, in SI (:mod:`studies.tracking.run_values`): a parameter
written ``86`` (mm) in one study and ``{value = 0.086, units = "m"}`` in another is the same
value, and so is one fixed at its default and one left there. The rest of a definition (design,
responses, curves, factor columns) is compared as the TOML wrote it. Code is the engine's and
the scene's distribution, version and source hash, recorded in ``run.json``
(:func:`studies.run.provenance.code`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from studies.common.units import UNITS, from_si
from studies.run.provenance import describe_scene_code

MISSING = "—"
VALUE_SECTIONS = ("parameters", "settings", "description")
FACTOR_VALUE_KEYS = ("levels", "units")  # compared in SI, from the registry
KINDS = {"parameter": "fixed parameter", "default": "fixed parameter", "setting": "setting"}


@dataclass
class Difference:
    """One entry that differs between runs (a value per run, reference first)."""

    kind: str  # "fixed parameter", "setting", "factor", "study", "code", "version"
    name: str
    values: list[str]
    note: str = ""
    detail: list[str] = field(default_factory=list)  # per run, where values alone are equal

    def text(self) -> str:
        """The values, ``a → b`` for two runs and ``a | b | c`` for more, then the note."""
        joined = (" → " if len(self.values) == 2 else " | ").join(self.values)
        return f"{joined}, {self.note}" if self.note else joined

    def label(self, index: int) -> str:
        """What this difference is in run ``index`` (a plot legend's words)."""
        detail = f" ({self.detail[index]})" if self.detail else ""
        return f"{self.name} {self.values[index]}{detail}"


def definition_differences(
    definitions: list[dict[str, Any]], values: list[list[dict[str, Any]]]
) -> list[Difference]:
    """Differences of the TOML definitions (values compared in SI when the registry has them)."""
    indexed = all(values)
    flat = [flatten(_structure(d) if indexed else d) for d in definitions]
    keys = list(dict.fromkeys(k for f in flat for k in f))
    out = []
    for key in keys:
        shown = [short(f.get(key, MISSING)) for f in flat]
        if len(set(shown)) > 1:
            section, _, name = key.partition(".")
            kind = {"factors": "factor", "parameters": "fixed parameter", "settings": "setting"}
            out.append(Difference(kind.get(section, "study"), name or section, shown))
    return out + (_value_differences(values) if indexed else [])


def _structure(definition: dict[str, Any]) -> dict[str, Any]:
    """The definition without its values (those are compared in SI)."""
    out = {k: v for k, v in definition.items() if k not in VALUE_SECTIONS}
    factors = out.get("factors")
    if isinstance(factors, dict):
        out["factors"] = {
            name: {k: v for k, v in spec.items() if k not in FACTOR_VALUE_KEYS}
            if isinstance(spec, dict)
            else spec
            for name, spec in factors.items()
        }
    return out


def _value_differences(values: list[list[dict[str, Any]]]) -> list[Difference]:
    tables = [_value_table(rows) for rows in values]
    names = list(dict.fromkeys(n for t in tables for n in t))
    out = []
    for name in names:
        entries = [t.get(name, ("", MISSING, MISSING)) for t in tables]
        if len({key for _, key, _ in entries}) > 1:
            kinds = {kind for kind, _, _ in entries if kind}
            kind = "factor" if "factor" in kinds else KINDS.get(min(kinds), "fixed parameter")
            out.append(Difference(kind, name, [shown for _, _, shown in entries]))
    return out


def _value_table(rows: list[dict[str, Any]]) -> dict[str, tuple[str, str, str]]:
    """Name → (kind, exact key in SI, text in the scene's units) of a run's parameters,
    settings and factors."""
    grouped: dict[str, tuple[str, list[Any], str, str]] = {}
    for row in rows:
        if row["kind"] == "response":
            continue
        value = row["num"] if row["num"] is not None else row["text"]
        entry: tuple[str, list[Any], str, str] = (
            row["kind"],
            [],
            row["units"],
            row.get("declared_units") or row["units"],
        )
        grouped.setdefault(row["name"], entry)[1].append(value)
    out = {}
    for name, (kind, levels, units, declared) in grouped.items():
        one = levels if kind == "factor" else levels[0]
        exact = _exact(one) + _suffix(units)
        if declared in UNITS and all(isinstance(v, float) for v in levels):
            shown = [from_si(v, declared) for v in levels]
            out[name] = (
                kind,
                exact,
                short(shown if kind == "factor" else shown[0]) + _suffix(declared),
            )
        else:
            out[name] = (kind, exact, short(one) + _suffix(units))
    return out


def _suffix(units: str | None) -> str:
    return f" {units}" if units not in ("", "1", None) else ""


def code_differences(records: list[dict[str, Any]]) -> list[Difference]:
    """Commit, engine and scene code that differ (sources by hash, named when changed)."""
    out = []
    commits = [
        f"{x.get('git_commit') or 'none'}"[:10] + (" +dirty" if x.get("git_dirty") else "")
        for x in records
    ]
    if len(set(commits)) > 1:
        out.append(Difference("code", "commit", commits))
    codes = [x.get("code", {}) for x in records]
    engines = [c.get("engine", {}) for c in codes]
    scenes = [c.get("scene", {}) for c in codes]
    names = "/".join(sorted({str(s.get("scene")) for s in scenes if s}))
    engine_words = [f"{e.get('distribution', '?')} {e.get('version', '?')}" for e in engines]
    ids = [str(x.get("run_id", "?")) for x in records]
    out += _code_difference("engine", engines, engine_words, ids)
    if any(s.get("plugin") for s in scenes):  # a built-in scene's code is the engine's
        words = [describe_scene_code(s).rsplit(", source", 1)[0] for s in scenes]
        out += _code_difference(f"scene {names}", scenes, words, ids)
    return out


def _code_difference(
    what: str, entries: list[dict[str, Any]], words: list[str], ids: list[str]
) -> list[Difference]:
    """One difference when the distributions, versions or source hashes differ; with more
    than two runs its note names the runs (``ids``) whose source differs from the first's."""
    hashes = [str(e.get("source_sha256", ""))[:8] or MISSING for e in entries]
    if len(set(words)) == 1 and len(set(hashes)) == 1:
        return []
    note = detail = None
    if len(set(hashes)) > 1:
        note = "source changed"
        if len(hashes) == 2:
            note += f" ({' → '.join(hashes)})"
        else:
            changed = [
                f"{i} {h}" for i, h in zip(ids[1:], hashes[1:], strict=True) if h != hashes[0]
            ]
            note += f" in {', '.join(changed)} (reference {ids[0]} {hashes[0]})"
        detail = [f"source {h}" for h in hashes]
    return [Difference("code", what, words, note or "", detail or [])]


def version_differences(records: list[dict[str, Any]]) -> list[Difference]:
    versions = [x.get("versions", {}) for x in records]
    names = list(dict.fromkeys(k for v in versions for k in v))
    return [
        Difference("version", n, [str(v.get(n, MISSING)) for v in versions])
        for n in names
        if len({str(v.get(n, MISSING)) for v in versions}) > 1
    ]


def flatten(table: dict[str, Any], prefix: str = "") -> dict[str, Any]:
    out: dict[str, Any] = {}
    for key, value in table.items():
        name = f"{prefix}{key}"
        if isinstance(value, dict):
            out |= flatten(value, f"{name}.")
        else:
            out[name] = value
    return out


def _exact(value: Any) -> str:
    """A value as text to 12 significant digits: what tells values apart (the round-off of a
    unit conversion is no difference)."""
    if isinstance(value, list):
        return "[" + ", ".join(_exact(v) for v in value) + "]"
    return f"{value:.12g}" if isinstance(value, float) else str(value)


def short(value: Any) -> str:
    """A value as a person reads it: numbers to 6 significant digits."""
    if isinstance(value, float | np.floating):
        return f"{float(value):.6g}"
    if isinstance(value, list):
        return "[" + ", ".join(short(v) for v in value) + "]"
    if isinstance(value, np.generic):
        return str(value.item())
    return str(value)
