"""Scene ``rocker``: OHC cam with a variable-ratio rocker, valve kinematics (physics §3).

The linkage itself (tappet law, rocker kinematics [R1]–[R6], caches, checks, kinematic
responses) is :class:`studies.scenes.linkage.scene.LinkageScene`, which the ``valve`` scenes
build on too; the rocker scene is that linkage on its own: its two stages ``tappet`` and
``rocker``, the valve-lift figure and the linkage status table.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from studies.scenes.linkage.scene import LinkageScene, LinkageState

if TYPE_CHECKING:
    import xarray as xr

    from studies.scenes.base import FigureBuilder


class RockerScene(LinkageScene[LinkageState]):
    """The cam–rocker–valve linkage as a scene of its own (kinematics only)."""

    name = "rocker"
    seconds_per_point = 2e-2
    description = "OHC cam with variable-ratio rocker: valve lift, force ratio (kinematics)"
    state_type = LinkageState

    def figures(self) -> dict[str, FigureBuilder]:
        from studies.scenes.linkage.figures import valve_lift_figure  # noqa: PLC0415

        return {"valve_lift": valve_lift_figure}

    def summaries(self, ds: xr.Dataset) -> list[str]:
        from studies.scenes.linkage.summaries import linkage_status_summary  # noqa: PLC0415  (xarray on use)

        return linkage_status_summary(ds)
