"""What the numbers say, computed once in O(N): range analysis, S/N, ANOVA and sums of squares, sensitivity, predictions for arrays, best computed points for grids, the trade-off and the confirmation/refinement study.

May import: studies.run, studies.define, studies.scenes, studies.common.
"""
