"""Scene ``reed``: reed-valve natural frequencies and margins to the excitation band (physics.md
§6): the scene, its summary table, figures and the Campbell diagram."""

from studies.scenes.reed.scene import ReedScene

__all__ = ["ReedScene"]
