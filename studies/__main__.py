"""``python -m studies``: see :mod:`studies.cli`.

A finished command ends the process at once (:func:`leave`): the interpreter's teardown frees
every object Numba, xarray and matplotlib made (0.4 s after a 9-point run) and writes nothing
a command needs. Exit handlers run first. A live non-daemon thread, a profiler or a tracer
(cProfile, coverage: they write their files at teardown) gets a normal exit.
"""

import atexit
import contextlib
import os
import sys
import threading

from studies.cli import main
from studies.common.errors import EXIT_OUTPUT_ERROR
from studies.common.matplotlib_folder import writable_config_folder


def leave(code: int) -> None:
    """Exit with ``code`` without the interpreter's teardown (as mypy does), once the output
    streams are flushed and the exit handlers have run; a normal exit where teardown does
    something (see the module's text)."""
    others = [t for t in threading.enumerate() if t is not threading.main_thread()]
    if any(not t.daemon for t in others) or sys.getprofile() or sys.gettrace():
        raise SystemExit(code)
    atexit._run_exitfuncs()
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (BrokenPipeError, ValueError):  # a pipe closed by `| head`, as in main
            continue
        except OSError as exc:  # e.g. output redirected to a full disk: one line, a failure
            if not code:  # a command that failed has said why already
                with contextlib.suppress(OSError):
                    os.write(2, f"error: the output could not be written: {exc}\n".encode())
                code = EXIT_OUTPUT_ERROR
    os._exit(code)


if __name__ == "__main__":  # not when a worker process imports it
    writable_config_folder()
    leave(main())
