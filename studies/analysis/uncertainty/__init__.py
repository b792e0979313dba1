"""Statistics of uncertainty: each design point's distribution under noise
(:mod:`.noise_statistics`), the moments and correlations of a Sobol' or Latin-hypercube sample
(:mod:`.sample_statistics`), Saltelli's Sobol' indices (:mod:`.sobol_indices`) and the
probability of violation over two control factors (:mod:`.violation_map`).

May import: studies.analysis, studies.run, studies.define, studies.scenes, studies.common.
"""
