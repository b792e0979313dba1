"""Scene ``rocker``: OHC cam with a variable-ratio rocker, valve kinematics (physics §3)."""

from studies.scenes.rocker.scene import RockerScene

__all__ = ["RockerScene"]
