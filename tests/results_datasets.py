"""Results Datasets laid out as :mod:`studies.run.results` writes them, with synthetic responses,
for checking analysis and reports without running kernels (shared by the report tests)."""

from __future__ import annotations

import json
import tomllib
from pathlib import Path

import numpy as np
import xarray as xr

from studies.define import designs

CATALOG = Path(__file__).parents[1] / "studies" / "catalog"


def study_dataset(path: Path, seed: int = 0) -> xr.Dataset:
    """A results Dataset of a shipped study with synthetic additive responses plus noise."""
    text = path.read_text(encoding="utf-8")
    study = tomllib.loads(text)
    factors = study["factors"]
    spec = study.get("design", {})
    design = designs.orthogonal(
        spec["type"],
        {f: len(v["levels"]) for f, v in factors.items()},
        {f: v.get("column") for f, v in factors.items()},
        tuple(spec.get("error_columns", ())),
        spec.get("interactions", ()),
    )
    coords: dict = {"run": np.arange(design.runs)}
    for f, v in factors.items():
        coords[f] = (
            "run",
            np.asarray(v["levels"])[design.levels[f]],
            {"units": v.get("units", "")},
        )
        coords[f"{f}_level"] = ("run", design.levels[f].astype(np.int32))
    for name in [*design.interactions, *design.error_columns]:
        coords[f"{name}_level"] = ("run", design.levels[name].astype(np.int32))
    rng = np.random.default_rng(seed)
    levels = np.array([design.levels[f] for f in factors], dtype=float).T
    data = {
        r: ("run", 100.0 + levels @ rng.normal(0, 10, len(factors)) + rng.normal(0, 1, design.runs),
            {"units": "MPa", "long_name": r.replace("_", " "), "better": "smaller"})
        for r in study["responses"]
    }  # fmt: skip
    ds = xr.Dataset(data, coords=coords)
    ds.attrs = {
        "title": f"{study['name']}: {study.get('description', '')}",
        "study_name": study["name"],
        "scene": study["scene"],
        "design": design.name,
        "factors": json.dumps(list(factors)),
        "error_columns": json.dumps(list(design.error_columns)),
        "interaction_columns": json.dumps({k: list(v) for k, v in design.interactions.items()}),
        "array_columns": json.dumps(design.columns),
        "responses": json.dumps(study["responses"]),
        "study_toml": text,
        "run_id": "20250101T000000Z-abc123",
        "git_commit": "0123456789abcdef",
        "git_dirty": 0,
    }
    return ds


def l27_dataset(replicates: int = 0, pair: tuple[str, str] = ("A", "B")) -> xr.Dataset:
    counts = dict.fromkeys("ABCD", 3) | {"E": 2}
    design = designs.orthogonal("auto", counts, dict.fromkeys(counts), (), [pair])
    coords: dict = {}
    units = {"A": "mm", "B": "deg", "D": "N", "E": "mm"}
    for f in counts:
        values = np.arange(1.0, 4.0) * 10 if f != "C" else np.array(["lin", "sin", "cyc"])
        coords[f] = ("run", values[design.levels[f]], {"units": units.get(f, "")})
        coords[f"{f}_level"] = ("run", design.levels[f].astype(np.int32))
    for name in [*design.interactions, *design.error_columns]:
        coords[f"{name}_level"] = ("run", design.levels[name].astype(np.int32))
    lv = design.levels
    rng = np.random.default_rng(1)
    mu = 10 + 2 * lv["A"] - lv["B"] + 1.5 * (lv["A"] == lv["B"]) + 0.5 * lv["C"]
    attrs = {"units": "N", "long_name": "force", "better": "smaller"}
    if replicates:
        y = mu[:, None] + rng.normal(0, 0.3, (design.runs, replicates))
        var = (("run", "replicate"), y, attrs)
    else:
        var = ("run", mu + rng.normal(0, 0.3, design.runs), attrs)
    ds = xr.Dataset({"force": var}, coords=coords)
    ds.attrs = {
        "design": design.name,
        "factors": json.dumps(list(counts)),
        "error_columns": json.dumps(list(design.error_columns)),
        "interaction_columns": json.dumps({k: list(v) for k, v in design.interactions.items()}),
        "array_columns": json.dumps(design.columns),
    }
    return ds
