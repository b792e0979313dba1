"""Scene ``rocker``: OHC cam with a variable-ratio rocker, valve kinematics (physics §3).

The chain itself (tappet law, rocker kinematics, caches, checks) is
:class:`studies.scenes.linkage.scene.LinkageScene`, which the ``valve`` scene builds on too; this scene
adds what a user of the kinematics reads: the valve-lift figure and the invalid-chain table.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from studies.scenes.linkage.scene import LinkageScene

if TYPE_CHECKING:
    import xarray as xr

    from studies.scenes.base import FigureBuilder


class RockerScene(LinkageScene):
    """The kinematic chain as a scene of its own (declarations in :mod:`~studies.scenes.linkage.scene`)."""

    def figures(self) -> dict[str, FigureBuilder]:
        from studies.scenes.linkage.figures import valve_lift_figure  # noqa: PLC0415

        return {"valve_lift": valve_lift_figure}

    def summaries(self, ds: xr.Dataset) -> list[str]:
        from studies.scenes.linkage.summaries import linkage_status_summary  # noqa: PLC0415  (xarray on use)

        return linkage_status_summary(ds)
