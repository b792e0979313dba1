"""Running a plan: chunked evaluation in SIMD-sized blocks (runner), the cluster, results as labelled xarray datasets and their netCDF writer, code provenance.

May import: studies.define, studies.scenes, studies.common.
"""
