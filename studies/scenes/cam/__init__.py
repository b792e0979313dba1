"""Scene ``cam``: flat-faced tappet cam kinematics and contact criteria (physics §2): the scene
(``scene``), its declarations (``parameters``), measured lift tables (``lift_tables``) and
figures (``figures``)."""

from studies.scenes.cam.scene import CamScene

__all__ = ["CamScene"]
