"""Vector lanes per SIMD register on this host, as LLVM uses them under our Numba options.

Read from a plain loop compiled like the kernels rather than from a CPU name: AVX2 gives 4
float64 / 8 float32 lanes, AVX-512 8 / 16 (or 4 / 8 where LLVM prefers 256-bit vectors on an
AVX-512 CPU), SSE 2 / 4. A forced ``NUMBA_CPU_NAME`` / ``NUMBA_CPU_FEATURES`` target changes it
the same way it changes the kernels. On a target without AVX (an SSE-only ``generic``
x86-64) LLVM keeps loops with many selects scalar; :func:`target_features` tells which.
"""

from __future__ import annotations

import re

import numba
import numpy as np
from numba.core.registry import cpu_target

from engine_kernels._jit import FASTMATH

_LLVM_TYPES = {np.dtype(np.float32): "float", np.dtype(np.float64): "double"}


def widest_vector(llvm: str, dtype: type) -> int:
    """Most lanes of any ``<n x T>`` vector of ``dtype`` in LLVM IR (1: none)."""
    element = _LLVM_TYPES[np.dtype(dtype)]
    return max((int(n) for n in re.findall(rf"<(\d+) x {element}>", llvm)), default=1)


def _scaled_sum(data, a):
    for i in range(data.size):
        data[i] = data[i] * a + a


def host_lanes(dtype: type) -> int:
    """Lanes of ``dtype`` per vector that LLVM uses for a simple loop on this host."""
    reference = numba.njit(fastmath=FASTMATH)(_scaled_sum)
    reference(np.zeros(64, dtype), np.dtype(dtype).type(2.0))
    return widest_vector(reference.inspect_llvm(reference.signatures[0]), dtype)


def target_features() -> set[str]:
    """CPU features Numba compiles for (those of ``NUMBA_CPU_NAME``/``NUMBA_CPU_FEATURES``
    when set, else the host's), e.g. ``{"+avx2", "+fma", ...}``."""
    codegen = cpu_target.target_context.codegen()
    return set(getattr(codegen, "_tm_features", "").split(","))
