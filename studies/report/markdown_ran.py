"""What actually ran where a scene may replace a requested level, for the report.

A response that records the value a parameter actually ran with (``used_for`` in its
attributes: the valve scene's ``integrator_used`` and ``angle_step_used``, where a tolerance
lets the engine pick the method and step per point) shows when a run's levels are a request
and not what computed its results. The report names the level and says what ran instead.
"""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np
import xarray as xr

from studies.analysis.taguchi import factor_names
from studies.common.text_safety import Markup, md_escape
from studies.report.markdown_format import levels_of, units_of, value_text
from studies.report.markdown_terms import at_run


def recorders(view: xr.Dataset) -> dict[str, str]:
    """Factor → the response recording the value it ran with (factors of the design, in
    their order)."""
    by_factor = {str(view[r].attrs.get("used_for", "")): str(r) for r in view.data_vars}
    return {f: by_factor[f] for f in factor_names(view) if f in by_factor}


def _used(view: xr.Dataset, response: str, run: int) -> object:
    """The recorded value of ``response`` at ``run`` (a code's meaning for a status code)."""
    y = view[response]
    value = at_run(view, response, run)
    if "flag_values" in y.attrs:
        meanings = str(y.attrs["flag_meanings"]).split()
        codes = [int(v) for v in np.atleast_1d(y.attrs["flag_values"])]
        return meanings[codes.index(int(value))] if int(value) in codes else None
    return float(value) if np.isfinite(value) else None


def _same(requested: object, used: object) -> bool:
    if isinstance(requested, str) or isinstance(used, str):
        return str(requested) == str(used)
    return bool(np.isclose(float(requested), float(used), rtol=1e-9, atol=0.0))  # type: ignore[arg-type]


def replaced(view: xr.Dataset, an: xr.Dataset, run: int) -> dict[str, Markup]:
    """Factor → what ran instead (as text with units), for each factor whose requested level
    at ``run`` is not what ran."""
    out = {}
    for f, response in recorders(view).items():
        used = _used(view, response, run)
        requested = levels_of(an, f)[int(at_run(view, f"{f}_level", run))]
        if used is not None and not _same(requested, used):
            units = units_of(view, response)
            out[f] = value_text(used, units if units != "1" else "")
    return out


def ran_text(view: xr.Dataset, an: xr.Dataset, run: int) -> Markup:
    """``; ran integrator = dopri, angle_step = 0.0625 degree`` (empty when all ran as asked)."""
    instead = replaced(view, an, run)
    if not instead:
        return Markup("")
    return Markup("; ran " + ", ".join(f"{md_escape(f)} = {shown}" for f, shown in instead.items()))


def ran_note(view: xr.Dataset, an: xr.Dataset, runs: Iterable[int]) -> list[str]:
    """A paragraph listing the runs of ``runs`` that did not run as requested (none: [])."""
    runs = [int(r) for r in runs if int(r) >= 0]
    listed = [(r, ran_text(view, an, r)) for r in runs]
    listed = [(r, text) for r, text in listed if text]
    if not listed:
        return []
    recorded = ", ".join(sorted(set(recorders(view).values())))
    parts = "; ".join(f"run {r + 1}{text[1:]}" for r, text in listed)
    return [
        (
            f"These levels are a request: in {len(listed)} of these {len(runs)} runs the "
            f"scene ran something else (recorded in {md_escape(recorded)}), and the values "
            f"above are what that computed: {parts}."
        ),
        "",
    ]
