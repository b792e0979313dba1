"""Renderers of :mod:`studies.analysis.uncertainty`: the tables, sentences and figures under
noise (:mod:`.noise_report`), of a sample (:mod:`.sample_report`), of Sobol' indices
(:mod:`.sobol_report`) and of the violation map (:mod:`.violation_map`).

May import: studies.report, studies.analysis, studies.run, studies.common.
"""
