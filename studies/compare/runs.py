"""What changed between recorded runs: definitions, code, versions, timings and responses.

Everything is read from the run folders (``study.toml``, ``run.json``, ``results.nc``) and the
registry, never from scene code, so runs of scenes that are no longer installed still compare.
Design points are matched by the values of the factors the runs share, in SI (so levels written
in mm and in m match): two different designs over the same factors compare on the points they
have in common. Under ``[noise]`` every (design point, noise case) value is compared, matched
on the factor values and the noise case, which is the same case in both runs only when their
``[noise]`` tables agree (else nothing is compared). A response "moved" when a common value
differs beyond its tolerance (:mod:`studies.compare.tolerances`; by default rtol 1e-7).
"""

from __future__ import annotations

import json
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import xarray as xr

from studies.common.errors import RunStateError, StudyError
from studies.common.units import UNITS, to_si
from studies.compare.differences import (
    MISSING,
    Difference,
    code_differences,
    definition_differences,
    flatten,
    short,
    version_differences,
)
from studies.compare.tolerances import DEFAULT, Tolerance, deviations
from studies.run.results import NOISE, is_scalar, is_status, open_results
from studies.tracking.store import RunStore


@dataclass
class RecordedRun:
    """A run as its folder recorded it."""

    run_id: str
    record: dict[str, Any]
    definition: dict[str, Any]
    results: xr.Dataset
    values: list[dict[str, Any]] = field(default_factory=list)  # the registry's, in SI

    @property
    def factors(self) -> list[str]:
        return list(json.loads(self.results.attrs.get("factors", "[]")))

    def responses(self) -> list[str]:
        """Numeric responses on ``run`` or ``run × noise`` (status codes and bit masks
        excluded)."""
        names = json.loads(self.results.attrs.get("responses", "[]"))
        return [
            n
            for n in names
            if n in self.results
            and is_scalar(self.results[n])
            and self.results[n].dtype.kind in "fiu"
            and not is_status(self.results[n])
        ]


@dataclass
class ResponseChange:
    """How one response moved from the reference run to another run on their common points."""

    response: str
    units: str
    run_id: str
    points: int
    max_abs: float
    max_rel: float
    beyond: int  # points outside the tolerance
    tolerance: Tolerance
    worst: tuple[str, float, float] | None  # (point, reference value, value) that moved most

    @property
    def changed(self) -> bool:
        return self.beyond > 0


@dataclass
class Comparison:
    runs: list[RecordedRun]
    definition: list[Difference]
    code: list[Difference]
    versions: list[Difference]
    matched_on: list[str]
    changes: list[ResponseChange]

    def label(self, index: int, most: int = 3) -> str:
        """What run ``index`` is, in the words of what differs (a legend entry); its id when
        nothing but the id differs."""
        differing = self.definition + self.code + self.versions
        if not differing:
            return self.runs[index].run_id
        words = "; ".join(d.label(index) for d in differing[:most])
        return words + (f"; +{len(differing) - most} more" if len(differing) > most else "")

    def moved(self) -> list[str]:
        """Responses that moved in any run (reference order)."""
        return list(dict.fromkeys(c.response for c in self.changes if c.changed))


def load_run(store: RunStore, ref: str) -> RecordedRun:
    """The run of ``store`` named by an id, a unique id prefix or a tag (RunNotFound if
    none)."""
    row = store.resolve_run(ref)
    folder = Path(row["folder"])
    results = folder / "results.nc"
    if not results.exists():
        msg = f"run {row['run_id']} has no results.nc (status {row['status']}): nothing to compare"
        raise RunStateError(msg)
    record = json.loads((folder / "run.json").read_text(encoding="utf-8"))
    definition = tomllib.loads((folder / "study.toml").read_text(encoding="utf-8"))
    values = store.run_values(row["run_id"])
    return RecordedRun(row["run_id"], record, definition, open_results(results).load(), values)


def load_results(store: RunStore, ref: str) -> tuple[str, xr.Dataset]:
    """A results Dataset named by a run reference (a run of ``store``) or by the path of a
    results ``.nc`` file (a reviewed baseline kept outside any registry): (what to call it,
    the Dataset)."""
    path = Path(ref)
    if path.suffix == ".nc" and path.is_file():
        return str(path), open_results(path).load()
    run = load_run(store, ref)
    return f"run {run.run_id}", run.results


def compare(
    runs: list[RecordedRun],
    default: Tolerance = DEFAULT,
    tolerances: dict[str, Tolerance] | None = None,
) -> Comparison:
    """Compare runs with the first (the reference); a response moved where a point differs
    beyond its tolerance (``tolerances`` per response, else ``default``)."""
    tolerances = tolerances or {}
    if len(runs) < 2:
        raise StudyError("name at least two runs to compare")
    shared = [r for r in runs[0].responses() if all(r in x.responses() for x in runs[1:])]
    if not shared:
        msg = "the runs share no response: " + "; ".join(
            f"{x.run_id}: {', '.join(x.responses()) or 'none'}" for x in runs
        )
        raise StudyError(msg)
    factors = shared_factors(runs)
    changes = []
    for other in runs[1:]:
        common = matched_points(runs[0].results, other.results, factors)
        changes += [
            _change(
                common,
                r,
                str(runs[0].results[r].attrs.get("units", "")),
                other.run_id,
                tolerances.get(r, default),
            )
            for r in shared
        ]
    records = [x.record for x in runs]
    return Comparison(
        runs,
        definition_differences([x.definition for x in runs], [x.values for x in runs]),
        code_differences(records),
        version_differences(records),
        factors,
        changes,
    )


def shared_factors(runs: list[RecordedRun]) -> list[str]:
    factors = [f for f in runs[0].factors if all(f in x.factors for x in runs[1:])]
    if not factors:
        msg = "the runs share no factor, so no design point of one can be matched to the other"
        raise StudyError(msg)
    return factors


def point_table(ds: xr.Dataset, factors: list[str], responses: list[str]) -> pd.DataFrame:
    """Responses indexed by the values of ``factors`` in SI, a row per design point; under
    ``[noise]`` a row per design point and noise case, indexed by the case too (ValueError if
    the factor values repeat)."""
    cases = ds.sizes.get(NOISE, 1)
    frame = pd.DataFrame({f: np.repeat(_si(ds[f]), cases) for f in factors})
    if NOISE in ds.dims:
        frame[NOISE] = np.tile(ds[NOISE].values, ds.sizes["run"])
    for r in responses:
        frame[r] = ds[r].values.astype(np.float64).ravel()  # run-major: as repeat and tile
    indexed = frame.set_index(factors + ([NOISE] if NOISE in ds.dims else []))
    if not indexed.index.is_unique:
        msg = (
            f"run {ds.attrs.get('run_id', '?')} has several design points with the same values "
            f"of {', '.join(factors)}: the points cannot be matched by the shared factors"
        )
        raise StudyError(msg)
    return indexed


def matched_points(reference: xr.Dataset, other: xr.Dataset, factors: list[str]) -> pd.DataFrame:
    """The design points both runs have, columns ``<response>`` (reference) and
    ``<response>_other``, indexed by the factor values (and the noise case: StudyError when
    the runs' noise cases differ)."""
    same_noise(reference, other)
    names = [n for n in reference.data_vars if n in other.data_vars]
    names = [n for n in names if is_scalar(reference[n]) and is_scalar(other[n])]
    a = point_table(reference, factors, [str(n) for n in names])
    b = point_table(other, factors, [str(n) for n in names])
    common = a.join(b.add_suffix("_other"), how="inner")
    if common.empty:
        msg = f"the runs have no design point in common over {', '.join(factors)}"
        raise StudyError(msg)
    return common


def noise_table(ds: xr.Dataset) -> dict[str, Any] | None:
    """The ``[noise]`` table of the study that made ``ds``, flattened (None without noise)."""
    if NOISE not in ds.dims:
        return None
    try:
        study = tomllib.loads(str(ds.attrs.get("study_toml", "")))
    except tomllib.TOMLDecodeError:
        study = {}
    return flatten(study.get("noise", {}))


def same_noise(reference: xr.Dataset, other: xr.Dataset) -> None:
    """StudyError unless noise case k is the same case in both runs: neither has ``[noise]``,
    or both have the same ``[noise]`` table."""
    a, b = noise_table(reference), noise_table(other)
    if a == b:
        return
    ids = [str(ds.attrs.get("run_id", "?")) for ds in (reference, other)]
    if a is None or b is None:
        what = [
            f"{ds.attrs.get('noise_design') or 'no [noise]'} in {i}"
            for ds, i in zip((reference, other), ids, strict=True)
        ]
    else:
        keys = [k for k in dict.fromkeys([*a, *b]) if a.get(k, MISSING) != b.get(k, MISSING)]
        what = [
            f"{k} = {short(a.get(k, MISSING))} in {ids[0]}, {short(b.get(k, MISSING))} in {ids[1]}"
            for k in keys
        ]
    msg = (
        f"the runs' [noise] tables differ ({'; '.join(what)}): their noise cases are not the "
        "same cases, so nothing is compared; compare runs whose [noise] tables agree"
    )
    raise StudyError(msg)


def _si(coordinate: xr.DataArray) -> np.ndarray:
    """A factor's values in SI when its units are known (else as stored)."""
    units = str(coordinate.attrs.get("units", ""))
    values = coordinate.values
    if units in UNITS and values.dtype.kind in "fiu":
        return np.asarray(to_si(values.astype(np.float64), units))
    return values


def point_label(common: pd.DataFrame, row: int) -> str:
    """Row ``row`` of a :func:`matched_points` table as ``factor=value`` pairs (values in SI,
    as matched; ``noise=k`` its noise case)."""
    index = common.index[row]
    values = index if isinstance(index, tuple) else (index,)
    names = [str(n) for n in common.index.names]
    return ", ".join(f"{n}={short(v)}" for n, v in zip(names, values, strict=True))


def _change(
    common: pd.DataFrame, response: str, units: str, run_id: str, tol: Tolerance
) -> ResponseChange:
    a = common[response].to_numpy()
    b = common[f"{response}_other"].to_numpy()
    inside, diff, rel = deviations(a, b, tol)
    beyond = np.where(inside, 0.0, diff)
    worst = None
    if not inside.all():
        i = int(np.argmax(beyond))
        worst = (point_label(common, i), float(a[i]), float(b[i]))
    return ResponseChange(
        response,
        units,
        run_id,
        len(common),
        float(diff.max(initial=0.0)),
        float(rel.max(initial=0.0)),
        int((~inside).sum()),
        tol,
        worst,
    )


def format_comparison(c: Comparison) -> str:
    """The comparison as text: differences, timings, then one line per moved response (its
    largest change and where), and the responses within tolerance."""
    ids = [x.run_id for x in c.runs]
    lines = [f"reference {ids[0]}; compared: {', '.join(ids[1:])}", ""]
    differing = c.definition + c.code + c.versions
    lines.append("what differs:" if differing else "definitions, code and versions: identical")
    width = max((len(f"{d.kind} {d.name}") for d in differing), default=0)
    lines += [f"  {f'{d.kind} {d.name}':<{width}}  {d.text()}" for d in differing]
    lines += ["", "timings:"]
    for x in c.runs:
        t = x.record.get("timings", {})
        lines.append(
            f"  {x.run_id:<30} compile {t.get('compile_s', float('nan')):.2f} s, "
            f"run {t.get('run_s', float('nan')):.3f} s, {x.results.sizes['run']} design points"
        )
    tolerances = sorted({(ch.tolerance.rtol, ch.tolerance.atol) for ch in c.changes})
    limits = "; ".join(f"rtol {r:g}, atol {a:g}" for r, a in tolerances)
    noise = " and the noise case" if NOISE in c.runs[0].results.dims else ""
    lines += [
        "",
        f"responses (matched on {', '.join(c.matched_on)} in SI{noise}; moved: beyond {limits}):",
    ]
    moved = [ch for ch in c.changes if ch.changed]
    if moved:
        lines.append(
            f"  {'response':<34} {'run':<30} {'moved':>9} {'max |Δ|':>11} {'max rel':>9}  most at"
        )
    for ch in moved:
        name = f"{ch.response} [{ch.units}]" if ch.units not in ("", "1") else ch.response
        where = f"{ch.worst[0]}: {ch.worst[1]:.6g} → {ch.worst[2]:.6g}" if ch.worst else ""
        lines.append(
            f"  {name:<34} {ch.run_id:<30} {f'{ch.beyond}/{ch.points}':>9} "
            f"{ch.max_abs:>11.4g} {ch.max_rel:>9.3g}  {where}"
        )
    names = c.moved()
    still = [r for r in dict.fromkeys(ch.response for ch in c.changes) if r not in names]
    lines += [
        "",
        f"moved: {', '.join(names) or 'none'}",
        f"within tolerance: {', '.join(still) or 'none'}",
    ]
    return "\n".join(lines)
