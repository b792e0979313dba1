"""Scene ``rocker``: OHC cam with a variable-ratio rocker, valve kinematics (physics §3).

The chain itself (tappet law, rocker kinematics, caches, checks) is
:class:`studies.scenes.chain.ChainScene`, which the ``valve`` scene builds on too; this scene
adds what a user of the kinematics reads: the valve-lift figure and the invalid-chain table.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from studies.scenes.chain import ChainScene

if TYPE_CHECKING:
    import xarray as xr

    from studies.scenes.base import FigureBuilder


class RockerScene(ChainScene):
    """The kinematic chain as a scene of its own (declarations in :mod:`~studies.scenes.chain`)."""

    def figures(self) -> dict[str, FigureBuilder]:
        from studies.scenes.chain_figures import valve_lift_figure  # noqa: PLC0415

        return {"valve_lift": valve_lift_figure}

    def summaries(self, ds: xr.Dataset) -> list[str]:
        from studies.scenes.chain_summaries import chain_status_summary  # noqa: PLC0415  (xarray on use)

        return chain_status_summary(ds)
