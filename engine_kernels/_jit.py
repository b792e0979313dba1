"""The one place Numba options live.

Every kernel in ``engine_kernels`` is compiled through the decorators below, so caching,
floating-point contraction and the parallel switch are set once:

* ``ENGINE_KERNELS_PARALLEL=0`` turns ``prange`` loops into plain loops (useful when a Dask
  worker already owns the cores, or to debug);
* ``NUMBA_DISABLE_JIT=1`` (Numba's own switch) runs everything as plain Python, which the
  test-suite uses to check that compiled and interpreted results agree.

``fastmath={'contract'}`` only allows fused multiply-add; it never reorders sums or assumes
away NaN/Inf, so kernels keep IEEE semantics for the physics checks that rely on them.
"""

from __future__ import annotations

import os

import numba

FASTMATH = {"contract"}
PARALLEL = os.environ.get("ENGINE_KERNELS_PARALLEL", "1") not in ("0", "false", "False", "")


def jit(func):
    """Compile a scalar kernel (no parallel loops), cached on disk."""
    return numba.njit(cache=True, fastmath=FASTMATH, nogil=True)(func)


def batch(func):
    """Compile a batch driver whose outer loop is ``prange`` over cases.

    Numba's disk cache does not key on the ``parallel`` flag, so the serial variant is never
    cached: otherwise a cached parallel build would silently serve ``ENGINE_KERNELS_PARALLEL=0``.
    """
    return numba.njit(cache=PARALLEL, fastmath=FASTMATH, nogil=True, parallel=PARALLEL)(func)


prange = numba.prange
