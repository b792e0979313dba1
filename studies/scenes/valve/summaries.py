"""The ``valve`` scene's table for ``analysis.txt``: the design points whose dynamics did not
finish ok, by reason."""

from __future__ import annotations

import numpy as np
import xarray as xr

from engine_kernels import valvetrain as valve
from studies.common.blocks import run_slices
from studies.common.summary_tables import RunList
from studies.scenes.valve.parameters import STATUS_NOT_RUN


def dynamics_status_summary(ds: xr.Dataset) -> list[str]:
    """Design points whose dynamics did not finish ok, by reason (they explain NaN responses);
    the status read a block of runs at a time."""
    if "status" not in ds:
        return []
    status = ds["status"].variable
    bad = RunList()
    by_code = {code: RunList() for code in range(1, STATUS_NOT_RUN + 1)}
    for part in run_slices(len(status)):
        codes = np.asarray(status[part]).astype(float)
        found = np.flatnonzero(codes != valve.STATUS_OK)
        bad.add(part.start + found)
        for code, runs in by_code.items():
            runs.add(part.start + found[codes[found] == code])
    if not bad.count:
        return []
    names = [*valve.VALVE_STATUS_NAMES, "not run (kinematic chain invalid)"]
    lines = [f"Dynamics not finished ok (status) at {bad.count} of {len(status)} points"]
    for code, runs in by_code.items():
        if runs.count:
            lines.append(runs.line(f"{code} {names[code]}"))
    return ["\n".join(lines)]
