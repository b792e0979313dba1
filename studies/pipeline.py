"""Run a study end to end: plan → evaluate → Dataset → netCDF → analysis → run record.

The run folder and registry row are created only after the study has passed validation, so a
malformed study writes nothing; a run the registry cannot record (damaged, locked, full) removes
its folder again before computing anything. While the run lives it holds the lock on its folder
and a thread keeps its heartbeat fresh (:mod:`studies.tracking.liveness`). Every finished chunk is
checkpointed under ``chunks/`` in the run folder; a run that fails or is interrupted (Ctrl-C)
keeps its folder with ``run.json`` status ``failed`` or ``interrupted`` and the error, and
:func:`resume_run`
(``python -m studies run --resume RUN_ID``) finishes it from its last finished chunk. A run is
finished in one step, the atomic rewrite of ``run.json``; the checkpoints are removed and the
registry updated after it (a registry that missed it catches up on sight).
"""

from __future__ import annotations

import contextlib
import difflib
import errno
import os
import shutil
import sqlite3
import time
from concurrent.futures import Executor
from dataclasses import asdict, dataclass
from pathlib import Path

import xarray as xr

from studies.analysis.analyze import ANALYSIS_NAME
from studies.common.errors import RunNotFound, RunStateError
from studies.common.text_safety import printable_attributes
from studies.define.definition import parse_study
from studies.define.plan import Plan, plan_study
from studies.report.write import write_analysis
from studies.run import provenance
from studies.run.results import open_results
from studies.run.results_writer import ResultsWriter
from studies.run.runner import DEFAULT_CHUNK_SIZE, chunk_cases, chunks, evaluate
from studies.scenes import SceneOutput
from studies.tracking import liveness, records
from studies.tracking.checkpoints import (
    checkpoint_bytes,
    load_chunk,
    read_run_record,
    save_chunk,
)
from studies.tracking.liveness import FolderLock, Heartbeat, lock_folder
from studies.tracking.registry_file import RegistryUnusable
from studies.tracking.store import RunStore

CHECKPOINTS = "chunks"
RESULTS_NAME = "results.nc"
ORIGINAL_STUDY = CHECKPOINTS + "/study.toml"  # the text the checkpoints were computed from
RESUME_WAIT_S = 1.0  # a listing may hold a run folder's lock for an instant; a run holds it


@dataclass(frozen=True)
class RunResult:
    record: records.RunRecord
    dataset: xr.Dataset
    folder: Path
    files: tuple[Path, ...]


def run_study(
    name_or_path: str | Path,
    outputs: Path | None = None,
    chunk_size: int = DEFAULT_CHUNK_SIZE,
    progress: bool = True,
) -> RunResult:
    """Validate and run a study; write its run folder under ``outputs`` (default:
    :func:`studies.tracking.records.default_outputs`)."""
    plan = plan_study(name_or_path)
    return run_plan(plan, outputs, chunk_size, progress)


def run_plan(
    plan: Plan,
    outputs: Path | None = None,
    chunk_size: int = DEFAULT_CHUNK_SIZE,
    progress: bool = True,
    executor: Executor | None = None,
) -> RunResult:
    """Run a validated plan in a new run folder under ``outputs`` (chunks on ``executor``)."""
    store = RunStore((outputs or records.default_outputs()).resolve())
    _check_disk(plan, store.outputs)
    chunk_size = chunk_cases(plan, min(chunk_size, plan.max_chunk))  # fine settings: fewer
    d = plan.definition
    commit, dirty = provenance.git_state()
    code = provenance.code(type(plan.scene))
    run_id, folder = store.run_folder(d.name, records.new_run_id(d.text))
    lock = lock_folder(folder) or FolderLock(None)  # a new folder: no one else holds it
    try:
        (folder / "study.toml").write_text(d.text, encoding="utf-8")
        (folder / CHECKPOINTS).mkdir()
        (folder / ORIGINAL_STUDY).write_text(d.text, encoding="utf-8")
    except BaseException:
        shutil.rmtree(folder, ignore_errors=True)
        lock.release()
        raise
    record = records.RunRecord(
        run_id=run_id,
        study=d.name,
        scene=d.scene,
        design=plan.design.name,
        runs=plan.runs,
        status="running",
        started=records.now(),
        git_commit=commit,
        git_dirty=dirty,
        definition_sha256=records.definition_hash(d.text, d.input_files()),
        code=code,
        code_sha256=provenance.code_hash(code),
        folder=str(folder),
        versions=provenance.versions(),
        host=provenance.host(),
        settings=dict(d.settings),
        chunk_size=chunk_size,
        workdir=str(Path.cwd()),
    )
    try:
        return _execute(plan, store, record, progress, {}, executor, fresh=True)
    finally:
        lock.release()


def _check_disk(plan: Plan, root: Path) -> None:
    """Refuse, before anything is written, a run whose checkpoints alone cannot fit on the
    disk of ``root`` (:func:`studies.tracking.checkpoints.checkpoint_bytes`; results.nc and
    the figures come on top)."""
    needed = checkpoint_bytes(plan)
    existing = next(p for p in (root, *root.parents) if p.exists())
    free = shutil.disk_usage(existing).free
    if needed > free:
        what = (
            f"{plan.definition.name} needs at least {needed / 1e9:.3g} GB of disk for its "
            f"{plan.cases} points' checkpoints ({len(plan.responses)} responses"
            + (f" and {len(plan.definition.curves)} curves" if plan.definition.curves else "")
            + f"), {free / 1e9:.3g} GB are free: free space, choose another --outputs, or "
            "ask for fewer curves or points"
        )
        raise OSError(errno.ENOSPC, what, str(root))


def resume_run(run_id: str, outputs: Path | None = None, progress: bool = True) -> RunResult:
    """Finish an interrupted or failed run from its checkpointed chunks."""
    store = RunStore((outputs or records.default_outputs()).resolve())
    row = store.find_run(run_id)
    if row is None:
        raise RunNotFound(f"no unique run matches {run_id!r} under {store.outputs}")
    folder = Path(row["folder"])
    lock = lock_folder(folder, RESUME_WAIT_S)
    if lock is None:
        msg = (
            f"run {row['run_id']} is being run or resumed by another process (its folder "
            f"{folder} is locked): not resumed"
        )
        raise RunStateError(msg)
    try:
        if not lock.holds(folder):
            raise RunNotFound(f"run {row['run_id']} was moved by another process: not resumed")
        record = read_run_record(folder / "run.json")
        record.folder = str(folder)  # where it was found (a copied tree records another)
        if record.status == "finished":
            raise RunStateError(f"run {record.run_id} is already finished: nothing to resume")
        if liveness.liveness(asdict(record)) == "running":
            msg = (
                f"run {record.run_id} is still running (process {record.pid} on "
                f"{record.host.get('node', '?')}, last heartbeat {record.heartbeat}): not resumed"
            )
            raise RunStateError(msg)
        inputs = Path(record.workdir) if record.workdir else None  # relative paths: as it did
        _check_unchanged(folder / "study.toml", record.definition_sha256, inputs)
        plan = plan_study(folder / "study.toml", folder=inputs)
        code = provenance.code(type(plan.scene))
        if record.code_sha256 and provenance.code_hash(code) != record.code_sha256:
            msg = (
                f"the code changed since run {record.run_id} started (engine or scene source, "
                "or the numba/numpy/scipy versions: `python -m studies show` has what it ran "
                "with). Resuming would mix design points computed by two codes; run the study "
                f"anew: python -m studies run {folder / 'study.toml'}"
            )
            raise RunStateError(msg)
        done = {
            int(path.stem): path
            for path in sorted((folder / CHECKPOINTS).glob("*.npz"))
            if path.stem.isdigit()  # not a temporary file a kill left mid-write
        }
        count = -(-plan.cases // record.chunk_size) if record.chunk_size > 0 else 0
        beyond = sorted(str(done[i]) for i in done if i >= count)
        if record.chunk_size < 1 or beyond:
            msg = (
                f"run {record.run_id}: chunk size {record.chunk_size} gives {count} chunks, but "
                f"{', '.join(beyond[:3]) or 'none'} lie beyond them: delete those and resume"
            )
            raise RunStateError(msg)
    except BaseException:
        lock.release()
        raise
    record.status, record.error = "running", ""
    try:
        return _execute(plan, store, record, progress, done)
    finally:
        lock.release()


def _execute(
    plan: Plan,
    store: RunStore,
    record: records.RunRecord,
    progress: bool,
    done: dict[int, Path],
    executor: Executor | None = None,
    fresh: bool = False,
) -> RunResult:
    """Compute and record a run whose folder lock the caller holds (``fresh``: a new run,
    whose folder is removed again if the registry cannot record it)."""
    folder = Path(record.folder)
    record.pid, record.host = os.getpid(), provenance.host()
    _start(store, record, fresh)
    heartbeat = Heartbeat(record.beat, liveness.HEARTBEAT_S)
    attrs = {
        "run_id": record.run_id,
        "git_commit": record.git_commit,
        "git_dirty": record.git_dirty,
        "versions": record.versions,
        "code": record.code,
        "created": record.started,
    }
    writer = None
    before = set(folder.iterdir())
    try:
        heartbeat.start()
        writer = ResultsWriter(plan, folder / RESULTS_NAME, attrs, record.chunk_size)
        parts = list(chunks(plan.cases, record.chunk_size))
        for index in sorted(done):
            writer.write(parts[index], _load_chunk(done[index], parts[index], plan, writer))

        def finished(index: int, out: SceneOutput) -> None:
            _save_chunk(folder, index, parts[index], out)
            writer.write(parts[index], out)

        ev = evaluate(
            plan,
            chunk_size=record.chunk_size,
            progress=progress,
            on_chunk=finished,
            done=dict.fromkeys(done),
            executor=executor,
            collect=False,
        )
        started = time.perf_counter()
        files = [writer.close({"timings": ev.timings})]
        phases = {**ev.timings, "results_s": time.perf_counter() - started}
        ds = printable_attributes(open_results(files[0]))  # as analyze reads it
        record.warnings = []  # this attempt's (a resume draws every figure again)
        files += write_analysis(ds, folder, timings=phases, problems=record.warnings)
        with xr.open_dataset(folder / ANALYSIS_NAME) as an:
            record.points_without_value = int(an.attrs.get("points_without_value", 0))
    except BaseException as exc:
        heartbeat.stop()
        if writer is not None:
            writer.abandon()
        _remove_new_files(folder, before)
        ended = "interrupted" if isinstance(exc, KeyboardInterrupt) else "failed"
        record.status, record.finished, record.error = ended, records.now(), repr(exc)
        try:
            record.write()
            store.register(record)
        except (OSError, sqlite3.Error) as unrecorded:  # e.g. the disk is still full
            exc.add_note(f"its run.json still says running ({unrecorded})")
        exc.add_note(
            f"run {record.run_id} kept its finished chunks; resume it with: "
            f"{store.resume_command(record.run_id)}"
        )
        raise
    heartbeat.stop()
    record.status, record.finished, record.timings = "finished", records.now(), phases
    record.write()  # the one step that finishes the run; the registry follows
    shutil.rmtree(folder / CHECKPOINTS, ignore_errors=True)
    try:
        store.register(record)
    except RegistryUnusable as exc:
        exc.add_note(
            f"run {record.run_id} finished and its results are in {folder}; the registry "
            "records it the next time runs are listed"
        )
        raise
    return RunResult(record, ds, folder, (folder / "study.toml", folder / "run.json", *files))


def _start(store: RunStore, record: records.RunRecord, fresh: bool) -> None:
    """Write run.json and register the run; a new run whose run.json cannot be written (a
    full disk) or that the registry refuses leaves nothing."""
    try:
        record.beat()
        store.register(record)
    except BaseException as exc:
        if fresh:
            shutil.rmtree(record.folder, ignore_errors=True)
            exc.add_note(f"nothing was run: the run folder {record.folder} was removed again")
        raise


def _remove_new_files(folder: Path, before: set[Path]) -> None:
    """Delete the files a failed attempt wrote into the run folder (results, analysis,
    figures: possibly cut short by a full disk); the checkpoints and the record stay.
    Never raises: it runs while another error is being reported."""
    try:
        written = [p for p in folder.iterdir() if p not in before and p.name != "run.json"]
    except OSError:
        return
    for path in written:
        with contextlib.suppress(OSError):
            path.unlink()


def _check_unchanged(study: Path, sha256: str, folder: Path | None) -> None:
    """Refuse to resume a run whose study file, or a file the study reads (a relative path in
    ``folder``), changed since it started (its checkpoints would be mixed with points of
    another definition)."""
    text = study.read_text(encoding="utf-8")
    definition, _ = parse_study(text, str(study), folder)
    inputs = definition.input_files() if definition is not None else ()
    if records.definition_hash(text, inputs) == sha256:
        return
    original = _recorded_text(study.parent)
    if original == text:
        missing = [str(path) for _, path in inputs if not path.is_file()]
        read = ", ".join(str(path) for _, path in inputs)
        what = f"is gone: {', '.join(missing)}" if missing else "changed after the run started"
        msg = (
            f"a file that {study} reads ({read}) {what}. Resuming would mix design points of "
            f"two inputs; run the study anew: python -m studies run {study}"
        )
        raise RunStateError(msg)
    changed = [
        line
        for line in difflib.unified_diff(original.splitlines(), text.splitlines(), lineterm="", n=0)
        if line[:1] in "+-" and line[:3] not in ("+++", "---")
    ]
    shown = "; ".join(changed[:6]) if original else "the recorded text is not available"
    msg = (
        f"{study} was edited after the run started (changed: {shown}). Resuming would mix "
        f"design points of two definitions; run the edited study anew: "
        f"python -m studies run {study}"
    )
    raise RunStateError(msg)


def _recorded_text(folder: Path) -> str:
    """The study text a run started with, as its checkpoints or results recorded it."""
    record = folder / ORIGINAL_STUDY
    return record.read_text(encoding="utf-8") if record.exists() else ""


def _save_chunk(folder: Path, index: int, part: slice, out: SceneOutput) -> None:
    save_chunk(folder / CHECKPOINTS / f"{index:06d}.npz", part, out)


def _load_chunk(path: Path, part: slice, plan: Plan, writer: ResultsWriter) -> SceneOutput:
    """A checkpointed chunk, validated against the plan (see :mod:`studies.tracking.checkpoints`)."""
    curves = {name: writer.width(name) for name in plan.definition.curves}
    return load_chunk(path, part, plan.responses, curves)
