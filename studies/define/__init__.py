"""What a study is: the study file parsed and validated (definition, values in SI), the designs (full factorial, orthogonal arrays) and the plan of design points.

May import: studies.scenes (the registry and the Scene interface), studies.common.
"""
