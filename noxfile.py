"""Developer and user sessions: tests, lint, studies, benchmarks.

nox -s tests                      the test-suite (what CI runs)
nox -s lint                       ruff, mypy and the import contract
nox -s study -- isac_l9 [opts]    run one catalogue study (or a TOML path)
nox -s studies                    run every shipped study
nox -s baseline                   refresh the regression baseline under tests/
nox -s bench                      benchmarks (figures printed and written to outputs/bench)
"""

from __future__ import annotations

import nox

nox.options.default_venv_backend = "venv"
nox.options.reuse_existing_virtualenvs = True
nox.options.sessions = ["tests", "lint"]

PYTHON = None  # the interpreter nox itself runs on


@nox.session(python=PYTHON)
def tests(session: nox.Session) -> None:
    """Run the test-suite."""
    session.install("-e", ".[test]")
    session.run("pytest", *session.posargs)


@nox.session(python=PYTHON)
def lint(session: nox.Session) -> None:
    """ruff (lint + format check), mypy, and the import contract of engine_kernels."""
    session.install("-e", ".[dev]")
    session.run("ruff", "check", ".")
    session.run("ruff", "format", "--check", ".")
    session.run("mypy")
    session.run("lint-imports")


@nox.session(python=PYTHON)
def study(session: nox.Session) -> None:
    """Run one study: ``nox -s study -- NAME_OR_PATH [--chunk-size N] [--outputs DIR]``."""
    if not session.posargs:
        session.error("name a study: nox -s study -- isac_l9  (python -m studies list shows all)")
    session.install("-e", ".")
    session.run("python", "-m", "studies", "run", *session.posargs)


@nox.session(python=PYTHON)
def studies(session: nox.Session) -> None:
    """Run every study in studies/catalog."""
    session.install("-e", ".")
    session.run("python", "-m", "studies", "run", "--all", *session.posargs)


@nox.session(python=PYTHON)
def baseline(session: nox.Session) -> None:
    """Refresh the regression baseline netCDF from a fresh isac_l9 run (review the diff!)."""
    session.install("-e", ".")
    session.run("python", "tests/studies/refresh_baseline.py", *session.posargs)


@nox.session(python=PYTHON)
def bench(session: nox.Session) -> None:
    """Benchmarks: print figures and write JSON under outputs/bench/."""
    session.install("-e", ".")
    session.run("python", "-m", "studies", "bench", "all", *session.posargs)
