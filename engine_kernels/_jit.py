"""The one place Numba options live, and where Numba is first imported.

Every kernel in ``engine_kernels`` is compiled through the decorators below, so caching,
floating-point contraction and the parallel switch are set once:

* ``ENGINE_KERNELS_PARALLEL=0`` turns ``prange`` loops into plain loops (useful when a Dask
  worker already owns the cores, or to debug);
* ``NUMBA_DISABLE_JIT=1`` (Numba's own switch) runs everything as plain Python, which the
  test-suite uses to check that compiled and interpreted results agree.

``fastmath={'contract'}`` only allows fused multiply-add; it never reorders sums or assumes
away NaN/Inf, so kernels keep IEEE semantics for the physics checks that rely on them.

Importing Numba and starting its compiler cost about a second, which a command that computes
nothing (``--help``, ``check``, ``runs``) should not pay. A decorated function is therefore a
:class:`Kernel` until the first kernel is called: then :func:`bind` imports Numba, makes every
kernel's dispatcher and puts the dispatchers in place of the :class:`Kernel` objects (and
Numba's ``prange`` in place of :data:`prange`) in the package's modules, so compiled code only
ever sees Numba's own objects. A :class:`Kernel` held elsewhere forwards to its dispatcher.

Numba's disk cache checks only the timestamp of the file that defines a function, not of the
modules it calls (whose code it inlines). :func:`_drop_stale_cache` therefore clears the
package's cache whenever any kernel source changes, so an edit can never be served stale.
"""

from __future__ import annotations

import contextlib
import functools
import hashlib
import importlib
import os
import sys
import threading
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import numpy as np

FASTMATH = {"contract"}
PARALLEL = os.environ.get("ENGINE_KERNELS_PARALLEL", "1") not in ("0", "false", "False", "")
_PACKAGE = Path(__file__).resolve().parent
_STAMP = "engine_kernels.sources.sha256"
_OPTIONS: dict[str, Any] = {"fastmath": FASTMATH, "nogil": True}


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


class prange:
    """``range`` until :func:`bind` puts ``numba.prange`` in its place in every kernel module."""

    def __new__(cls, *args: int) -> range:  # type: ignore[misc]
        return range(*args)


class Kernel:
    """A kernel function and its Numba options; compiled through Numba once one is called.

    ``py_func`` is the plain Python function (as on a Numba dispatcher). Calling the kernel, or
    reading any other dispatcher attribute, binds Numba first (:func:`bind`).
    """

    def __init__(self, func: Callable[..., Any], options: dict[str, Any]) -> None:
        functools.update_wrapper(self, func)
        self.py_func = func
        self.options = options
        self.dispatcher: Any = None
        _KERNELS.append(self)

    def __call__(self, *args: Any) -> Any:
        if self.dispatcher is None:
            if _PLAIN.depth:
                return self.py_func(*args)
            bind()
        return self.dispatcher(*args)

    def __getattr__(self, name: str) -> Any:
        if name.startswith("__") or name == "dispatcher":
            raise AttributeError(name)
        if self.dispatcher is None:
            bind()
        return getattr(self.dispatcher, name)

    def __reduce__(self) -> tuple[Any, tuple[str, str]]:
        return _kernel_named, (self.py_func.__module__, self.py_func.__qualname__)

    def __repr__(self) -> str:
        return f"<kernel {self.py_func.__module__}.{self.py_func.__qualname__}>"


def _kernel_named(module: str, qualname: str) -> Any:
    return getattr(importlib.import_module(module), qualname)


class _Plain(threading.local):
    depth = 0  # > 0 while call_small runs a kernel as plain Python in this thread
    left: int | None = None  # evaluations left inside without_compiler(); None outside it


_PLAIN = _Plain()
INTERPRETED_WORK = 100_000
"""Most inner evaluations :func:`call_small` runs as plain Python: about 0.75 s at the 7.5 µs an
evaluation of a cam law takes there, less than starting Numba's compiler and loading a kernel."""
EVALUATIONS = "kernel evaluations"
COMBINATIONS = "distinct combinations"
QUICK_COMBINATIONS = 4_000_000
"""Distinct combinations a check examines inside :func:`without_compiler` (NumPy grouping of
4·10⁶ rows: about 0.5 s)."""
QUICK_WORK = 120_000
"""Inner evaluations :func:`without_compiler` allows in all: about 0.4 s of plain Python at the
3.3 µs an evaluation of the six-segment cam law takes there (the analytic laws: 1.7-2 µs)."""


class CompilerNeeded(RuntimeError):
    """Raised inside :func:`without_compiler` by a kernel call that would start Numba's compiler
    or exceed the plain-Python budget; ``work`` is the call's count of inner evaluations (0: a
    direct kernel call, whose work is not counted)."""

    def __init__(self, work: int, what: str = EVALUATIONS) -> None:
        super().__init__(f"{work} {what}: more than a quick check may take on")
        self.work = work
        self.what = what  # what ``work`` counts


def claim_combinations(count: int) -> None:
    """Inside :func:`without_compiler`, raise :class:`CompilerNeeded` at once if a check would
    examine more than :data:`QUICK_COMBINATIONS` distinct combinations (their grouping alone
    takes O(count log count) time)."""
    if _PLAIN.left is not None and count > QUICK_COMBINATIONS:
        raise CompilerNeeded(count, COMBINATIONS)


def claim(work: int, what: str = EVALUATIONS) -> None:
    """Inside :func:`without_compiler`, raise :class:`CompilerNeeded` at once if ``work``
    (kernel evaluations, or ``what`` else: items each needing at least one) exceeds the
    evaluations left: a caller about to prepare the inputs of that many (O(work) time and
    memory) learns first that it will not be allowed to evaluate them."""
    left = _PLAIN.left
    if left is not None and work > left:
        raise CompilerNeeded(work, what)


@contextlib.contextmanager
def without_compiler(budget: int = QUICK_WORK) -> Iterator[None]:
    """Within: :func:`call_small` runs at most ``budget`` inner evaluations in all (in this
    thread), as plain Python while Numba is not bound; a call beyond that, one that Python
    cannot finish where compiled code gives NaN or ±inf, and any call that would bind Numba
    raise :class:`CompilerNeeded`. A command that must answer at once (``check``) says what it
    left unchecked instead of starting the compiler. Nested, it draws on the outer budget."""
    outer = _PLAIN.left
    start = budget if outer is None else min(budget, outer)
    _PLAIN.left = start
    try:
        yield
    finally:
        spent = start - _PLAIN.left
        _PLAIN.left = None if outer is None else outer - spent


def call_small(kernel: Any, work: int, *args: Any) -> Any:
    """``kernel(*args)``, run as plain Python while Numba is not bound and ``work`` (a count of
    the kernel's inner evaluations) is at most :data:`INTERPRETED_WORK`: a command that checks a
    few cams or linkages then answers without starting Numba's compiler.

    Python raises where compiled code gives NaN or ±inf (``math.sqrt(-1)``, ``x / 0``): such a
    call is run again compiled, which overwrites every output, so the answer is the compiled
    one up to the rounding of fused multiply-adds.
    """
    if _PLAIN.left is not None:
        return _within_budget(kernel, work, args)
    if _numba is None and work <= INTERPRETED_WORK:
        with contextlib.suppress(ArithmeticError, ValueError, TypeError), np.errstate(all="ignore"):
            return _plain(kernel, args)
    return kernel(*args)  # compiled: Numba bound, much work, or plain Python raised above


def _within_budget(kernel: Any, work: int, args: tuple[Any, ...]) -> Any:
    """:func:`call_small` inside :func:`without_compiler`."""
    left = _PLAIN.left
    assert left is not None
    if work > left:
        raise CompilerNeeded(work)
    _PLAIN.left = left - work
    if _numba is not None:
        return kernel(*args)  # already compiled in this process: no compiler to start
    try:
        with np.errstate(all="ignore"):
            return _plain(kernel, args)
    except (ArithmeticError, ValueError, TypeError) as exc:
        raise CompilerNeeded(work) from exc


def _plain(kernel: Any, args: tuple[Any, ...]) -> Any:
    _PLAIN.depth += 1
    try:
        return kernel.py_func(*args)
    finally:
        _PLAIN.depth -= 1


_KERNELS: list[Kernel] = []
_LOCK = threading.Lock()
_numba: Any = None


def bound() -> bool:
    """True once Numba is imported and the kernels are its dispatchers."""
    return _numba is not None


def bind() -> None:
    """Import Numba, make the dispatcher of every kernel defined so far, and put the
    dispatchers (and ``numba.prange``) in place of their stand-ins in the kernel modules."""
    global _numba  # noqa: PLW0603  (once per process, under the lock)
    if _numba is None and _PLAIN.left is not None:
        raise CompilerNeeded(0)
    with _LOCK:
        if _numba is not None:
            return
        _drop_stale_cache()
        import numba  # noqa: PLC0415  (the point of this module: Numba on first use)

        for kernel in _KERNELS:
            kernel.dispatcher = numba.njit(**kernel.options)(kernel.py_func)
        stand_ins = {id(prange): numba.prange}
        for kernel in _KERNELS:
            stand_ins[id(kernel)] = kernel.dispatcher
        for name, module in list(sys.modules.items()):
            if name.partition(".")[0] == __package__ and module is not None:
                _replace_stand_ins(vars(module), stand_ins)
        _numba = numba


def _replace_stand_ins(namespace: dict[str, Any], stand_ins: dict[int, Any]) -> None:
    """Put Numba's objects in place of the stand-ins (keyed by ``id``) in ``namespace``."""
    for key, value in list(namespace.items()):
        if id(value) in stand_ins:
            namespace[key] = stand_ins[id(value)]


def _decorate(func: Callable[..., Any], **options: Any) -> Any:
    options = {**_OPTIONS, **options}
    if _numba is not None:
        return _numba.njit(**options)(func)
    return Kernel(func, options)


def jit(func: Callable[..., Any]) -> Any:
    """Compile a scalar kernel (no parallel loops), cached on disk."""
    return _decorate(func, cache=True)


def jit_inline(func: Callable[..., Any]) -> Any:
    """Like :func:`jit`, but inlined into its callers at the Numba IR level.

    For small helpers inside lane (SIMD) loops: a call boundary there stops LLVM from
    vectorising the loop.
    """
    return _decorate(func, cache=True, inline="always")


def jit_lanes(func: Callable[..., Any]) -> Any:
    """Like :func:`jit`, with NumPy's error model, for functions holding SIMD lane loops.

    Under Python's error model every float division checks its divisor and may raise, a
    branch out of the loop that stops LLVM from vectorising it; here ``x/0`` gives ±inf or
    NaN as IEEE says (a lane whose value is then discarded by a select needs no branch).
    """
    return _decorate(func, cache=True, error_model="numpy")


def batch(func: Callable[..., Any]) -> Any:
    """Compile a batch driver whose outer loop is ``prange`` over cases.

    Numba's disk cache does not key on the ``parallel`` flag, so the serial variant is never
    cached: otherwise a cached parallel build would silently serve ``ENGINE_KERNELS_PARALLEL=0``.
    """
    return _decorate(func, cache=PARALLEL, parallel=PARALLEL)
