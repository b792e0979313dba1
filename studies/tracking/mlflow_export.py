"""MLflow export (``run --mlflow URI``, ``mlflow RUN… --to URI``): one MLflow run per study run.

The local store MLflow recommends is SQLite: ``sqlite:///mlflow.db`` (a file ``mlflow.db`` in
the current folder; ``sqlite:////abs/path/mlflow.db`` for an absolute path); artifacts go to
``mlartifacts/`` beside the database. MLflow 3 refuses its old file store (``file:./mlruns``)
unless told otherwise; a server (``http://host:5000``) works too. ``mlflow-skinny`` with
SQLAlchemy and Alembic is the optional extra (``pip install -e '.[mlflow]'``).

The MLflow experiment is named after the study, the MLflow run after the run id. Parameters,
settings and defaults are params in SI (``bore`` = ``0.086 m``), factors ``factor.<name>``
(levels ``|``-separated), response summaries metrics ``<response>.min|mean|max`` in SI (their
units as tags ``units.<response>``); the run's tags are MLflow tags ``tag.<tag>``, its notes the
MLflow run description; the run folder (figures, ``results.nc``, ``analysis.nc``, reports,
``run.json``) its artifacts. A study run is logged once: exporting it again finds the MLflow
run tagged with its id; an export that fails part-way deletes its partial MLflow run.
"""

from __future__ import annotations

import json
import logging
import math
import os
import warnings
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any
from urllib.parse import urlparse

from studies.common.errors import StudyError
from studies.tracking.run_values import values_of

EXTRA = "pip install -e '.[mlflow]' (from a checkout of engine-studies)"
RUN_TAG = "engine_studies.run_id"
PROBE_ENVIRONMENT = {  # a server that does not answer: one quick try, not minutes of retries
    "MLFLOW_HTTP_REQUEST_MAX_RETRIES": "0",
    "MLFLOW_HTTP_REQUEST_TIMEOUT": "10",
}
RECOMMENDED = "sqlite:///mlflow.db"


def params_and_metrics(folder: Path) -> tuple[dict[str, str], dict[str, float], dict[str, str]]:
    """What is logged for the finished run in ``folder``: (params, metrics, metric units)."""
    params: dict[str, str] = {}
    factors: dict[str, list[str]] = {}
    factor_units: dict[str, str] = {}
    metrics: dict[str, float] = {}
    units: dict[str, str] = {}
    for kind, name, text, num, unit, _declared in values_of(folder, "finished"):
        if kind == "factor":
            factors.setdefault(name, []).append(text)
            factor_units[name] = unit
        elif kind == "response":
            if num is not None and math.isfinite(num):
                metrics[name] = num
                units[name.rsplit(".", 1)[0]] = unit
        else:
            params[name] = _with_units(text, unit)
    params |= {f"factor.{k}": _with_units("|".join(v), factor_units[k]) for k, v in factors.items()}
    return params, metrics, units


def _with_units(text: str, unit: str) -> str:
    return f"{text} {unit}" if unit not in ("", "1") else text


def _mlflow() -> Any:
    try:
        import mlflow  # noqa: PLC0415 (an optional extra: imported only when asked for)
    except ImportError:
        raise StudyError(f"MLflow export needs the optional mlflow extra: {EXTRA}") from None
    for name in ("mlflow", "alembic"):  # their INFO lines ("Updating database tables")
        logging.getLogger(name).setLevel(logging.WARNING)
    return mlflow


@contextmanager
def _quiet(probe: bool = False) -> Iterator[None]:
    """MLflow's and its libraries' deprecation warnings are theirs, not the user's (SQLAlchemy
    2.1 warns about MLflow's own queries); a probe of a server tries once, quickly."""
    saved = {k: os.environ.get(k) for k in PROBE_ENVIRONMENT}
    if probe:
        os.environ.update({k: v for k, v in PROBE_ENVIRONMENT.items() if saved[k] is None})
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            yield
    finally:
        for key, value in saved.items():
            if value is None:
                os.environ.pop(key, None)


def check_store(uri: str) -> None:
    """Fail early, before anything runs, when MLflow cannot use ``uri`` (ValueError, one line
    with the recommended form)."""
    mlflow = _mlflow()
    mlflow.set_tracking_uri(uri)
    try:
        with _quiet(probe=True):
            mlflow.MlflowClient().search_experiments(max_results=1)
    except Exception as exc:  # noqa: BLE001  MLflow raises its own and its stores' errors
        detail = getattr(exc, "message", None) or str(exc)
        msg = (
            f"--mlflow {uri}: MLflow cannot use this store ({detail.splitlines()[0][:160]}); "
            f"for a local store use SQLite, e.g. --mlflow {RECOMMENDED}"
        )
        raise StudyError(msg) from None


def log_run(uri: str, folder: Path, tags: list[str], notes: list[str]) -> tuple[str, bool]:
    """Log the finished run in ``folder`` to MLflow at ``uri`` unless it is logged already:
    (the MLflow run id, whether it was logged now). ValueError in one line if MLflow fails."""
    mlflow = _mlflow()
    record = json.loads((folder / "run.json").read_text(encoding="utf-8"))
    check_store(uri)
    try:
        with _quiet():
            return _log(mlflow, uri, folder, record, tags, notes)
    except Exception as exc:  # noqa: BLE001  MLflow's, its store's or the network's errors
        detail = getattr(exc, "message", None) or str(exc) or type(exc).__name__
        msg = f"MLflow at {uri} did not log run {record['run_id']}: {detail.splitlines()[0][:200]}"
        raise StudyError(msg) from None


def _log(
    mlflow: Any, uri: str, folder: Path, record: dict[str, Any], tags: list[str], notes: list[str]
) -> tuple[str, bool]:
    client = mlflow.MlflowClient()
    experiment = _experiment(mlflow, client, uri, record["study"])
    earlier = client.search_runs([experiment], f"tags.`{RUN_TAG}` = '{record['run_id']}'")
    for run in earlier:
        if run.info.status == "FINISHED":
            return str(run.info.run_id), False
        client.delete_run(run.info.run_id)  # a partial export: replaced, never duplicated
    params, metrics, units = params_and_metrics(folder)
    active = mlflow.start_run(experiment_id=experiment, run_name=record["run_id"])
    try:
        mlflow.set_tags(_tags(record, units, tags, notes))
        mlflow.log_params(params)
        mlflow.log_metrics(metrics)
        mlflow.log_artifacts(str(folder))
    except BaseException:
        mlflow.end_run("FAILED")
        client.delete_run(active.info.run_id)
        raise
    mlflow.end_run()
    return str(active.info.run_id), True


def _experiment(mlflow: Any, client: Any, uri: str, name: str) -> str:
    """The id of the experiment ``name``, created with its artifacts beside a SQLite
    database (MLflow's default would be the current folder)."""
    found = client.get_experiment_by_name(name)
    if found is not None:
        return str(found.experiment_id)
    location = None
    parsed = urlparse(uri)
    if parsed.scheme == "sqlite" and parsed.path not in ("", "/:memory:"):
        database = Path(uri.removeprefix("sqlite:///")).resolve()
        location = (database.parent / "mlartifacts").as_uri()
    try:
        return str(client.create_experiment(name, artifact_location=location))
    except mlflow.exceptions.MlflowException:  # another process created it meanwhile
        return str(client.get_experiment_by_name(name).experiment_id)


def _tags(
    record: dict[str, Any], units: dict[str, str], tags: list[str], notes: list[str]
) -> dict[str, str]:
    code = record.get("code", {})
    scene = code.get("scene", {})
    engine = code.get("engine", {})
    out = {
        RUN_TAG: record["run_id"],
        "git_commit": record.get("git_commit") or "none",
        "git_dirty": str(bool(record.get("git_dirty"))),
        "scene": record.get("scene", ""),
        "design": record.get("design", ""),
        "engine": f"{engine.get('version', '?')} source {engine.get('source_sha256', '?')}",
        "scene_code": (
            f"{scene.get('distribution') or '?'} {scene.get('version') or '?'} "
            f"source {scene.get('source_sha256', '?')}"
        ),
    }
    out |= {f"units.{name}": unit for name, unit in units.items()}
    out |= {f"tag.{tag}": "1" for tag in tags}
    if notes:
        out["mlflow.note.content"] = "\n".join(notes)  # MLflow's run description
    return out
