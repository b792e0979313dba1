"""Provenance of the code: the engine's git commit is its own repository's only, and the source
hash, not the commit, tells an edited copy of the engine from the original."""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from studies.run import provenance

ROOT = Path(__file__).resolve().parents[2]
PRINT_STATE = (
    "import json; from studies.run import provenance as p; "
    "print(json.dumps([p.git_state(), p.engine_code()['source_sha256']]))"
)


def git(cwd: Path, *args: str) -> str:
    return subprocess.run(
        ["git", "-c", "user.name=t", "-c", "user.email=t@example.org", *args],
        cwd=cwd,
        check=True,
        capture_output=True,
        text=True,
    ).stdout.strip()


def state_of_copy(root: Path) -> tuple[list, str]:
    """(git_state, engine source hash) as a copy of the engine under ``root`` sees them."""
    done = subprocess.run(
        [sys.executable, "-c", PRINT_STATE],
        cwd=root,  # the copy's packages come first on sys.path
        env={"PATH": "/usr/bin:/bin"},
        capture_output=True,
        text=True,
        check=True,
    )
    state, source = json.loads(done.stdout)
    return state, source


def copy_engine(to: Path) -> Path:
    for package in provenance.ENGINE_PACKAGES:
        shutil.copytree(ROOT / package, to / package, ignore=shutil.ignore_patterns("__pycache__"))
    shutil.copy(ROOT / "pyproject.toml", to / "pyproject.toml")
    return to


def test_inside_a_users_git_repository_no_commit_is_recorded_and_edits_change_the_hash(
    tmp_path: Path,
) -> None:
    if shutil.which("git") is None:
        pytest.skip("git is not installed")
    user = tmp_path / "user_project"
    engine = copy_engine(user / "vendor" / "engine")
    git(user, "init", "--quiet")
    git(user, "add", ".")
    git(user, "commit", "--quiet", "-m", "the user's own commit")
    state, source = state_of_copy(engine)
    assert state == ["", False]  # the user's commit is not the engine's
    # same files, same bytes: the same hash as this checkout
    assert source == provenance.engine_code()["source_sha256"]

    kernel = engine / "engine_kernels" / "cam" / "contact.py"
    kernel.write_text(kernel.read_text(encoding="utf-8") + "\n# an edit\n", encoding="utf-8")
    _, edited = state_of_copy(engine)
    assert edited != source  # uncommitted and outside any commit: the hash still sees it


def test_the_engines_own_checkout_records_its_commit() -> None:
    if shutil.which("git") is None or not (ROOT / ".git").exists():
        pytest.skip("not running from a git checkout of the engine")
    commit, _ = provenance.git_state()
    assert commit == git(ROOT, "rev-parse", "HEAD")
