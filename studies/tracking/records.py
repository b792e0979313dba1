"""Run records: what ``run.json`` holds, how run ids are made and where outputs go by default.

    outputs/
      registry.sqlite              one row per run, its values, tags and notes (studies.tracking.registry)
      .trash/                      removed runs (studies.tracking.trash)
      <study>/<run-id>/
        study.toml                 exact copy of the definition that ran
        labels.json                its tags and notes (studies.common.labels)
        run.json                   id, status, code (engine and scene distributions, versions
                                   and source hashes), git commit + dirty flag, versions,
                                   host, start/end, seconds per phase, accuracy settings,
                                   the working folder it started in (relative input paths,
                                   e.g. a lift table, are read from it, on a resume too)
        results.nc                 the labelled results (see studies.run.results)
        analysis.txt               range analysis and ANOVA tables
        *.png                      figures

The run id is ``<UTC timestamp>-<6 hex digits of the definition hash>``, so ids sort by time
and runs of the same definition share a suffix. The folders are the truth and the registry
their index; :class:`studies.tracking.store.RunStore` keeps both.
"""

from __future__ import annotations

import contextlib
import datetime as dt
import hashlib
import json
import os
import threading
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

from studies.common.bounded_files import TABLE_FILE_BYTES, InputFileError, read_bounded_bytes
from studies.run.runner import DEFAULT_CHUNK_SIZE

OUTPUTS_VARIABLE = "ENGINE_STUDIES_OUTPUTS"
_WRITING = threading.Lock()  # run.json is written by the run and by its heartbeat thread


@dataclass
class RunRecord:
    """What ``run.json`` holds and what the registry indexes."""

    run_id: str
    study: str
    scene: str
    design: str
    runs: int
    status: str
    started: str
    git_commit: str
    git_dirty: bool
    definition_sha256: str
    folder: str
    versions: dict[str, str] = field(default_factory=dict)
    host: dict[str, str] = field(default_factory=dict)
    settings: dict[str, Any] = field(default_factory=dict)
    finished: str = ""
    timings: dict[str, float] = field(default_factory=dict)
    error: str = ""
    chunk_size: int = DEFAULT_CHUNK_SIZE
    pid: int = 0
    heartbeat: str = ""
    points_without_value: int = 0
    code: dict[str, Any] = field(default_factory=dict)
    code_sha256: str = ""
    warnings: list[str] = field(default_factory=list)  # e.g. a figure that could not be drawn
    workdir: str = ""  # the working folder at the start ("": recorded before it was)

    def write(self) -> None:
        """Write ``run.json`` (under a temporary name renamed into place: never half a file;
        a write that fails, on a full disk say, removes the temporary file and names run.json)."""
        path = Path(self.folder) / "run.json"
        tmp = path.with_name("run.json.writing")
        with _WRITING:
            text = json.dumps(asdict(self), indent=2, default=str) + "\n"
            try:
                tmp.write_text(text, encoding="utf-8")
                tmp.replace(path)
            except OSError as exc:
                with contextlib.suppress(OSError):
                    tmp.unlink(missing_ok=True)
                exc.filename = exc.filename or str(path)
                raise

    def beat(self) -> None:
        """Record that the run is alive now (the heartbeat thread calls this)."""
        self.heartbeat = dt.datetime.now(dt.UTC).isoformat(timespec="milliseconds")
        self.write()


def default_outputs() -> Path:
    """Where runs are recorded when no ``--outputs`` is given, the same from any folder: the
    environment variable ``ENGINE_STUDIES_OUTPUTS``, else the ``outputs/`` folder of this
    checkout (beside ``studies/``), else ``./outputs`` (an installed package)."""
    chosen = os.environ.get(OUTPUTS_VARIABLE)
    if chosen:
        return Path(chosen).expanduser().resolve()
    checkout = Path(__file__).resolve().parents[2] / "outputs"
    if (checkout / "README.md").exists():
        return checkout
    return Path("outputs").resolve()


def now() -> str:
    return dt.datetime.now(dt.UTC).isoformat(timespec="seconds")


def definition_hash(text: str, inputs: tuple[tuple[Path, Path], ...] = ()) -> str:
    """The SHA-256 of a study's text and of the contents of every file it reads (``inputs``,
    e.g. a lift table: its path as written, and the file read): the cache key, so a changed
    table is never served from a stale run, wherever a relative path was read from. With no
    input files it is the hash of the text alone."""
    digest = hashlib.sha256(text.encode("utf-8"))
    for written, path in inputs:
        digest.update(b"\0" + str(written).encode("utf-8") + b"\0")
        try:
            digest.update(read_bounded_bytes(path, "input file", TABLE_FILE_BYTES))
        except InputFileError as exc:  # planning reports the unreadable file; the key differs
            digest.update(f"unreadable: {exc}".encode())
    return digest.hexdigest()


def new_run_id(text: str) -> str:
    stamp = dt.datetime.now(dt.UTC).strftime("%Y%m%dT%H%M%S%f")[:-3]
    return f"{stamp}-{definition_hash(text)[:6]}"
