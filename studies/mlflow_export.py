"""Optional MLflow logging (``run --mlflow URI``): one MLflow run per study run.

The MLflow experiment is named after the study; the MLflow run after the run id. Fixed
parameters and settings are logged as params under their names, factors as
``factor.<name>`` (their levels, ``|``-separated), the response summaries as metrics
``<response>.min|mean|max`` and the run folder as artifacts. ``mlflow`` is an optional extra
(``pip install engine-studies[mlflow]``); nothing else needs it.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

from studies import registry

EXTRA = "pip install 'engine-studies[mlflow]'"


def params_and_metrics(folder: Path) -> tuple[dict[str, str], dict[str, float]]:
    """What is logged for the finished run in ``folder``: (params, metrics)."""
    params: dict[str, str] = {}
    factors: dict[str, list[str]] = {}
    metrics: dict[str, float] = {}
    for kind, name, text, num, _units in registry.values_of(folder, "finished"):
        if kind == "factor":
            factors.setdefault(name, []).append(text)
        elif kind == "response":
            if num is not None and math.isfinite(num):
                metrics[name] = num
        else:
            params[name] = text
    params |= {f"factor.{k}": "|".join(v) for k, v in factors.items()}
    return params, metrics


def log_run(uri: str, record: Any) -> str:
    """Log a finished run (its :class:`studies.tracking.RunRecord`) to the MLflow tracking
    server or store at ``uri``; return the MLflow run id."""
    try:
        import mlflow  # noqa: PLC0415 (an optional extra: imported only when asked for)
    except ImportError:
        raise ValueError(f"--mlflow needs the optional mlflow package: {EXTRA}") from None
    folder = Path(record.folder)
    params, metrics = params_and_metrics(folder)
    mlflow.set_tracking_uri(uri)
    try:
        mlflow.set_experiment(record.study)
    except mlflow.exceptions.MlflowException as exc:
        msg = f"run {record.run_id} is recorded, but MLflow at {uri} refused it: {exc.message}"
        raise ValueError(msg) from None
    with mlflow.start_run(run_name=record.run_id) as active:
        mlflow.set_tags(
            {
                "run_id": record.run_id,
                "git_commit": record.git_commit,
                "git_dirty": str(record.git_dirty),
                "scene": record.scene,
                "design": record.design,
            }
        )
        mlflow.log_params(params)
        mlflow.log_metrics(metrics)
        mlflow.log_artifacts(str(folder))
        return str(active.info.run_id)
