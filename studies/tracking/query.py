"""Find runs: filters on the registry's rows and indexed values, output as text, JSON or CSV.

A ``--where`` expression is ``NAME OP VALUE [UNIT]`` with OP one of ``== = != < <= > >=``.
NAME is a registry column (study, scene, design, status, runs, git_commit, compile_s, run_s,
started, finished), a parameter (fixed or left at its default) or setting (its value), a factor
(true when any of its levels satisfies it) or a response summary ``<response>.min|mean|max``.
A number is in the units the scene declares for NAME (those of ``python -m studies scenes``,
whatever units each study file wrote) unless a unit follows it (``bore>=80 mm``; one that
does not measure what NAME measures, ``cam_speed>=80 mm``, is refused); values are compared in
SI, ``==`` to 12 significant digits. Each run is compared in its own scene's units: where two
scenes declare NAME in different units a bare number is read in each run's, and a run whose
units a written unit does not convert to does not match (:func:`find_runs` says how many runs
that skipped). Anything else compares as text (quotes optional).
"""

from __future__ import annotations

import csv
import datetime as dt
import io
import json
import re
from dataclasses import dataclass
from typing import Any

from studies.common.errors import StudyError
from studies.common.units import UNITS, compatible_units, from_si, to_si
from studies.tracking import registry
from studies.tracking.housekeeping import parse_age
from studies.tracking.liveness import current_status
from studies.tracking.store import RunStore

EXPRESSION = re.compile(r"^\s*([A-Za-z_][\w.]*)\s*(==|=|!=|<=|>=|<|>)\s*([^<>=!\s].*?)\s*$")
NUMBER = re.compile(r"^([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*(\S*)$")
SAME = 1e-12  # relative difference below which == holds (the round-off of a unit conversion)
STATUS = "status"  # a run's status now (liveness), not the registry's last word: filtered here
COLUMNS = {
    "study",
    "scene",
    "design",
    "runs",
    "git_commit",
    "compile_s",
    "run_s",
    "started",
    "finished",
}
DATES = ("started", "finished")  # ISO 8601 in the registry: ordered as text
TABLE_COLUMNS = ("run_id", "study", "status", "runs", "compile_s", "run_s", "git_commit", "tags")


@dataclass(frozen=True)
class Condition:
    name: str
    op: str
    value: str | float
    units: str = ""  # of a number, when written

    def sql(self, known: dict[str, tuple[str, list[str]]]) -> tuple[str, list[Any]]:
        """A WHERE clause on ``runs`` and its arguments (``known``: value name → (kind, the
        units the scenes of the runs declare for it)). A number is compared, in each run, in
        SI of the units its scene declares: a bare number is in those units; a run whose
        units the number's do not convert to does not match (:meth:`unconvertible`)."""
        op = "=" if self.op == "==" else self.op
        if self.name in COLUMNS:
            return f"runs.{self.name} {op} ?", [self.value]
        kind, declared = known.get(self.name, ("", []))
        if not kind:
            responses = {n.rsplit(".", 1)[0] for n, (k, _) in known.items() if k == "response"}
            if self.name in responses:
                msg = f"{self.name} is a response: filter on {self.name}.min, .mean or .max"
            else:
                names = sorted({*COLUMNS, STATUS, *known})
                msg = (
                    f"--where names {self.name!r}, which no run records (known: {', '.join(names)})"
                )
            raise StudyError(msg)
        head = "EXISTS (SELECT 1 FROM run_values v WHERE v.run_id = runs.run_id AND v.name = ? "
        if not isinstance(self.value, float):
            if kind == "response" or op not in ("=", "!="):
                msg = (
                    f"--where {self.name}{self.op}{self.value!r}: {self.value!r} is not a number"
                    + (" (a response's summary is a number)" if kind == "response" else "")
                    + "; < <= > >= compare numbers, text is compared with == or !="
                )
                raise StudyError(msg)
            return head + f"AND v.text {op} ?)", [self.name, self.value]
        away = self.unconvertible(declared)
        convertible = [d for d in declared if d not in away]
        if not convertible:
            msg = (
                f"--where {self.name}: {self.units!r} measures {UNITS[self.units].dimension}, "
                f"{self.name} is in {' or '.join(map(repr, away))} (use one of "
                f"{', '.join(dict.fromkeys(u for a in away for u in compatible_units(a)))})"
            )
            raise StudyError(msg)
        tests, args = [], []
        for units in convertible:
            si = self.si(units)
            if op in ("=", "!="):
                near = "ABS(v.num - ?) <= ? * ABS(?)"
                tests.append(near if op == "=" else f"NOT ({near})")
                args += [units, si, SAME, si]
            else:
                tests.append(f"v.num {op} ?")
                args += [units, si]
        either = " OR ".join(f"(IFNULL(v.declared_units, '') = ? AND {t})" for t in tests)
        return head + f"AND ({either}))", [self.name, *args]

    def unconvertible(self, declared: list[str]) -> list[str]:
        """Those of the units ``declared`` for the name that the number's written units do
        not convert to (``m/s^2`` and ``mm/rad^2``, say)."""
        if not isinstance(self.value, float) or self.units not in UNITS:
            return []
        written = UNITS[self.units].dimension
        return [d for d in declared if d in UNITS and UNITS[d].dimension != written]

    def si(self, declared: str) -> float:
        """The number in SI: in its own units if written, else in the scene's (``declared``)."""
        assert isinstance(self.value, float)
        units = self.units or declared
        return to_si(self.value, units) if units in UNITS else self.value


def parse_condition(text: str) -> Condition:
    """``cam_speed>=5000`` → Condition (ValueError with the accepted form otherwise)."""
    match = EXPRESSION.match(text)
    if not match:
        msg = (
            f"cannot read --where {text!r}: write NAME OP VALUE with OP one of "
            '== != < <= > >=, e.g. "cam_speed>=5000" or "max_jerk.max<900"'
        )
        raise StudyError(msg)
    name, op, raw = match.groups()
    raw = raw.strip("'\"")
    if name in DATES:  # an ISO date or time, compared as text: 2026-12-07 < 2026-12-07T10:00
        return Condition(name, op, raw)
    number = NUMBER.match(raw)
    if number is None:
        return Condition(name, op, raw)
    value, units = number.groups()
    if units and units not in UNITS:
        msg = (
            f'--where {text!r}: unknown units {units!r} (write e.g. "bore>=80 mm"; '
            "`python -m studies scenes` lists each name's units)"
        )
        raise StudyError(msg)
    return Condition(name, op, float(value), units)


def since_date(text: str) -> str:
    """An ISO date or time, or an age (``30d``, ``12h``, ``2w``) → the ISO string the
    registry's ``started`` is compared with."""
    try:
        when = dt.datetime.fromisoformat(text)
    except ValueError:
        try:
            when = dt.datetime.now(dt.UTC) - parse_age(text)
        except (ValueError, OverflowError):
            msg = f"--since {text!r} is not a date or an age: write e.g. 2026-11-01 or 30d"
            raise StudyError(msg) from None
    if when.tzinfo is None:
        when = when.replace(tzinfo=dt.UTC)
    return when.isoformat(timespec="seconds")


def find_runs(
    store: RunStore,
    study: str | None = None,
    scene: str | None = None,
    status: str | None = None,
    since: str | None = None,
    where: list[str] | None = None,
    tag: str | None = None,
) -> tuple[list[dict[str, Any]], list[str]]:
    """Registry rows of ``store`` that satisfy every filter, newest first, each with its
    current status, tags, notes and folder under the outputs root; and a line for each
    ``where`` whose number left out runs that meet every other filter because their scene's
    units for its name are not those the number's convert to."""
    store.reconcile()
    if not store.registry.exists():
        return [], []
    conditions = [parse_condition(w) for w in where or []]
    current = [c for c in conditions if c.name == STATUS]
    conditions = [c for c in conditions if c.name != STATUS]
    for c in current:
        if c.op not in ("==", "=", "!="):
            raise StudyError(f"--where status: use == or != (e.g. status==finished), not {c.op}")
    clauses: list[str] = []
    args: list[Any] = []
    for column, value in (("study", study), ("scene", scene)):
        if value:
            clauses.append(f"runs.{column} = ?")
            args.append(value)
    if since:
        clauses.append("runs.started >= ?")
        args.append(since_date(since))
    if tag:
        clauses.append("runs.run_id IN (SELECT run_id FROM tags WHERE tag = ?)")
        args.append(tag)
    skips: list[tuple[Condition, list[str]]] = []  # conditions that leave runs out by units
    flags, flag_args = "", []
    with store.connection() as con:
        known: dict[str, tuple[str, list[str]]] = {}
        for r in con.execute("SELECT DISTINCT name, kind, declared_units FROM run_values"):
            known.setdefault(r["name"], (r["kind"], []))[1].append(r["declared_units"] or "")
        for c in conditions:
            clause, extra = c.sql(known)
            away = c.unconvertible(known.get(c.name, ("", []))[1])
            if away:
                other_units = (
                    "EXISTS (SELECT 1 FROM run_values v WHERE v.run_id = runs.run_id AND "
                    f"v.name = ? AND v.declared_units IN ({', '.join('?' * len(away))}))"
                )
                clause, extra = f"({clause} OR {other_units})", [*extra, c.name, *away]
                flags += f", {other_units} AS skipped_{len(skips)}"
                flag_args += [c.name, *away]
                skips.append((c, away))
            clauses.append(clause)
            args += extra
        query = f"SELECT runs.*{flags} FROM runs" + (
            " WHERE " + " AND ".join(clauses) if clauses else ""
        )
        order = " ORDER BY started DESC, run_id DESC"
        rows = [dict(r) for r in con.execute(query + order, [*flag_args, *args])]
    tags, notes = store.tags_and_notes()
    out = []
    left_out = [0] * len(skips)
    for row in rows:
        skipped = [bool(row.pop(f"skipped_{i}")) for i in range(len(skips))]
        row["folder"] = str(store.folder(row))
        row["status"], _ = current_status(row)
        if status and row["status"] != status:
            continue
        if any((row["status"] == str(c.value)) != (c.op != "!=") for c in current):
            continue
        if any(skipped):
            left_out = [n + s for n, s in zip(left_out, skipped, strict=True)]
            continue
        row["tags"] = tags.get(row["run_id"], [])
        row["notes"] = notes.get(row["run_id"], [])
        out.append(row)
    said = [
        f"skipped {n} run{'s' * (n != 1)} whose {c.name} is in {' or '.join(map(repr, away))}: "
        f"{c.units!r} measures {UNITS[c.units].dimension}"
        for (c, away), n in zip(skips, left_out, strict=True)
        if n
    ]
    return out, said


def with_values(store: RunStore, rows: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """Rows with their parameters (fixed, and left at their defaults), settings, factor levels
    and response summaries, in SI; ``units`` maps each name to its SI unit and
    ``declared_units`` to the unit its scene declares."""
    for row in rows:
        values: dict[str, dict[str, Any]] = {
            "parameters": {},
            "defaults": {},
            "settings": {},
            "factors": {},
            "responses": {},
            "units": {},
            "declared_units": {},
        }
        for v in store.run_values(row["run_id"]):
            value = v["num"] if v["num"] is not None else v["text"]
            name = v["name"]
            if v["kind"] == "factor":
                values["factors"].setdefault(name, []).append(value)
            elif v["kind"] == "response":
                name, summary = name.rsplit(".", 1)
                values["responses"].setdefault(name, {"units": v["units"]})[summary] = value
            else:
                values[f"{v['kind']}s"][name] = value
            values["units"][name] = v["units"] or ""
            values["declared_units"][name] = v["declared_units"] or v["units"] or ""
        row.update(values)
    return rows


def as_json(rows: list[dict[str, Any]]) -> str:
    return json.dumps(rows, indent=2, default=str)


def as_csv(rows: list[dict[str, Any]]) -> str:
    """One line per run: the registry columns, tags, notes, then every value flattened, in SI
    with the unit in the column name (``bore [m]``; factors as their levels joined by ``|``,
    responses as ``<name>.<summary> [units]``)."""
    flat = []
    for row in rows:
        line = {k: v for k, v in row.items() if not isinstance(v, dict | list)}
        line["tags"] = " ".join(row.get("tags", []))
        line["notes"] = " | ".join(row.get("notes", []))
        units = row.get("units", {})
        for section in ("parameters", "defaults", "settings"):
            line |= {_header(k, units.get(k)): v for k, v in row.get(section, {}).items()}
        line |= {
            _header(k, units.get(k)): "|".join(map(str, v))
            for k, v in row.get("factors", {}).items()
        }
        for name, entry in row.get("responses", {}).items():
            line |= {
                _header(f"{name}.{s}", entry.get("units")): entry.get(s) for s in registry.SUMMARIES
            }
        flat.append(line)
    header = list(dict.fromkeys(k for line in flat for k in line))
    buffer = io.StringIO()
    writer = csv.DictWriter(buffer, header, lineterminator="\n")
    writer.writeheader()
    writer.writerows(flat)
    return buffer.getvalue()


def _header(name: str, units: str | None) -> str:
    return f"{name} [{units}]" if units not in ("", "1", None) else name


def as_table(rows: list[dict[str, Any]], columns: list[str] | None = None) -> str:
    """The runs as a text table; ``columns`` adds values (``bore``, ``cam_speed`` for a
    factor's levels, ``max_jerk.max``) in the units the scene declares, named in the header
    or, where the listed runs' scenes declare different units, in each cell (rows need
    :func:`with_values`)."""
    columns = columns or []
    declared = {c: {_locate(r, c)[1] for r in rows} - {""} for c in columns}
    mixed = {c for c in columns if len(declared[c]) > 1}  # scenes declaring other units
    shown = [[_column(r, c, c in mixed) for c in columns] for r in rows]
    heads = [_header(c, "" if c in mixed else next(iter(declared[c]), "")) for c in columns]
    widths = [max([len(h)] + [len(v[i]) for v in shown]) for i, h in enumerate(heads)]
    extra = "".join(f" {h:>{w}}" for h, w in zip(heads, widths, strict=True))
    lines = [
        (
            f"{'run id':<30} {'study':<20} {'status':<11} {'runs':>6} {'compile s':>10} "
            f"{'run s':>8}  {'commit':<16}{extra} tags"
        )
    ]
    for r, values in zip(rows, shown, strict=True):
        dirty = "+dirty" if r["git_dirty"] else ""
        cells = "".join(f" {v:>{w}}" for v, w in zip(values, widths, strict=True))
        lines.append(
            f"{r['run_id']:<30} {r['study']:<20} {r['status']:<11} {r['runs']:>6} "
            f"{_num(r['compile_s']):>10} {_num(r['run_s']):>8}  "
            f"{(r['git_commit'] or 'none')[:10] + dirty:<16}{cells} {' '.join(r['tags'])}"
        )
    return "\n".join(lines)


def check_columns(rows: list[dict[str, Any]], columns: list[str]) -> None:
    """ValueError naming a ``--columns`` name that no listed run records."""
    known = {n for r in rows for n in r.get("declared_units", {})}
    unknown = [c for c in columns if c not in known and c.rsplit(".", 1)[0] not in known]
    if rows and unknown:
        msg = (
            f"--columns names {', '.join(map(repr, unknown))}, which no listed run records "
            f"(known: {', '.join(sorted(known))})"
        )
        raise StudyError(msg)


def _column(row: dict[str, Any], column: str, with_units: bool = False) -> str:
    """One value of a run in the unit its scene declares ("-" when the run has none), that
    unit written after it ``with_units`` (where the listed runs' scenes declare different
    units for the column, its header has none)."""
    value, declared = _locate(row, column)
    text = _shown(value, declared)
    return f"{text} {declared}" if with_units and value is not None and declared else text


def _locate(row: dict[str, Any], column: str) -> tuple[Any, str]:
    """(value in SI, the scene's unit) of a column of a run; a response summary is
    ``<response>.<summary>``."""
    name, _, summary = column.rpartition(".")
    responses = row.get("responses", {})
    if name in responses:
        value = responses[name].get(summary)
    else:
        name = column
        sections = ("factors", "parameters", "defaults", "settings")
        value = next((row[s][name] for s in sections if name in row.get(s, {})), None)
    return value, row.get("declared_units", {}).get(name, "")


def _shown(value: Any, declared: str) -> str:
    if value is None:
        return "-"
    if isinstance(value, list):
        return "|".join(_shown(v, declared) for v in value)
    if isinstance(value, float):
        return f"{from_si(value, declared) if declared in UNITS else value:.6g}"
    return str(value)


def _num(x: float | None) -> str:
    return "-" if x is None else f"{x:.3f}"
