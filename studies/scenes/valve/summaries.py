"""The ``valve`` scene's table for ``analysis.txt``: the design points whose dynamics did not
finish ok, by reason."""

from __future__ import annotations

import numpy as np
import xarray as xr

from engine_kernels import valvetrain as valve
from studies.common.summary_tables import runs_line
from studies.scenes.valve.parameters import STATUS_NOT_RUN


def dynamics_status_summary(ds: xr.Dataset) -> list[str]:
    """Design points whose dynamics did not finish ok, by reason (they explain NaN responses)."""
    blocks = []
    if "status" in ds:
        status = ds["status"].values.astype(float)
        bad = np.flatnonzero(status != valve.STATUS_OK)
        if bad.size:
            names = [*valve.VALVE_STATUS_NAMES, "not run (kinematic chain invalid)"]
            lines = [f"Dynamics not finished ok (status) at {bad.size} of {status.size} points"]
            for code in range(1, STATUS_NOT_RUN + 1):
                runs = bad[status[bad] == code]
                if runs.size:
                    lines.append(runs_line(f"{code} {names[code]}", runs))
            blocks.append("\n".join(lines))
    return blocks
