"""A run's tags and notes, kept in its own folder (``labels.json``) as well as in the registry.

The registry is an index that can be rebuilt from the run folders (``studies reindex``); what a
user wrote about a run must survive that, so every tag and note is written here first:

    {"tags": {"baseline": "<UTC time tagged>"}, "notes": [{"written": "<UTC time>", "text": "…"}]}

A tag names one run. When two folders claim one tag (a crash between moving it off one run and
onto another), the later time wins.
"""

from __future__ import annotations

import json
import re
from dataclasses import dataclass, field
from pathlib import Path
from types import TracebackType
from typing import Self

from studies.common.errors import StudyError

LABELS = "labels.json"
TAG = re.compile(r"^[A-Za-z][A-Za-z0-9._+-]{0,63}$")


@dataclass
class Labels:
    tags: dict[str, str] = field(default_factory=dict)  # tag → when it was set
    notes: list[dict[str, str]] = field(default_factory=list)  # {"written", "text"}


def check_tag(tag: str) -> None:
    """ValueError unless ``tag`` is an ASCII letter then up to 63 of them, digits or ``._+-``: run ids
    start with a digit, so a tag can never be taken for an id or an id's prefix."""
    if not TAG.match(tag):
        msg = (
            f"tag {tag!r} is not allowed: a tag starts with an ASCII letter and holds ASCII letters, digits "
            "and . _ + - (at most 64), so that it can never be mistaken for a run id"
        )
        raise StudyError(msg)


def read_labels(folder: Path) -> Labels:
    """The labels of the run in ``folder`` (none when the file is absent or unreadable)."""
    try:
        raw = json.loads((folder / LABELS).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return Labels()
    if not isinstance(raw, dict):
        return Labels()
    tags = raw.get("tags", {})
    notes = raw.get("notes", [])
    return Labels(
        {str(k): str(v) for k, v in tags.items()} if isinstance(tags, dict) else {},
        [
            {"written": str(n.get("written", "")), "text": str(n.get("text", ""))}
            for n in notes
            if isinstance(n, dict)
        ]
        if isinstance(notes, list)
        else [],
    )


def write_labels(folder: Path, labels: Labels) -> None:
    """Write ``labels.json`` whole (a temporary file renamed into place)."""
    path = folder / LABELS
    tmp = path.with_name(LABELS + ".writing")
    text = json.dumps({"tags": labels.tags, "notes": labels.notes}, indent=2) + "\n"
    tmp.write_text(text, encoding="utf-8")
    tmp.replace(path)


def add_tag(folder: Path, tag: str, when: str) -> None:
    labels = read_labels(folder)
    labels.tags[tag] = when
    write_labels(folder, labels)


def drop_tag(folder: Path, tag: str) -> None:
    labels = read_labels(folder)
    if labels.tags.pop(tag, None) is not None:
        write_labels(folder, labels)


def add_note(folder: Path, written: str, text: str) -> None:
    labels = read_labels(folder)
    labels.notes.append({"written": written, "text": text})
    write_labels(folder, labels)


class Undo:
    """Snapshots of labels files (:meth:`save` before changing one), put back as they were
    when the ``with`` block fails: a registry that refuses a tag leaves the folders as before."""

    def __init__(self) -> None:
        self._saved: list[tuple[Path, bytes | None]] = []

    def save(self, folder: Path) -> None:
        path = folder / LABELS
        try:
            self._saved.append((path, path.read_bytes()))
        except FileNotFoundError:
            self._saved.append((path, None))

    def __enter__(self) -> Self:
        return self

    def __exit__(
        self,
        kind: type[BaseException] | None,
        error: BaseException | None,
        trace: TracebackType | None,
    ) -> None:
        if error is None:
            return
        for path, data in reversed(self._saved):
            try:
                if data is None:
                    path.unlink(missing_ok=True)
                else:
                    path.write_bytes(data)
            except OSError:
                continue
