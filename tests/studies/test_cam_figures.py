"""``cam_curves.png`` (studies/scenes/cam/figures.py): a line per design point, at most
``MAX_LINES`` of them, spread over the order of the factor values."""

from __future__ import annotations

import json

import numpy as np
import xarray as xr

from studies.scenes.cam.figures import MAX_LINES, cam_curves_figure


def curves_dataset(runs: int) -> xr.Dataset:
    """``runs`` design points of one factor, stored in shuffled order, each with a lift curve
    that names its run (its value at every angle is the run's factor value)."""
    radius = np.random.default_rng(7).permutation(np.linspace(15.0, 25.0, runs))
    angle = np.linspace(-90.0, 90.0, 31)
    lift = np.repeat(radius[:, None], angle.size, axis=1)
    return xr.Dataset(
        {"lift": (("run", "cam_angle"), lift, {"units": "mm"})},
        coords={
            "base_radius": ("run", radius, {"units": "mm"}),
            "cam_angle": ("cam_angle", angle, {"units": "degree"}),
        },
        attrs={"factors": json.dumps(["base_radius"])},
    )


def drawn(runs: int) -> tuple[list[float], str]:
    fig = cam_curves_figure(curves_dataset(runs))
    assert fig is not None
    lines = fig.axes[0].get_lines()
    return [float(line.get_ydata()[0]) for line in lines], fig.get_suptitle()


def test_few_design_points_are_all_drawn_in_factor_order() -> None:
    values, title = drawn(20)
    np.testing.assert_array_equal(values, np.linspace(15.0, 25.0, 20))
    assert title == "Cam curves per design point"


def test_many_design_points_draw_a_bounded_spread_and_say_so() -> None:
    # 5000 stored curves drew 5000 lines per panel: minutes of matplotlib for an unreadable
    # figure. Now MAX_LINES of them, from the smallest factor value to the largest.
    values, title = drawn(5000)
    assert len(values) == MAX_LINES
    assert values[0] == 15.0
    assert values[-1] == 25.0
    assert np.all(np.diff(values) > 0.0)  # in factor order, each curve once
    assert np.isin(values, np.linspace(15.0, 25.0, 5000)).all()
    assert title == (
        f"Cam curves of {MAX_LINES} of 5000 design points (evenly spread in the order of the "
        "factor values)"
    )
