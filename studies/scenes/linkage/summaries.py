"""The table the ``rocker`` and ``valve`` scenes share for ``analysis.txt``: the design points
whose kinematic linkage is invalid, by reason."""

from __future__ import annotations

import numpy as np
import xarray as xr

from engine_kernels.valvetrain import rocker
from studies.common.summary_tables import runs_line


def linkage_status_summary(ds: xr.Dataset) -> list[str]:
    """Design points whose kinematic linkage is invalid, by reason (they explain NaN responses)."""
    blocks = []
    if "chain_status" in ds:
        flags = ds["chain_status"].values.astype(float)
        bad = np.flatnonzero(flags != rocker.ROCKER_OK)
        if bad.size:
            lines = [f"Kinematic chain invalid (chain_status) at {bad.size} of {flags.size} points"]
            for flag, meaning in rocker.ROCKER_STATUS_FLAGS:
                runs = bad[(flags[bad].astype(int) & flag) != 0]
                if runs.size:
                    lines.append(runs_line(meaning, runs))
            blocks.append("\n".join(lines))
    return blocks
