"""Scenes ``valve`` (valve-train dynamics through the rocker: jump, bounce, seating, jump
speed; physics §4) and ``valve_accuracy`` (the dynamics against an independent scipy reference,
per integrator and step) and ``valve_spring_ladder`` (the dynamics per rung of the spring-model
ladder, lumped to N coil masses [V4], with the cost of each): the scenes, their declarations, figures, summary table, the
reference solvers (``reference``) and the accuracy measurements (``reference.accuracy``), the figures (``figures``).

Each scene is imported from its own module (``scene``, ``accuracy``, ``ladder``) when it is
looked up, so a ``valve`` study never loads the scipy reference solvers."""
