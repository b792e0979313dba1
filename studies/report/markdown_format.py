"""Markdown formatting shared by the report's sections: numbers, tables, labels, level
values from the analysis Dataset, figure links."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from studies.common.text_safety import Markup, figure_target, md_escape


def pct(value: float) -> str:
    return f"{value:.1f}" if np.isfinite(value) else "—"


def num(value: Any, digits: int = 4) -> str:
    """``digits`` significant figures; ``inf``/``-inf`` as such, NaN (no value) as —."""
    if isinstance(value, str):
        return value
    if value is None or np.isnan(value):
        return "—"
    if not np.isfinite(value):
        return "inf" if value > 0 else "-inf"
    if value == 0:  # also -0.0, which would print as "-0"
        return "0"
    return f"{value:.{digits}g}"


def cell(value: Any) -> str:
    """A table cell: a number formatted, report markup (:class:`Markup`) as it is, any other
    text escaped (it may come from the user or a results file)."""
    if isinstance(value, Markup):
        return value
    text = num(value) if isinstance(value, float | np.floating) else str(value)
    return md_escape(text)


def table(header: Sequence[str], rows: Sequence[Sequence[Any]]) -> str:
    lines = ["| " + " | ".join(cell(h) for h in header) + " |"]
    lines.append("|" + "|".join("---" for _ in header) + "|")
    lines += ["| " + " | ".join(cell(v) for v in row) + " |" for row in rows]
    return "\n".join(lines)


def aligned(header: Sequence[str], rows: Sequence[Sequence[str]]) -> list[str]:
    """A plain-text table (``analysis.txt``): the header and each row, columns right-aligned
    to their widest cell, two spaces apart."""
    widths = [max([len(h), *(len(r[j]) for r in rows)]) for j, h in enumerate(header)]
    return ["  ".join(c.rjust(w) for c, w in zip(r, widths, strict=True)) for r in [header, *rows]]


def label(name: str, units: str) -> Markup:
    """``name [units]``; dimensionless ("1") and unknown units are left out (Markdown: both
    escaped, the brackets not)."""
    shown = md_escape(name)
    return Markup(f"{shown} [{md_escape(units)}]") if units and units != "1" else shown


def units_of(ds: xr.Dataset, name: str) -> str:
    return str(ds[name].attrs.get("units", "")) if name in ds.variables else ""


def value_text(value: Any, units: str) -> Markup:
    """A value and its units, none for a dimensionless "1" (Markdown, escaped)."""
    shown = num(value) if isinstance(value, int | float | np.number) else str(value)
    return md_escape(f"{shown} {units if units != '1' else ''}".rstrip())


def levels_of(an: xr.Dataset, term: str) -> dict[int, Any]:
    """Level index → the term's value (a number, else its label), for the levels it has."""
    values = an["level_value"].sel(term=term).values
    labels = an["level_label"].sel(term=term).values
    return {
        i: float(v) if np.isfinite(v) else str(label)
        for i, (v, label) in enumerate(zip(values, labels, strict=True))
        if label != ""
    }


def level_text(an: xr.Dataset, factor: str, level: int) -> Markup:
    """1-based level number and the factor's value: ``2 (9 deg)`` (Markdown, escaped)."""
    units = str(an["term_units"].sel(term=factor).values)
    shown = value_text(levels_of(an, factor)[level], units if units != "1" else "")
    return Markup(f"{level + 1} ({shown})")


def figure(name: str, caption: str, figures: set[str]) -> list[str]:
    """An image link to one of the run's figures (caption escaped, file name encoded)."""
    return [f"![{md_escape(caption)}]({figure_target(name)})", ""] if name in figures else []


def other_figures(lines: list[str], figures: set[str]) -> list[str]:
    """Links to the figures no section has shown (e.g. the scene's own figures)."""
    text = "\n".join(lines)
    rest = sorted(f for f in figures if f"]({figure_target(f)})" not in text)
    if not rest:
        return []
    out = ["## Other figures", ""]
    for f in rest:
        out += figure(f, Path(f).stem.replace("_", " "), figures)
    return out
