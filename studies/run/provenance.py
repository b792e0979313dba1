"""Where a result came from: the code that computed it, git commit and dirty flag, package
versions, host.

The code of a run is the engine's and its scene's installed source files, each hashed
(SHA-256 over every file's path and bytes), with the distribution name and version they came
from, and the versions of the libraries that compute (numba, numpy, scipy, Python). Its hash,
:func:`code_hash`, is half the cache key (the definition's hash is the other half): an edit to
a scene plugin or to this package, committed or not, versioned or not, is never served a
result computed by the code before it.
"""

from __future__ import annotations

import hashlib
import importlib.util
import json
import platform
import subprocess
import sys
import tomllib
from collections.abc import Iterable
from functools import cache
from importlib import metadata
from pathlib import Path
from typing import Any

ENGINE = "engine-studies"
ENGINE_PACKAGES = ("studies", "engine_kernels")
PACKAGES = (
    ENGINE,
    "numba",
    "numpy",
    "scipy",
    "xarray",
    "netCDF4",
    "pandas",
    "matplotlib",
)
LIBRARIES = ("numba", "llvmlite", "numpy", "scipy")  # what computes a result: in the cache key
SOURCE_ROOT = Path(__file__).resolve().parents[2]
SKIPPED_SUFFIXES = {".pyc", ".pyo", ".so", ".nbi", ".nbc"}  # compiled or cached, not source
NO_COMMIT = ""


@cache
def git_state() -> tuple[str, bool]:
    """(commit, dirty) of the engine's own git repository, ``("", False)`` when the engine does
    not run from it: installed as a package, or inside another project's repository (whose
    commit says nothing about this code; the source hash covers it either way)."""
    try:
        top = _git("rev-parse", "--show-toplevel")
        if Path(top).resolve() != SOURCE_ROOT or not _is_engine_project(SOURCE_ROOT):
            return NO_COMMIT, False
        commit = _git("rev-parse", "HEAD")
        status = _git(
            "status",
            "--porcelain",
            "--untracked-files=no",
            "--",
            *ENGINE_PACKAGES,
            "pyproject.toml",
        )
    except (OSError, subprocess.SubprocessError):
        return NO_COMMIT, False
    return commit, bool(status)


def _git(*args: str) -> str:
    return subprocess.run(
        ["git", *args], cwd=SOURCE_ROOT, capture_output=True, text=True, check=True, timeout=10
    ).stdout.strip()


def _is_engine_project(root: Path) -> bool:
    try:
        project = tomllib.loads((root / "pyproject.toml").read_text(encoding="utf-8"))
    except (OSError, tomllib.TOMLDecodeError):
        return False
    return bool(project.get("project", {}).get("name") == ENGINE)


def versions() -> dict[str, str]:
    out = {"python": platform.python_version()}
    for name in PACKAGES:
        out[name] = _version(name) or "not installed"
    return out


def _version(distribution: str) -> str:
    try:
        return metadata.version(distribution)
    except metadata.PackageNotFoundError:
        return ""


def host() -> dict[str, str]:
    return {"node": platform.node(), "machine": platform.machine(), "system": platform.system()}


def source_files(path: Path) -> list[Path]:
    """The source files of a package folder (every file but compiled and cached ones) or the
    module file itself, sorted."""
    if path.is_file():
        return [path]
    return sorted(
        p
        for p in path.rglob("*")
        if p.is_file() and "__pycache__" not in p.parts and p.suffix not in SKIPPED_SUFFIXES
    )


def tree_sha256(root: Path, files: Iterable[Path]) -> str:
    """SHA-256 over each file's path relative to ``root`` and its bytes."""
    digest = hashlib.sha256()
    for path in files:
        digest.update(path.relative_to(root).as_posix().encode("utf-8") + b"\0")
        digest.update(hashlib.sha256(path.read_bytes()).digest())
    return digest.hexdigest()


@cache
def engine_code() -> dict[str, str]:
    """This package's distribution, version and the hash of its source (``studies`` and
    ``engine_kernels``: every built-in scene and kernel)."""
    files = [f for name in ENGINE_PACKAGES for f in source_files(SOURCE_ROOT / name)]
    return {
        "distribution": ENGINE,
        "version": _version(ENGINE),
        "source_sha256": tree_sha256(SOURCE_ROOT, files),
    }


def scene_code(scene_class: type) -> dict[str, Any]:
    """The code of a scene: for a built-in scene the engine's, for a plugin its distribution,
    version and the hash of the source of every top-level package and module the distribution
    provides (the scene's own package whatever its distribution)."""
    name = str(getattr(scene_class, "name", scene_class.__name__))
    source = Path(sys.modules[scene_class.__module__].__file__ or "").resolve()
    if source.is_relative_to(SOURCE_ROOT / "studies"):
        return {"scene": name, "plugin": False, **engine_code()}
    return {"scene": name, "plugin": True, **_plugin_code(scene_class, source)}


@cache
def _plugin_code(scene_class: type, source: Path) -> dict[str, str]:
    top = scene_class.__module__.split(".", 1)[0]
    distribution = _distribution_of(top)
    names = _import_names(distribution) if distribution else []
    roots = {name: _source_root(name) for name in sorted({top, *names})}
    roots[top] = roots[top] or source
    digest = hashlib.sha256()
    for name, root in roots.items():
        if root is not None:
            package = root.parent if root.name == "__init__.py" else root
            files = source_files(package)
            digest.update(f"{name}\0{tree_sha256(package.parent, files)}\n".encode())
    return {
        "distribution": distribution,
        "version": _version(distribution) if distribution else "",
        "source_sha256": digest.hexdigest(),
    }


def _distribution_of(top_level: str) -> str:
    """The installed distribution that provides the import name ``top_level`` ("" if none)."""
    names = metadata.packages_distributions().get(top_level, [])
    return names[0] if names else ""


def _import_names(distribution: str) -> list[str]:
    """Every top-level import name ``distribution`` provides: a plugin's scene may import a
    module of its own distribution beside its package, whose edit must count too."""
    provided = metadata.packages_distributions()
    return [name for name, owners in provided.items() if distribution in owners]


def _source_root(name: str) -> Path | None:
    """The file of the top-level module ``name`` or its package's ``__init__.py`` (the folder
    of a namespace package), found without importing it; None if it cannot be found."""
    file = getattr(sys.modules.get(name), "__file__", None)
    if file:
        return Path(file).resolve()
    try:
        spec = importlib.util.find_spec(name)
    except (ImportError, ValueError):
        return None
    if spec is None:
        return None
    if spec.origin and spec.origin not in ("built-in", "frozen", "namespace"):
        return Path(spec.origin).resolve()
    locations = list(spec.submodule_search_locations or [])
    return Path(locations[0]).resolve() if locations else None


def libraries() -> dict[str, str]:
    """The versions of Python and of the libraries that compute (:data:`LIBRARIES`)."""
    return {"python": platform.python_version()} | {
        n: _version(n) or "not installed" for n in LIBRARIES
    }


def code(scene_class: type) -> dict[str, Any]:
    """Everything that computed a run of a scene: the engine, the scene and the libraries."""
    return {"engine": engine_code(), "scene": scene_code(scene_class), "libraries": libraries()}


def code_hash(recorded: dict[str, Any]) -> str:
    """The cache key's code half: SHA-256 of :func:`code`'s record."""
    return hashlib.sha256(json.dumps(recorded, sort_keys=True).encode("utf-8")).hexdigest()


def describe_scene_code(entry: dict[str, Any]) -> str:
    """One scene's code in words: ``plugin engine-studies-oscillator 0.1.0, source 1a2b3c4d``."""
    if not entry:
        return "not recorded"
    origin = "plugin" if entry.get("plugin") else "built-in"
    distribution = entry.get("distribution") or "no distribution"
    version = entry.get("version") or "?"
    return f"{origin} {distribution} {version}, source {str(entry.get('source_sha256', ''))[:8]}"
