"""A run's checkpoints and record, validated before a resume trusts them.

Each finished chunk of design points is saved as ``chunks/<index>.npz``: one array per response
(``scalar:<name>``) and per curve (``curve:<name>``), plus ``meta:version`` and
``meta:runs`` (the chunk's first and past-the-end design point). Before a resume uses a chunk,
:func:`load_chunk` checks that it is that chunk of that plan: version, design points, exactly
the plan's responses and curves, one value per design point (and the curve's width), numbers
only. ``run.json`` is checked by :func:`read_run_record`: an object with the record's keys and
value types. Anything else is refused in one sentence that names the file and what to do; the
other checkpoints stay.
"""

from __future__ import annotations

import dataclasses
import json
import zipfile
import zlib
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from studies.common.errors import OutputsError, RunStateError
from studies.scenes import SceneOutput
from studies.tracking.records import RunRecord

if TYPE_CHECKING:
    from studies.define.plan import Plan

CHECKPOINT_VERSION = 2  # 1: no meta arrays (before validation)
REDO = "delete it and resume: its design points are computed again"
FIELD_TYPES = {"str": str, "int": int, "bool": bool, "float": float}


class DamagedCheckpoint(OutputsError):
    """A checkpoint chunk file that cannot be decoded or does not belong to the run."""


def save_chunk(path: Path, part: slice, out: SceneOutput) -> None:
    """Write chunk ``path`` (design points ``part``) under a temporary name renamed into
    place: a chunk file is either complete or absent."""
    path.parent.mkdir(exist_ok=True)
    arrays: dict[str, np.ndarray] = {f"scalar:{k}": v for k, v in out.scalars.items()}
    arrays |= {f"curve:{k}": v for k, v in out.curves.items()}
    arrays["meta:version"] = np.array(CHECKPOINT_VERSION)
    arrays["meta:runs"] = np.array([part.start, part.stop])
    tmp = path.with_suffix(".tmp.npz")
    np.savez(tmp, **arrays)  # type: ignore[arg-type]
    tmp.replace(path)


def checkpoint_bytes(plan: Plan) -> int:
    """Bytes the chunk checkpoints of ``plan`` hold once every chunk is in: each computed
    point's responses and curve values, 8 bytes each, uncompressed (``chunks/`` of a run
    folder, kept until ``results.nc`` is complete, so a run needs at least this much disk)."""
    width = plan.scene.curve_coordinate(plan.settings).size if plan.definition.curves else 0
    per_case = len(plan.responses) + len(plan.definition.curves) * width
    return 8 * per_case * plan.cases


def load_chunk(
    path: Path, part: slice, responses: tuple[str, ...], curves: dict[str, int]
) -> SceneOutput:
    """Chunk ``path`` if it holds design points ``part`` with exactly ``responses`` and the
    ``curves`` (name → width); OSError if unreadable, :class:`DamagedCheckpoint` otherwise."""
    try:
        with path.open("rb") as file, np.load(file) as data:  # file: closed even if damaged
            arrays = {key: data[key] for key in data.files}
    except (ValueError, EOFError, KeyError, zipfile.BadZipFile, zlib.error) as exc:
        msg = f"checkpoint {path} is damaged ({type(exc).__name__}: {exc}); {REDO}"
        raise DamagedCheckpoint(msg) from None
    problem = _problem(arrays, part, responses, curves)
    if problem:
        raise DamagedCheckpoint(
            f"checkpoint {path} does not belong to this run ({problem}); {REDO}"
        )
    scalars = {k.split(":", 1)[1]: v for k, v in arrays.items() if k.startswith("scalar:")}
    curve_values = {k.split(":", 1)[1]: v for k, v in arrays.items() if k.startswith("curve:")}
    return SceneOutput(scalars, curve_values)


def _problem(
    arrays: dict[str, np.ndarray], part: slice, responses: tuple[str, ...], curves: dict[str, int]
) -> str:
    version = arrays.get("meta:version")
    if version is None or version.shape != () or int(version) != CHECKPOINT_VERSION:
        shown = "none" if version is None else str(version.tolist())
        return f"checkpoint version {shown}, expected {CHECKPOINT_VERSION}"
    runs = arrays.get("meta:runs")
    if runs is None or runs.tolist() != [part.start, part.stop]:
        held = "unknown" if runs is None else str(runs.tolist())
        return f"design points {held}, expected [{part.start}, {part.stop}]"
    expected = {f"scalar:{r}" for r in responses} | {f"curve:{c}" for c in curves}
    held_keys = {k for k in arrays if not k.startswith("meta:")}
    if held_keys != expected:
        missing, extra = sorted(expected - held_keys), sorted(held_keys - expected)
        return "; ".join(
            f"{what} {', '.join(keys)}"
            for what, keys in (("missing", missing), ("unexpected", extra))
            if keys
        )
    n = part.stop - part.start
    for key in sorted(expected):
        values = arrays[key]
        name = key.split(":", 1)[1]
        shape = (n,) if key.startswith("scalar:") else (n, curves[name])
        if values.shape != shape:
            return f"{key} has shape {values.shape}, expected {shape}"
        if values.dtype.kind not in "biuf":
            return f"{key} holds {values.dtype} values, not numbers"
    return ""


def read_run_record(path: Path) -> RunRecord:
    """The :class:`RunRecord` of ``run.json`` (ValueError naming the file and the first
    problem: not JSON, not an object, a missing, unknown or mistyped key)."""
    try:
        raw = json.loads(path.read_text(encoding="utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise RunStateError(f"{path} is not a run record: {exc}") from None
    problem = _record_problem(raw)
    if problem:
        raise RunStateError(f"{path} is not a run record ({problem}): it was not resumed")
    return RunRecord(**raw)


def _record_problem(raw: Any) -> str:
    if not isinstance(raw, dict):
        return f"a JSON {type(raw).__name__}, expected an object"
    fields = {f.name: f for f in dataclasses.fields(RunRecord)}
    unknown = sorted(set(raw) - set(fields))
    if unknown:
        return f"unknown key {', '.join(map(repr, unknown))}"
    required = [
        name
        for name, f in fields.items()
        if f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING
    ]
    missing = [name for name in required if name not in raw]
    if missing:
        return f"missing key {', '.join(map(repr, missing))}"
    for name, value in raw.items():
        kind = str(fields[name].type).split("[", 1)[0]
        expected = dict if kind == "dict" else FIELD_TYPES.get(kind)
        if expected is None:
            continue
        ok = isinstance(value, expected) and not (expected is int and isinstance(value, bool))
        if expected is float:
            ok = isinstance(value, int | float) and not isinstance(value, bool)
        if not ok:
            return f"{name} = {json.dumps(value)[:40]} should be of type {kind}"
    return ""
