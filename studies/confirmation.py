"""The confirmation run of a Taguchi study: the chosen levels as a ready-to-run study file
(a full factorial of one point) built from the run's own study text."""

from __future__ import annotations

import json
import math
import re
import tomllib
from collections.abc import Mapping
from typing import Any

import xarray as xr

from studies.taguchi import factor_names, level_values, plain

_BARE_KEY = re.compile(r"^[A-Za-z0-9_-]+$")


def confirmation_values(ds: xr.Dataset, levels: Mapping[str, int]) -> dict[str, Any]:
    """Factor → its physical value at the chosen level (plain Python types)."""
    return {f: level_values(ds, f)[int(levels[f])] for f in factor_names(ds)}


def confirmation_toml(ds: xr.Dataset, levels: Mapping[str, int]) -> str:
    """A study file that runs the chosen levels once: the original study (attribute
    ``study_toml``) with ``design = "full_factorial"`` and one level per factor.

    Without the original text, only the ``[factors]`` tables are written.
    """
    values = confirmation_values(ds, levels)
    original = tomllib.loads(ds.attrs["study_toml"]) if ds.attrs.get("study_toml") else {}
    study = {k: v for k, v in original.items() if k not in ("design", "factors")}
    name = str(original.get("name", ds.attrs.get("study_name", "study")))
    if original:
        study["name"] = f"{name}_confirmation"
        study["description"] = f"Confirmation run of {name}: every factor at its chosen level"
        study["design"] = {"type": "full_factorial"}
    factors = {}
    for f, value in values.items():
        units = ds[f].attrs.get("units", "") if f in ds.coords else ""
        factors[f] = {"levels": [value]} | ({"units": str(units)} if units else {})
    study["factors"] = factors
    run = ds.attrs.get("run_id", "")
    shown = " ".join(f"{name}{f' (run {run})' if run else ''}".splitlines())  # one comment line
    header = f"# Confirmation run of {shown}: the chosen levels.\n"
    return header + _toml(study)


def _toml_value(value: Any) -> str:
    value = plain(value)
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if math.isfinite(value):
            return repr(value)
        return "nan" if math.isnan(value) else ("inf" if value > 0 else "-inf")
    if isinstance(value, str):
        return json.dumps(value, ensure_ascii=False)
    if isinstance(value, list):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    if isinstance(value, dict):
        return "{ " + ", ".join(f"{_key(k)} = {_toml_value(v)}" for k, v in value.items()) + " }"
    msg = f"cannot write {value!r} ({type(value).__name__}) as TOML"
    raise TypeError(msg)


def _key(key: str) -> str:
    return key if _BARE_KEY.match(key) else json.dumps(key, ensure_ascii=False)


def _toml(data: Mapping[str, Any]) -> str:
    """TOML text of a study dict: top-level values, then tables (a table of tables as
    ``[name.sub]`` sections)."""
    lines = [f"{_key(k)} = {_toml_value(v)}" for k, v in data.items() if not isinstance(v, dict)]
    for key, table in data.items():
        if not isinstance(table, dict):
            continue
        if table and all(isinstance(v, dict) for v in table.values()):
            for sub, inner in table.items():
                lines += ["", f"[{_key(key)}.{_key(sub)}]"]
                lines += [f"{_key(k)} = {_toml_value(v)}" for k, v in inner.items()]
        else:
            lines += ["", f"[{_key(key)}]"]
            lines += [f"{_key(k)} = {_toml_value(v)}" for k, v in table.items()]
    return "\n".join(lines) + "\n"
