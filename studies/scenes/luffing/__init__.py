"""Scene ``luffing``: the crane-trolley drive sizing checks (physics §7): the scene, its
declarations, summary tables and figures."""

from studies.scenes.luffing.scene import LuffingScene

__all__ = ["LuffingScene"]
