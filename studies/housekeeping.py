"""Remove runs: the folder and every registry row together, never one without the other.

The folder is first renamed to ``<run-id>.removing`` (atomic), then the registry rows are
deleted in one transaction, then the renamed folder is deleted. If the registry cannot be
changed the folder is renamed back; a ``.removing`` folder that a crash left behind holds a run
that is no longer registered, and :func:`collect_garbage` deletes it.
"""

from __future__ import annotations

import datetime as dt
import re
import shutil
from contextlib import closing
from pathlib import Path
from typing import Any

from studies import registry, tracking

REMOVING = ".removing"
AGE = re.compile(r"^\s*(\d+(?:\.\d+)?)\s*([smhdw])\s*$")
UNIT_S = {"s": 1, "m": 60, "h": 3600, "d": 86400, "w": 7 * 86400}
MAX_AGE = dt.timedelta(days=1000 * 365)  # older runs than this cannot exist; datetime ends at 9999


def parse_age(text: str) -> dt.timedelta:
    """``30d``, ``12h``, ``2w``, ``90m``, ``45s`` → a timedelta (ValueError otherwise)."""
    match = AGE.match(text)
    if not match:
        raise ValueError(f"--older-than {text!r}: write a number and s, m, h, d or w, e.g. 30d")
    seconds = float(match[1]) * UNIT_S[match[2]]
    if seconds > MAX_AGE.total_seconds():
        msg = f"--older-than {text.strip()} is more than {MAX_AGE.days // 365} years: give a shorter age"
        raise ValueError(msg)
    return dt.timedelta(seconds=seconds)


def remove_run(outputs: Path, row: dict[str, Any]) -> None:
    """Delete a run's folder and registry rows (ValueError while it is still running)."""
    status, _ = tracking.current_status(row)
    if status == "running":
        raise ValueError(f"run {row['run_id']} is still running: not removed")
    folder = Path(row["folder"])
    trash = folder.with_name(folder.name + REMOVING)
    if folder.exists():
        folder.rename(trash)
    try:
        with closing(registry.connect(outputs)) as con, con:
            registry.delete_run(con, row["run_id"])
    except BaseException:
        if trash.exists():
            trash.rename(folder)
        raise
    shutil.rmtree(trash, ignore_errors=True)


def collect_garbage(
    outputs: Path, older_than: dt.timedelta, keep_tagged: bool, dry_run: bool = False
) -> list[dict[str, Any]]:
    """Remove the runs that started more than ``older_than`` ago (not running ones; not tagged
    ones with ``keep_tagged``) and leftover ``.removing`` folders; return the removed rows."""
    cutoff = dt.datetime.now(dt.UTC) - older_than
    tags, _ = registry.tags_and_notes(outputs)
    chosen = []
    for row in tracking.list_runs(outputs):
        started = dt.datetime.fromisoformat(row["started"]) if row["started"] else cutoff
        if started >= cutoff or (keep_tagged and row["run_id"] in tags):
            continue
        if tracking.current_status(row)[0] == "running":
            continue
        chosen.append(row)
    if dry_run:
        return chosen
    for row in chosen:
        remove_run(outputs, row)
    for leftover in outputs.glob(f"*/*{REMOVING}"):
        shutil.rmtree(leftover, ignore_errors=True)
    return chosen
