"""How far a response may move: ``rtol``/``atol`` per response, from the command line or a TOML
file, shared by ``compare`` (what "moved" means) and ``regress`` (what fails).

A value is within tolerance when ``|value - reference| <= atol + rtol * |reference|`` (the
criterion of ``numpy.isclose``); NaN matches NaN, and ``rtol = inf`` skips a response (a
wall-clock timing). The file holds one table per response::

    [max_contact_stress]   # MPa
    rtol = 1e-6
    [cost_per_case]
    rtol = inf
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from studies.common.bounded_files import TABLE_FILE_BYTES, read_bounded_text
from studies.common.errors import StudyError

DEFAULT_RTOL = 1e-7
DEFAULT_ATOL = 0.0


@dataclass(frozen=True)
class Tolerance:
    rtol: float = DEFAULT_RTOL
    atol: float = DEFAULT_ATOL


DEFAULT = Tolerance()


def read_tolerances(path: Path) -> dict[str, Tolerance]:
    """``[response] rtol = …, atol = …`` tables of a TOML file (ValueError on anything else)."""
    try:
        raw = tomllib.loads(read_bounded_text(path, "--tolerances", TABLE_FILE_BYTES))
    except tomllib.TOMLDecodeError as exc:
        raise StudyError(f"{path}: not valid TOML ({exc})") from None
    out = {}
    for name, table in raw.items():
        unknown = set(table) - {"rtol", "atol"} if isinstance(table, dict) else {"(not a table)"}
        if unknown:
            msg = f"{path}: [{name}] may hold rtol and atol only, not {', '.join(sorted(unknown))}"
            raise StudyError(msg)
        out[name] = Tolerance(
            float(table.get("rtol", DEFAULT_RTOL)), float(table.get("atol", DEFAULT_ATOL))
        )
    return out


def deviations(
    expected: np.ndarray, actual: np.ndarray, tol: Tolerance
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per point: within ``tol`` (bool), ``|actual - expected|`` and that over ``|expected|``
    (0 where equal, the same infinity or both NaN; inf where only one is NaN)."""
    with np.errstate(invalid="ignore", divide="ignore"):
        diff = np.abs(actual - expected)
        same = (actual == expected) | (np.isnan(actual) & np.isnan(expected))  # incl. ±inf
        inside = same | (np.isfinite(diff) & (diff <= tol.atol + tol.rtol * np.abs(expected)))
        if math.isinf(tol.rtol) or math.isinf(tol.atol):
            inside[:] = True
        diff = np.where(same, 0.0, np.where(np.isnan(diff), np.inf, diff))
        rel = np.where(diff == 0, 0.0, diff / np.abs(expected))
    return inside, diff, rel
