"""What the optimum sections say about terms and runs: each factor's role (control, operating
condition, model rung), the chosen levels, and what a run without a value of its own is."""

from __future__ import annotations

import json
import math

import numpy as np
import xarray as xr

from studies.analysis.optimum import COMPUTED
from studies.common.text_safety import Markup, md_escape


def computed(an: xr.Dataset) -> bool:
    return an.attrs.get("optimum_basis") == COMPUTED


def optimum_levels(an: xr.Dataset, name: str) -> dict[str, int]:
    """Control factor → its chosen level (0-based) for ``name``."""
    r = an.sel(response=name)
    return {
        str(t): int(level)
        for t, level, role in zip(
            an["term"].values, r.optimum_level.values, an["term_role"].values, strict=True
        )
        if role == "control" and level >= 0
    }


def control_terms(an: xr.Dataset) -> list[str]:
    return [str(t) for t, role in zip(an["term"].values, an["term_role"].values, strict=True)
            if role == "control"]  # fmt: skip


def operating_terms(an: xr.Dataset) -> list[str]:
    """The operating conditions, model rungs included (:func:`model_terms`)."""
    return list(json.loads(an.attrs.get("operating_factors", "[]")))


def model_terms(an: xr.Dataset) -> list[str]:
    """The factors that are model rungs (``role = "model"``)."""
    return list(json.loads(an.attrs.get("model_factors", "[]")))


def not_chosen(an: xr.Dataset) -> list[str]:
    """Sentences naming the operating conditions and model rungs, which are never chosen."""
    models = model_terms(an)
    operating = [f for f in operating_terms(an) if f not in models]
    lines = []
    if operating:
        lines.append(
            f"Operating conditions, not chosen: {md_escape(', '.join(operating))} (every level "
            "is a case the design must meet)."
        )
    if models:
        lines.append(
            f"Model rungs, not chosen: {md_escape(', '.join(models))} (each level computes the "
            "same design with another model; values are given per model below)."
        )
    return lines


def units_suffix(r: xr.Dataset) -> Markup:
    """`` <units>`` (Markdown, escaped); nothing for a dimensionless "1"."""
    units = str(r.units.values)
    return Markup(f" {md_escape(units)}" if units and units != "1" else "")


def run_text(index: int) -> str:
    return f"run {index + 1}"


def at_run(view: xr.Dataset, name: str, run: int) -> np.ndarray:
    """The value of ``name`` at ``run``, read alone: results are opened without a cache
    (:func:`studies.run.results.open_results`), so ``.values`` would read the whole variable
    for one value (O(N) per table cell)."""
    return view[name].isel(run=int(run)).values


def bound_mark(view: xr.Dataset, name: str, run: int) -> str:
    """``: no value, counted at the bound`` when ``run`` has no value of ``name`` of its own
    (its response's ``none_means`` counted it at the best or worst value seen)."""
    own = float(at_run(view, name, run)) if name in view else math.nan
    return "" if np.isfinite(own) else ": no value, counted at the bound"


def none_text(view: xr.Dataset, name: str) -> str:
    """What a run without a value of ``name`` is, in words (its ``none_label``, else
    "no value")."""
    return str(view[name].attrs.get("none_label", "")) or "no value"
