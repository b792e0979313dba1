"""``dopri`` dates a jump where the drive force reaches zero (issue #26, the 1e-4 mm bars).

The kernels change the contact mode once the drive force has fallen through a dead band
(``TRANSITION_BAND``·preload below zero), which keeps a restart on the switching surface from
chattering. Converged (1e-12 m per step, table 1/256°), ``dopri``'s jump start used to lie
band/|dF/dθ| behind the reference on every separating point: 8.8e-6–6.6e-5° on the four points
below, to 2 % of that formula. That floor kept the second ``dopri`` rung away from 1e-4 mm.

Expected values: scipy's event-restarted DOP853 reference (rtol 1e-10, contact left at 1e-9 N),
stored in data/valve_error_bar_reference.nc; the slope of the drive force comes from the
run's own drive-force curve on a 1/256° grid.
"""

from __future__ import annotations

import math

import numpy as np
import xarray as xr
from valve_samples import REFERENCE_FILE, sample_plan, sample_points

from engine_kernels.valvetrain.valve.layout import C_DRIVE_FORCE, O_JUMP_START, P_PRELOAD
from engine_kernels.valvetrain.valve.model import TRANSITION_BAND
from studies.scenes.valve.batches import integrate_dopri
from studies.scenes.valve.scene import valve_rows

POINTS = np.array([67, 90, 132, 153])
"""Points of sample B that separate, with drive-force slopes of 3–27 N/deg at the jump."""
FINE_DEG = 1.0 / 256.0
CONVERGED = 1e-12
"""Lift tolerance per step [m] at which ``dopri``'s jump start no longer moves (1e-12 and 1e-13
agreed to 4e-8° on these points)."""


def test_converged_jump_start_is_where_the_drive_force_reaches_zero() -> None:
    with xr.open_dataset(REFERENCE_FILE) as stored:
        exact = np.degrees(stored["jump_start"].sel(sample="B").values[POINTS])
    plan = sample_plan(["jump_start"], "dopri", 0.0)
    points = {k: v[POINTS] for k, v in sample_points(plan, "B").items()}
    state = plan.scene.start(points, plan.settings, [], [])
    for key, idx in state.groups.items():
        excitation = plan.scene.excitation(state, key, 2.0 * FINE_DEG, unclipped=True)
        rows = valve_rows(points, idx)
        out, curves = integrate_dopri(excitation, rows, FINE_DEG, CONVERGED, True)
        start = math.degrees(excitation[2])
        for j, i in enumerate(idx):
            force = curves[j, C_DRIVE_FORCE]
            before = int((exact[i] - start) / FINE_DEG)
            slope = (force[before] - force[before - 1]) / FINE_DEG  # N/deg, falling
            late = TRANSITION_BAND * rows[j, P_PRELOAD] / -slope  # the old floor [deg]
            found = math.degrees(out[j, O_JUMP_START])
            assert late > 5e-6, (POINTS[i], late)  # a floor the old code could not pass
            assert abs(found - exact[i]) <= 0.05 * late, (POINTS[i], found - exact[i], late)
