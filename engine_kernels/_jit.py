"""The one place Numba options live.

Every kernel in ``engine_kernels`` is compiled through the decorators below, so caching,
floating-point contraction and the parallel switch are set once:

* ``ENGINE_KERNELS_PARALLEL=0`` turns ``prange`` loops into plain loops (useful when a Dask
  worker already owns the cores, or to debug);
* ``NUMBA_DISABLE_JIT=1`` (Numba's own switch) runs everything as plain Python, which the
  test-suite uses to check that compiled and interpreted results agree.

``fastmath={'contract'}`` only allows fused multiply-add; it never reorders sums or assumes
away NaN/Inf, so kernels keep IEEE semantics for the physics checks that rely on them.

Numba's disk cache checks only the timestamp of the file that defines a function, not of the
modules it calls (whose code it inlines). :func:`_drop_stale_cache` therefore clears the
package's cache whenever any kernel source changes, so an edit can never be served stale.
"""

from __future__ import annotations

import hashlib
import os
from pathlib import Path

import numba

FASTMATH = {"contract"}
PARALLEL = os.environ.get("ENGINE_KERNELS_PARALLEL", "1") not in ("0", "false", "False", "")
_PACKAGE = Path(__file__).resolve().parent
_STAMP = "engine_kernels.sources.sha256"


def _drop_stale_cache() -> None:
    """Delete cached machine code of this package if any kernel source changed since.

    Covers the family subpackages too: each keeps its cache in its own ``__pycache__``.
    """
    digest = hashlib.sha256()
    for source in sorted(_PACKAGE.rglob("*.py")):
        digest.update(source.relative_to(_PACKAGE).as_posix().encode() + source.read_bytes())
    cache = _PACKAGE / "__pycache__"
    stamp = cache / _STAMP
    try:
        if stamp.exists() and stamp.read_text() == digest.hexdigest():
            return
        for folder in _PACKAGE.rglob("__pycache__"):
            for stale in (*folder.glob("*.nbi"), *folder.glob("*.nbc")):
                stale.unlink(missing_ok=True)
        cache.mkdir(exist_ok=True)
        stamp.write_text(digest.hexdigest())
    except OSError:
        return  # read-only install: Numba then falls back to its own cache location


_drop_stale_cache()


def jit(func):
    """Compile a scalar kernel (no parallel loops), cached on disk."""
    return numba.njit(cache=True, fastmath=FASTMATH, nogil=True)(func)


def jit_inline(func):
    """Like :func:`jit`, but inlined into its callers at the Numba IR level.

    For small helpers inside lane (SIMD) loops: a call boundary there stops LLVM from
    vectorising the loop.
    """
    return numba.njit(cache=True, fastmath=FASTMATH, nogil=True, inline="always")(func)


def jit_lanes(func):
    """Like :func:`jit`, with NumPy's error model, for functions holding SIMD lane loops.

    Under Python's error model every float division checks its divisor and may raise, a
    branch out of the loop that stops LLVM from vectorising it; here ``x/0`` gives ±inf or
    NaN as IEEE says (a lane whose value is then discarded by a select needs no branch).
    """
    return numba.njit(cache=True, fastmath=FASTMATH, nogil=True, error_model="numpy")(func)


def batch(func):
    """Compile a batch driver whose outer loop is ``prange`` over cases.

    Numba's disk cache does not key on the ``parallel`` flag, so the serial variant is never
    cached: otherwise a cached parallel build would silently serve ``ENGINE_KERNELS_PARALLEL=0``.
    """
    return numba.njit(cache=PARALLEL, fastmath=FASTMATH, nogil=True, parallel=PARALLEL)(func)


prange = numba.prange
