"""Run a study end to end: plan → evaluate → Dataset → netCDF → analysis → run record.

The run folder and registry row are created only after the study has passed validation, so a
malformed study writes nothing. A run that fails while computing keeps its folder with
``run.json`` status ``failed`` and the error, and the registry says so.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import xarray as xr

from studies import provenance, tracking
from studies.plan import Plan, plan_study
from studies.report import write_analysis
from studies.results import build_dataset, write_netcdf
from studies.runner import DEFAULT_CHUNK_SIZE, evaluate

DEFAULT_OUTPUTS = Path("outputs")


@dataclass(frozen=True)
class RunResult:
    record: tracking.RunRecord
    dataset: xr.Dataset
    folder: Path
    files: tuple[Path, ...]


def run_study(
    name_or_path: str | Path,
    outputs: Path = DEFAULT_OUTPUTS,
    chunk_size: int = DEFAULT_CHUNK_SIZE,
    progress: bool = True,
) -> RunResult:
    """Validate and run a study; write its run folder under ``outputs``."""
    plan = plan_study(name_or_path)
    return run_plan(plan, outputs, chunk_size, progress)


def run_plan(
    plan: Plan,
    outputs: Path = DEFAULT_OUTPUTS,
    chunk_size: int = DEFAULT_CHUNK_SIZE,
    progress: bool = True,
) -> RunResult:
    d = plan.definition
    commit, dirty = provenance.git_state()
    run_id = tracking.new_run_id(d.text)
    folder = tracking.run_folder(outputs, d.name, run_id)
    (folder / "study.toml").write_text(d.text, encoding="utf-8")
    record = tracking.RunRecord(
        run_id=run_id,
        study=d.name,
        scene=d.scene,
        design=plan.design.name,
        runs=plan.runs,
        status="running",
        started=tracking.now(),
        git_commit=commit,
        git_dirty=dirty,
        definition_sha256=tracking.definition_hash(d.text),
        folder=str(folder),
        versions=provenance.versions(),
        host=provenance.host(),
        settings=dict(d.settings),
    )
    record.write()
    tracking.register(outputs, record)
    try:
        ev = evaluate(plan, chunk_size=chunk_size, progress=progress)
        attrs = {
            "run_id": run_id,
            "git_commit": commit,
            "git_dirty": dirty,
            "versions": record.versions,
            "timings": ev.timings,
            "created": record.started,
        }
        ds = build_dataset(plan, ev, attrs)
        files = [write_netcdf(ds, folder / "results.nc")]
        files += write_analysis(ds, folder)
    except BaseException as exc:
        record.status, record.finished, record.error = "failed", tracking.now(), repr(exc)
        record.write()
        tracking.register(outputs, record)
        raise
    record.status, record.finished, record.timings = "finished", tracking.now(), ev.timings
    record.write()
    tracking.register(outputs, record)
    return RunResult(record, ds, folder, (folder / "study.toml", folder / "run.json", *files))
