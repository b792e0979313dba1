"""Scene ``crank``: slider-crank kinematics, forces, torque and multi-cylinder harmonics
(physics §5): the scene, its declarations, pressure tables and figures."""

from studies.scenes.crank.scene import CrankScene

__all__ = ["CrankScene"]
