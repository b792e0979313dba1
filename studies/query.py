"""Find runs: filters on the registry's rows and indexed values, output as text, JSON or CSV.

A ``--where`` expression is ``NAME OP VALUE`` with OP one of ``== = != < <= > >=``. NAME is a
registry column (study, scene, design, runs, git_commit, compile_s, run_s, started, finished),
a fixed parameter or setting (its value), a factor (true when any of its levels satisfies it)
or a response summary ``<response>.min|mean|max``. A number compares numerically, anything else
as text (quotes optional).
"""

from __future__ import annotations

import csv
import datetime as dt
import io
import json
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from studies import registry, tracking
from studies.reindex import reconcile

EXPRESSION = re.compile(r"^\s*([A-Za-z_][\w.]*)\s*(==|=|!=|<=|>=|<|>)\s*([^<>=!\s].*?)\s*$")
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
TABLE_COLUMNS = ("run_id", "study", "status", "runs", "compile_s", "run_s", "git_commit", "tags")


@dataclass(frozen=True)
class Condition:
    name: str
    op: str
    value: str | float

    def sql(self, known: dict[str, str]) -> tuple[str, list[Any]]:
        """A WHERE clause on ``runs`` and its arguments (``known``: value name → kind)."""
        op = "=" if self.op == "==" else self.op
        if self.name in COLUMNS:
            return f"runs.{self.name} {op} ?", [self.value]
        kind = known.get(self.name)
        if kind is None:
            responses = {n.rsplit(".", 1)[0] for n, k in known.items() if k == "response"}
            if self.name in responses:
                msg = f"{self.name} is a response: filter on {self.name}.min, .mean or .max"
            else:
                names = sorted({*COLUMNS, *known})
                msg = (
                    f"--where names {self.name!r}, which no run records (known: {', '.join(names)})"
                )
            raise ValueError(msg)
        field = "num" if isinstance(self.value, float) else "text"
        return (
            (
                "EXISTS (SELECT 1 FROM run_values v WHERE v.run_id = runs.run_id AND v.name = ? "
                f"AND v.{field} {op} ?)"
            ),
            [self.name, self.value],
        )


def parse_condition(text: str) -> Condition:
    """``cam_speed>=5000`` → Condition (ValueError with the accepted form otherwise)."""
    match = EXPRESSION.match(text)
    if not match:
        msg = (
            f"cannot read --where {text!r}: write NAME OP VALUE with OP one of "
            '== != < <= > >=, e.g. "cam_speed>=5000" or "max_jerk.max<900"'
        )
        raise ValueError(msg)
    name, op, raw = match.groups()
    raw = raw.strip("'\"")
    try:
        value: str | float = float(raw)
    except ValueError:
        value = raw
    return Condition(name, op, value)


def since_date(text: str) -> str:
    """An ISO date or time → the ISO string the registry's ``started`` is compared with."""
    try:
        when = dt.datetime.fromisoformat(text)
    except ValueError:
        raise ValueError(f"--since {text!r} is not a date: write e.g. 2026-11-01") from None
    if when.tzinfo is None:
        when = when.replace(tzinfo=dt.UTC)
    return when.isoformat(timespec="seconds")


def find_runs(
    outputs: Path,
    study: str | None = None,
    scene: str | None = None,
    status: str | None = None,
    since: str | None = None,
    where: list[str] | None = None,
    tag: str | None = None,
) -> list[dict[str, Any]]:
    """Registry rows that satisfy every filter, newest first, each with its current status,
    tags, notes and folder under ``outputs``."""
    reconcile(outputs)
    if not (outputs / registry.REGISTRY).exists():
        return []
    conditions = [parse_condition(w) for w in where or []]
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
    with registry.connection(outputs) as con:
        known = dict(con.execute("SELECT DISTINCT name, kind FROM run_values").fetchall())
        for c in conditions:
            clause, extra = c.sql(known)
            clauses.append(clause)
            args += extra
        query = "SELECT * FROM runs" + (" WHERE " + " AND ".join(clauses) if clauses else "")
        rows = [dict(r) for r in con.execute(query + " ORDER BY started DESC, run_id DESC", args)]
    tags, notes = registry.tags_and_notes(outputs)
    out = []
    for row in rows:
        row["folder"] = str(registry.folder_of(outputs, row))
        row["status"], _ = tracking.current_status(row)
        if status and row["status"] != status:
            continue
        row["tags"] = tags.get(row["run_id"], [])
        row["notes"] = notes.get(row["run_id"], [])
        out.append(row)
    return out


def with_values(outputs: Path, rows: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """Rows with their parameters, settings, factor levels and response summaries."""
    for row in rows:
        values: dict[str, dict[str, Any]] = {
            "parameters": {},
            "settings": {},
            "factors": {},
            "responses": {},
        }
        for v in registry.run_values(outputs, row["run_id"]):
            value = v["num"] if v["num"] is not None else v["text"]
            if v["kind"] == "factor":
                values["factors"].setdefault(v["name"], []).append(value)
            elif v["kind"] == "response":
                name, summary = v["name"].rsplit(".", 1)
                entry = values["responses"].setdefault(name, {"units": v["units"]})
                entry[summary] = value
            else:
                values[f"{v['kind']}s"][v["name"]] = value
        row.update(values)
    return rows


def as_json(rows: list[dict[str, Any]]) -> str:
    return json.dumps(rows, indent=2, default=str)


def as_csv(rows: list[dict[str, Any]]) -> str:
    """One line per run: the registry columns, tags, notes, then every value flattened
    (factors as their levels joined by ``|``, responses as ``<name>.<summary> [units]``)."""
    flat = []
    for row in rows:
        line = {k: v for k, v in row.items() if not isinstance(v, dict | list)}
        line["tags"] = " ".join(row.get("tags", []))
        line["notes"] = " | ".join(row.get("notes", []))
        line |= row.get("parameters", {}) | row.get("settings", {})
        line |= {k: "|".join(map(str, v)) for k, v in row.get("factors", {}).items()}
        for name, entry in row.get("responses", {}).items():
            units = f" [{entry['units']}]" if entry.get("units") not in ("", "1", None) else ""
            line |= {f"{name}.{s}{units}": entry.get(s) for s in registry.SUMMARIES}
        flat.append(line)
    header = list(dict.fromkeys(k for line in flat for k in line))
    buffer = io.StringIO()
    writer = csv.DictWriter(buffer, header, lineterminator="\n")
    writer.writeheader()
    writer.writerows(flat)
    return buffer.getvalue()


def as_table(rows: list[dict[str, Any]]) -> str:
    lines = [
        (
            f"{'run id':<30} {'study':<20} {'status':<11} {'runs':>6} {'compile s':>10} "
            f"{'run s':>8}  {'commit':<16} tags"
        )
    ]
    for r in rows:
        dirty = "+dirty" if r["git_dirty"] else ""
        lines.append(
            f"{r['run_id']:<30} {r['study']:<20} {r['status']:<11} {r['runs']:>6} "
            f"{_num(r['compile_s']):>10} {_num(r['run_s']):>8}  "
            f"{(r['git_commit'] or '')[:10] + dirty:<16} {' '.join(r['tags'])}"
        )
    return "\n".join(lines)


def _num(x: float | None) -> str:
    return "-" if x is None else f"{x:.3f}"
