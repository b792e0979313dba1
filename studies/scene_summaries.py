"""Per-scene result tables for ``analysis.txt``, beside range analysis and ANOVA.

:func:`scene_summaries` dispatches on the ``scene`` attribute of a results Dataset and returns
text blocks (none for scenes or studies without the variables they need):

* ``reed`` — every design point's first natural frequency and its margin to the excitation
  band, to 4 significant figures, and whether it lies outside the band;
* ``luffing`` — every check as value, limit and the number of design points that pass, and
  the failing checks of each design point;
* ``rocker``, ``valve`` — the design points whose kinematic chain is invalid or whose
  dynamics did not finish ok, by reason (these explain NaN responses).
"""

from __future__ import annotations

import json
from collections.abc import Callable
from typing import Any

import numpy as np
import pandas as pd
import xarray as xr

from engine_kernels import valvetrain as valve
from engine_kernels.valvetrain import rocker
from studies.scenes.valve_parameters import STATUS_NOT_RUN

# check → (value, limit) response names of the luffing scene
LUFFING_CHECKS = {
    "motor": ("motor_power", "motor_rated_power"),
    "ratio": ("implied_ratio", "belt_ratio"),
    "coupling": ("coupling_torque", "coupling_limit"),
    "deflection": ("deflection", "deflection_limit"),
    "slope": ("slope", "slope_limit"),
    "key": ("key_stress", "key_limit"),
    "bearing": ("bearing_life", "bearing_limit"),
}


def _sig4(value: float) -> str:
    return "—" if not np.isfinite(value) else f"{value:.4g}"


def _factor_columns(ds: xr.Dataset) -> dict[str, Any]:
    columns: dict[str, Any] = {}
    for f in json.loads(ds.attrs.get("factors", "[]")):
        units = ds[f].attrs.get("units", "")
        key = f"{f} [{units}]" if units not in ("", "1") else f
        columns[key] = ds[f].values
    return columns


def _header(ds: xr.Dataset, name: str) -> str:
    units = ds[name].attrs.get("units", "")
    return f"{name} [{units}]" if units else name


def reed_summary(ds: xr.Dataset) -> list[str]:
    """First natural frequency and band margin of every design point (4 significant figures)."""
    if "first_frequency" not in ds:
        return []
    columns = _factor_columns(ds)
    columns[_header(ds, "first_frequency")] = [_sig4(v) for v in ds["first_frequency"].values]
    if {"band_min", "band_max"} <= set(ds.data_vars):
        columns["band [Hz]"] = [
            f"{_sig4(a)}–{_sig4(b)}"
            for a, b in zip(ds["band_min"].values, ds["band_max"].values, strict=True)
        ]
    if "first_margin" in ds:
        margin = ds["first_margin"].values
        columns[_header(ds, "first_margin")] = [_sig4(v) for v in margin]
        columns["first mode"] = np.where(margin > 0, "outside the band", "INSIDE the band")
    table = pd.DataFrame(columns).to_string(index=False)
    title = (
        "First natural frequency and its margin to the excitation band (4 significant "
        "figures; margin > 0 outside the band)"
    )
    return [f"{title}\n{table}"]


def luffing_summary(ds: xr.Dataset) -> list[str]:
    """Each check as value range, limit and pass count; the failing checks per design point."""
    checks = [c for c in LUFFING_CHECKS if f"{c}_ok" in ds]
    if not checks:
        return []
    n = ds.sizes["run"]
    rows = []
    for c in checks:
        value, limit = LUFFING_CHECKS[c]
        shown = {}
        for label, name in (("value", value), ("limit", limit)):
            if name in ds:
                v = ds[name].values.astype(float)
                span = (
                    _sig4(np.nanmin(v))
                    if np.nanmin(v) == np.nanmax(v)
                    else (f"{_sig4(np.nanmin(v))} … {_sig4(np.nanmax(v))}")
                )
                units = ds[name].attrs.get("units", "")
                shown[label] = f"{span} {units}" if units not in ("", "1") else span
            else:
                shown[label] = "(not stored)"
        passes = int(ds[f"{c}_ok"].values.sum())
        rows.append(
            {
                "check": c,
                "value": shown["value"],
                "limit": shown["limit"],
                "passes": f"{passes} of {n}",
            }
        )
    checks_table = pd.DataFrame(rows).to_string(index=False)
    columns = _factor_columns(ds)
    columns["failing checks"] = [
        ", ".join(c for c in checks if ds[f"{c}_ok"].values[run] == 0) or "none" for run in range(n)
    ]
    points_table = pd.DataFrame(columns).to_string(index=False)
    return [
        f"Design checks (value and limit over the design points)\n{checks_table}",
        f"Failing checks per design point\n{points_table}",
    ]


def _runs_line(label: str, runs: np.ndarray) -> str:
    shown = ", ".join(str(r) for r in runs[:20]) + (", …" if runs.size > 20 else "")
    return f"  {label}: {runs.size} (runs {shown})"


def valve_status_summary(ds: xr.Dataset) -> list[str]:
    """Design points with an invalid chain or dynamics that did not finish ok, by reason."""
    blocks = []
    if "chain_status" in ds:
        flags = ds["chain_status"].values.astype(float)
        bad = np.flatnonzero(flags != rocker.ROCKER_OK)
        if bad.size:
            lines = [f"Kinematic chain invalid (chain_status) at {bad.size} of {flags.size} points"]
            for flag, meaning in rocker.ROCKER_STATUS_FLAGS:
                runs = bad[(flags[bad].astype(int) & flag) != 0]
                if runs.size:
                    lines.append(_runs_line(meaning, runs))
            blocks.append("\n".join(lines))
    if "status" in ds:
        status = ds["status"].values.astype(float)
        bad = np.flatnonzero(status != valve.STATUS_OK)
        if bad.size:
            names = [*valve.VALVE_STATUS_NAMES, "not run (kinematic chain invalid)"]
            lines = [f"Dynamics not finished ok (status) at {bad.size} of {status.size} points"]
            for code in range(1, STATUS_NOT_RUN + 1):
                runs = bad[status[bad] == code]
                if runs.size:
                    lines.append(_runs_line(f"{code} {names[code]}", runs))
            blocks.append("\n".join(lines))
    return blocks


SUMMARIES: dict[str, Callable[[xr.Dataset], list[str]]] = {
    "reed": reed_summary,
    "luffing": luffing_summary,
    "rocker": valve_status_summary,
    "valve": valve_status_summary,
}


def scene_summaries(ds: xr.Dataset) -> list[str]:
    """Text blocks for the scene of ``ds`` (empty for scenes without a summary)."""
    summary = SUMMARIES.get(str(ds.attrs.get("scene", "")))
    return summary(ds) if summary else []
