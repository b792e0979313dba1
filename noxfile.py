"""Developer and user sessions: tests, lint, studies, benchmarks.

nox -s tests                      the test-suite (what CI runs)
nox -s lint                       ruff, mypy and the import contract
nox -s study -- isac_l9 [opts]    run one catalogue study (or a TOML path)
nox -s studies                    run every shipped study
nox -s baseline                   refresh the regression baseline under tests/
nox -s bench                      benchmarks (figures printed and written to outputs/bench)

``study``, ``studies``, ``bench`` and ``baseline`` share one environment (``.nox/run``); each
environment installs the package (editable) once and again only when ``pyproject.toml``
changes, so a second session starts in seconds.
"""

from __future__ import annotations

import hashlib
import os
import sys
from pathlib import Path

import nox

nox.options.default_venv_backend = "venv"
nox.options.reuse_existing_virtualenvs = True
nox.options.sessions = ["tests", "lint"]

PYTHON = None  # the interpreter nox itself runs on
HERE = Path(__file__).parent
SHARED = HERE / ".nox" / "run"  # the environment the user-facing sessions share
PARALLEL = ("-n", "auto", "--maxprocesses", "4", "--dist", "loadfile")
"""The whole suite in up to 4 processes (one per core), each test file in one of them (its
module fixtures built once); a run with arguments (``nox -s tests -- FILE``) is one process."""


def _install_once(session: nox.Session, python: Path, target: str) -> None:
    """``pip install -e target`` into the environment of ``python`` unless it was installed
    from this very ``pyproject.toml`` already (a stamp beside the environment records it)."""
    digest = hashlib.sha256((HERE / "pyproject.toml").read_bytes()).hexdigest()
    stamp = python.parent.parent / f"installed-{target.strip('.[]') or 'core'}.sha256"
    if stamp.exists() and stamp.read_text(encoding="utf-8") == digest:
        return
    # run_install: also under --install-only (a skipped install must not write the stamp)
    session.run_install(str(python), "-m", "pip", "install", "--quiet", "-e", target, external=True)
    stamp.write_text(digest, encoding="utf-8")


def _compile_sources(session: nox.Session, python: Path | str) -> None:
    """Byte-compile the package's sources (only files changed since their last compile).
    The install is editable, so its modules are read from the checkout; where the
    environment forbids writing bytecode (``PYTHONDONTWRITEBYTECODE``) every command would
    otherwise compile the modules it imports again (85 for a cam study: importing the
    pipeline took 1.31 s instead of 1.15 s, mean of 5 interleaved)."""
    sources = [str(HERE / name) for name in ("studies", "engine_kernels")]
    session.run(str(python), "-m", "compileall", "-q", *sources, external=True, silent=True)


def _own_python(session: nox.Session) -> Path:
    return Path(session.virtualenv.location) / ("Scripts" if os.name == "nt" else "bin") / "python"


def _shared_python(session: nox.Session) -> str:
    """The interpreter of the shared environment, made and installed on first use."""
    python = SHARED / ("Scripts" if os.name == "nt" else "bin") / "python"
    if not python.exists():
        session.run(sys.executable, "-m", "venv", str(SHARED), external=True)
    _install_once(session, python, ".")
    _compile_sources(session, python)
    return str(python)


@nox.session(python=PYTHON)
def tests(session: nox.Session) -> None:
    """Run the test-suite."""
    _install_once(session, _own_python(session), ".[test]")
    _compile_sources(session, _own_python(session))
    session.run("pytest", *(session.posargs or PARALLEL))


@nox.session(python=PYTHON)
def lint(session: nox.Session) -> None:
    """ruff (lint + format check), mypy, and the import contract of engine_kernels."""
    _install_once(session, _own_python(session), ".[dev]")
    session.run("ruff", "check", ".")
    session.run("ruff", "format", "--check", ".")
    session.run("mypy")
    session.run("lint-imports")


@nox.session(venv_backend="none")
def study(session: nox.Session) -> None:
    """Run one study: ``nox -s study -- NAME_OR_PATH [--chunk-size N] [--outputs DIR]``."""
    if not session.posargs:
        session.error("name a study: nox -s study -- isac_l9  (python -m studies list shows all)")
    session.run(_shared_python(session), "-m", "studies", "run", *session.posargs, external=True)


@nox.session(venv_backend="none")
def studies(session: nox.Session) -> None:
    """Run every study in studies/catalog."""
    python = _shared_python(session)
    session.run(python, "-m", "studies", "run", "--all", *session.posargs, external=True)


@nox.session(venv_backend="none")
def baseline(session: nox.Session) -> None:
    """Refresh the regression baseline netCDF from a fresh isac_l9 run (review the diff!)."""
    python = _shared_python(session)
    session.run(python, "tests/studies/refresh_baseline.py", *session.posargs, external=True)


@nox.session(venv_backend="none")
def bench(session: nox.Session) -> None:
    """Benchmarks: print figures and write JSON under outputs/bench/."""
    python = _shared_python(session)
    session.run(python, "-m", "studies", "bench", "all", *session.posargs, external=True)
