"""The errors a user can act on, and the exit code each gives.

The command line prints these in one line and exits with the error's :attr:`exit_code`;
anything else that escapes a command is a bug in the engine or a scene, shown with its
traceback. Each subclasses the built-in error it refines (``ValueError``, ``KeyError``,
``OSError``), so library code that catches those keeps working.
"""

from __future__ import annotations

EXIT_STUDY_ERROR = 2  # the input: a study file, an argument, a run reference
EXIT_OUTPUT_ERROR = 4  # the environment: outputs folder, registry, disk


class EngineError(Exception):
    """An error the user can act on (see the module docstring)."""

    exit_code = EXIT_STUDY_ERROR

    def __str__(self) -> str:  # the message as written (KeyError would quote it)
        return str(self.args[0]) if self.args else ""


class StudyError(EngineError, ValueError):
    """A study file, a command's argument or a requested analysis that cannot be used as
    given: nothing was run or written."""


class UnknownScene(StudyError, KeyError):
    """No scene, built in or from a plugin, has this name."""


class RunNotFound(EngineError, KeyError):
    """No run, or no single run, answers to the id, tag or folder given."""


class RunStateError(EngineError, ValueError):
    """A run whose state refuses the command: still running, already finished, moved by
    another process meanwhile, or changed since it started."""


class ClusterError(EngineError, ValueError):
    """The Dask scheduler cannot be reached, or its workers run other code than this process."""


class OutputsError(EngineError, OSError):
    """The outputs folder, the registry or a run's files cannot be read or written as needed."""

    exit_code = EXIT_OUTPUT_ERROR


class StudyFileError(StudyError):
    """A study that cannot run; ``problems`` lists every reason, one sentence each."""

    def __init__(self, source: str, problems: list[str]) -> None:
        self.source = source
        self.problems = problems
        lines = "\n".join(f"  - {p}" for p in problems)
        n = len(problems)
        super().__init__(f"study {source} has {n} problem{'s' if n != 1 else ''}:\n{lines}")


class NotDrawn(Exception):
    """A figure the results give no readable picture of (a factor with too many levels to lay
    out); the message says which and why in one line, which the run records as a warning."""
