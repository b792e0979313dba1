"""``ramp_height = 0`` is no ramp, whatever ``ramp_width`` and ``ramp_velocity`` say, in both
scenes of the six-segment profile (the parameter's description; an independent audit found a
ramp v·W/2 high built there)."""

from __future__ import annotations

import numpy as np
import pytest

from study_text import run, scene_study

EMPTY_RAMP = """ramp_height = 0.0
ramp_width = { value = 50.0, units = "degree" }
ramp_velocity = { value = 0.4, units = "mm/rad" }"""


def with_empty_ramp(scene: str, responses: str, factor: str, levels: str) -> dict:
    """The scalars of ``scene`` over ``factor`` = ``levels`` with the empty ramp above."""
    factors = f"[factors.{factor}]\nlevels = {levels}"
    study = scene_study(scene, responses=responses, parameters=EMPTY_RAMP, factors=factors)
    return run(study).scalars


def test_the_rocker_reaches_the_target_lift_with_a_ramp_of_height_0() -> None:
    # Before: a 0.1745 mm ramp (0.4 mm/rad x 50 deg / 2) on top of the profile gave
    # max_valve_lift 8.0505 mm where valve_lift asks 7.815 (lash 0.05 mm).
    scalars = with_empty_ramp(
        "rocker", '["max_valve_lift", "max_tappet_lift"]', "valve_lift", "[6.0, 7.815]"
    )
    # By construction [R3], [R6]: the nose of the chain gives the target valve lift exactly
    # (the nose, θ = 0, is a grid point), as without a ramp.
    np.testing.assert_allclose(scalars["max_valve_lift"], [6.0, 7.815], rtol=1e-9)
    # physics §3: 7.815 mm of valve lift is "about 6.30 mm" of tappet lift.
    assert scalars["max_tappet_lift"][1] == pytest.approx(6.30, abs=0.01)


def test_the_cam_lift_is_the_target_lift_and_feasible_with_a_ramp_of_height_0() -> None:
    # Before: max_lift 10.9745 mm (the 10.8 mm target plus a 0.1745 mm ramp), ramp_feasible 0.
    scalars = with_empty_ramp("cam", '["max_lift", "ramp_feasible"]', "lift", "[8.0, 10.8]")
    # physics §2: the working part is scaled to the target lift, and there is no ramp below it.
    np.testing.assert_allclose(scalars["max_lift"], [8.0, 10.8], rtol=1e-9)
    assert (scalars["ramp_feasible"] == 1).all()
