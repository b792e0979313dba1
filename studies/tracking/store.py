"""Run records: one folder per run and a row per run in a local SQLite registry.

    outputs/
      registry.sqlite              one row per run, its values, tags and notes (studies.tracking.registry)
      .trash/                      removed runs (studies.tracking.trash)
      <study>/<run-id>/
        study.toml                 exact copy of the definition that ran
        labels.json                its tags and notes (studies.common.labels)
        run.json                   id, status, code (engine and scene distributions, versions
                                   and source hashes), git commit + dirty flag, versions,
                                   host, start/end, compile vs run time, accuracy settings
        results.nc                 the labelled results (see studies.run.results)
        analysis.txt               range analysis and ANOVA tables
        *.png                      figures

The run id is ``<UTC timestamp>-<6 hex digits of the definition hash>``, so ids sort by time
and runs of the same definition share a suffix. The folders are the truth and the registry
their index: listing or looking up runs first registers what the registry misses
(:func:`studies.tracking.reindex.reconcile`), and rows address folders relative to the outputs root.
"""

from __future__ import annotations

import datetime as dt
import hashlib
import json
import os
import platform
import threading
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

from studies.common.bounded_files import TABLE_FILE_BYTES, InputFileError, read_bounded_bytes
from studies.common.errors import RunNotFound
from studies.run.runner import DEFAULT_CHUNK_SIZE
from studies.tracking import registry, trash
from studies.tracking.liveness import is_locked
from studies.tracking.reindex import reconcile

OUTPUTS_VARIABLE = "ENGINE_STUDIES_OUTPUTS"
HEARTBEAT_S = 5.0  # a live run's heartbeat thread rewrites run.json this often
STALE_S = 120.0  # a heartbeat older than this marks a run on another host as interrupted
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

    def write(self) -> None:
        """Write ``run.json`` (under a temporary name renamed into place: never half a file)."""
        path = Path(self.folder) / "run.json"
        tmp = path.with_name("run.json.writing")
        with _WRITING:
            text = json.dumps(asdict(self), indent=2, default=str) + "\n"
            tmp.write_text(text, encoding="utf-8")
            tmp.replace(path)

    def beat(self) -> None:
        """Record that the run is alive now (the heartbeat thread calls this)."""
        self.heartbeat = dt.datetime.now(dt.UTC).isoformat(timespec="milliseconds")
        self.write()


def liveness(record: dict[str, Any], folder: Path | None = None) -> str:
    """The status of a recorded run as it is now: an unfinished run is running while a
    process holds the lock on its ``folder`` (a resume, from its first instant); otherwise a
    "running" run is "interrupted" when its process is gone (same host) or its heartbeat is
    older than ``STALE_S`` (another host)."""
    status = str(record.get("status", ""))
    if status in ("running", "failed") and folder is not None and is_locked(folder):
        return "running"
    if status != "running":
        return status
    same_host = record.get("host", {}).get("node") == platform.node()
    pid = int(record.get("pid") or 0)
    if same_host and pid:
        return "running" if _alive(pid) else "interrupted"
    beat = record.get("heartbeat") or record.get("started", "")
    if not beat:
        return "running"
    age = (dt.datetime.now(dt.UTC) - dt.datetime.fromisoformat(beat)).total_seconds()
    return "interrupted" if age > STALE_S else "running"


def _alive(pid: int) -> bool:
    """Whether a process with this id exists on this host (a zombie counts as gone)."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    try:
        stat = Path(f"/proc/{pid}/stat").read_text(encoding="ascii")
    except OSError:
        return True
    return stat.rsplit(")", 1)[-1].split()[0] != "Z"


def current_status(row: dict[str, Any]) -> tuple[str, dict[str, Any] | None]:
    """A registry row's status now ("missing" when its folder is gone) and its run.json."""
    folder = Path(row["folder"])
    path = folder / "run.json"
    if not path.exists():
        return "missing", None
    record = json.loads(path.read_text(encoding="utf-8"))
    return liveness(record, folder), record


def resume_command(run_id: str, outputs: Path) -> str:
    """The command that finishes an interrupted or failed run."""
    return f"python -m studies run --resume {run_id} --outputs {outputs}"


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


RUN_ID_ATTEMPTS = 1000  # runs of one definition started in the same millisecond


def definition_hash(text: str, inputs: tuple[Path, ...] = ()) -> str:
    """The SHA-256 of a study's text and of the contents of every file it reads (``inputs``,
    e.g. a lift table): the cache key, so a changed table is never served from a stale run.
    With no input files it is the hash of the text alone."""
    digest = hashlib.sha256(text.encode("utf-8"))
    for path in inputs:
        digest.update(b"\0" + str(path).encode("utf-8") + b"\0")
        try:
            digest.update(read_bounded_bytes(path, "input file", TABLE_FILE_BYTES))
        except InputFileError as exc:  # planning reports the unreadable file; the key differs
            digest.update(f"unreadable: {exc}".encode())
    return digest.hexdigest()


def new_run_id(text: str) -> str:
    stamp = dt.datetime.now(dt.UTC).strftime("%Y%m%dT%H%M%S%f")[:-3]
    return f"{stamp}-{definition_hash(text)[:6]}"


def run_folder(outputs: Path, study: str, run_id: str) -> tuple[str, Path]:
    """Create the run's folder; the id gets a suffix ``-1``, ``-2``, … when another run of the
    same definition took it in the same millisecond. Returns the id used and the folder."""
    (outputs / study).mkdir(parents=True, exist_ok=True)
    taken = run_id
    for attempt in range(1, RUN_ID_ATTEMPTS + 1):
        folder = outputs / study / taken
        try:
            folder.mkdir()
        except FileExistsError:
            taken = f"{run_id}-{attempt}"
            continue
        return taken, folder
    msg = f"{RUN_ID_ATTEMPTS} runs of {study!r} took the id {run_id} at once: start fewer together"
    raise FileExistsError(msg)


def register(outputs: Path, record: RunRecord) -> None:
    """Insert or update the registry row of ``record`` (and its queryable values)."""
    row = registry.row_of(asdict(record), f"{record.study}/{record.run_id}")
    with registry.connection(outputs) as con:
        registry.upsert_run(con, row, outputs)


def list_runs(outputs: Path, study: str | None = None) -> list[dict[str, Any]]:
    """Registry rows, newest first (optionally of one study), each with its ``folder`` under
    ``outputs``; what the registry missed is registered first."""
    reconcile(outputs)
    if not (outputs / registry.REGISTRY).exists():
        return []
    with registry.connection(outputs) as con:
        query = "SELECT * FROM runs"
        args: tuple[str, ...] = ()
        if study:
            query += " WHERE study = ?"
            args = (study,)
        rows = [dict(r) for r in con.execute(query + " ORDER BY started DESC, run_id DESC", args)]
    return [r | {"folder": str(registry.folder_of(outputs, r))} for r in rows]


def finished_identical(
    outputs: Path, definition_sha256: str, code_sha256: str
) -> dict[str, Any] | None:
    """The newest finished run of the same definition (study text and input files) computed by
    the same code (engine and scene sources, library versions: :func:`provenance.code_hash`)."""
    for row in list_runs(outputs):
        same = row["definition_sha256"] == definition_sha256 and row["code_sha256"] == code_sha256
        if same and row["status"] == "finished" and (Path(row["folder"]) / "results.nc").exists():
            return row
    return None


def find_run(outputs: Path, run_id: str) -> dict[str, Any] | None:
    """The registry row named by ``run_id``: the id, else a tag, else a unique prefix of the id
    (a tag never hides a run's own id)."""
    rows = list_runs(outputs)
    exact = [r for r in rows if r["run_id"] == run_id]
    if not exact and rows:
        tagged = registry.tagged_run(outputs, run_id)
        exact = [r for r in rows if r["run_id"] == tagged]
    chosen = exact or [r for r in rows if r["run_id"].startswith(run_id)]
    return chosen[0] if len(chosen) == 1 else None


def resolve_run(outputs: Path, ref: str) -> dict[str, Any]:
    """:func:`find_run`, or KeyError with one sentence on what was wrong."""
    row = find_run(outputs, ref)
    if row is not None:
        return row
    matches = [r["run_id"] for r in list_runs(outputs) if r["run_id"].startswith(ref)]
    if matches:
        msg = (
            f"{ref!r} matches {len(matches)} runs ({', '.join(matches[:4])}…): give more of the id"
        )
    elif trash.holds(outputs, ref):
        msg = (
            f"run {ref} is in the trash: bring it back with "
            f"python -m studies restore {ref} --outputs {outputs}"
        )
    else:
        msg = (
            f"no run or tag {ref!r} under {outputs} "
            "(`python -m studies runs` lists the runs and their tags)"
        )
    raise RunNotFound(msg)
