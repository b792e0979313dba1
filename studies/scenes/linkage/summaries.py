"""The table the ``rocker`` and ``valve`` scenes share for ``analysis.txt``: the design points
whose kinematic linkage is invalid, by reason."""

from __future__ import annotations

import numpy as np
import xarray as xr

from engine_kernels.valvetrain import rocker
from studies.common.blocks import run_slices
from studies.common.summary_tables import RunList


def linkage_status_summary(ds: xr.Dataset) -> list[str]:
    """Design points whose kinematic linkage is invalid, by reason (they explain NaN responses);
    the status read a block of runs at a time."""
    if "chain_status" not in ds:
        return []
    status = ds["chain_status"].variable
    bad, by_flag = RunList(), {flag: RunList() for flag, _ in rocker.ROCKER_STATUS_FLAGS}
    for part in run_slices(len(status)):
        flags = np.asarray(status[part]).astype(float)
        found = np.flatnonzero(flags != rocker.ROCKER_OK)
        bad.add(part.start + found)
        for flag, runs in by_flag.items():
            runs.add(part.start + found[(flags[found].astype(int) & flag) != 0])
    if not bad.count:
        return []
    lines = [f"Kinematic chain invalid (chain_status) at {bad.count} of {len(status)} points"]
    for flag, meaning in rocker.ROCKER_STATUS_FLAGS:
        if by_flag[flag].count:
            lines.append(by_flag[flag].line(meaning))
    return ["\n".join(lines)]
