"""The excitation table of the valve dynamics: the linkage's valve lift before the lash is taken
up (physics §3 [R6], §4).

The rocker linkage reports the valve lift clipped at zero, ``Y = max(0, lb (sin β0 − sin β) − Δ)``:
the lift has a kink where the lash is taken up (and where it opens again), between two nodes of
any table. Interpolated from a clipped table, that kink is smeared over a table interval, an
error of 5–50 nm in Y and up to the whole jump of Y' there which does not shrink regularly
with the spacing, so error bars from a finer table missed it. The dynamics therefore read the
unclipped lift, a smooth curve that is negative while the lash is open, and the kernels clip it
where they read it (:func:`engine_kernels.valvetrain.valve.model.lash_clip`), exactly at its zero.

The unclipped lift is the linkage with no lash and the stem tip raised by the lash, less the lash:
β0 = asin((Δ + ρb + z)/lb) is the same for (Δ, z) and (0, z + Δ), so its lift
``lb (sin β0 − sin β)`` is the unclipped lift plus Δ and never negative (zero on the base
circle, where W = W0); velocity and acceleration are the same curves.
"""

from __future__ import annotations

import numpy as np

from engine_kernels.valvetrain import rocker
from studies.scenes.linkage.scene import RockerWalk, resampled_linkage
from studies.scenes.linkage.tappet import TappetTable


def unclipped_valve_lift(
    walk: RockerWalk, tappet: TappetTable, grid: tuple[float, float, float]
) -> np.ndarray:
    """(3, m) rows Y [m] (negative while the lash is open), Y' [m/rad], Y'' [m/rad²] on the
    cam-angle grid (start, spacing, stop) [deg], from the walk of the linkage with the stem
    raised by the lash and no lash (``LinkageScene.rocker_walk(..., no_lash=True)``)."""
    out = resampled_linkage(walk, tappet, grid)
    table = np.ascontiguousarray(out[: rocker.ROW_VALVE_ACCELERATION + 1])
    table[rocker.ROW_VALVE_LIFT] -= walk.raised
    return table
