"""Compiled physics kernels for engine-mechanism design studies.

Plain float/array-in, float/array-out functions in SI units (m, s, rad, N, Pa, kg), compiled
with Numba. This package never imports xarray, pandas or ``studies``: the study engine calls
into it, never the other way round (enforced by the import contract in ``nox -s lint``).
"""
