"""What every figure shares: units as a person reads them, cell text that stays readable on
its colour, and the colour scale a map's values call for."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from matplotlib.colors import LogNorm, Normalize, TwoSlopeNorm

LOG_DECADES = 100.0  # values spanning more than this ratio get a log scale
_SUPERSCRIPTS = str.maketrans("0123456789-", "⁰¹²³⁴⁵⁶⁷⁸⁹⁻")


def pretty_units(units: str) -> str:
    """UDUNITS text as printed: ``mm/rad^2`` → ``mm/rad²``, ``N*m`` → ``N·m``."""
    out, rest = [], units.replace("*", "·")
    while "^" in rest:
        head, rest = rest.split("^", 1)
        exponent = ""
        while rest and (rest[0].isdigit() or (rest[0] == "-" and not exponent)):
            exponent, rest = exponent + rest[0], rest[1:]
        out.append(head + exponent.translate(_SUPERSCRIPTS))
    return "".join(out) + rest


def axis_label(name: str, units: str) -> str:
    """``name [units]``, without brackets for dimensionless quantities."""
    return f"{name} [{pretty_units(units)}]" if units not in ("", "1") else name


def text_colour(rgba: Sequence[float] | np.ndarray) -> str:
    """Black on light cells, white on dark ones (relative luminance, ITU-R BT.601)."""
    r, g, b = (float(c) for c in rgba[:3])
    return "black" if 0.299 * r + 0.587 * g + 0.114 * b > 0.5 else "white"


def map_scale(values: np.ndarray, share: bool = False) -> tuple[Normalize, str]:
    """Norm and colour map for a map of ``values``: 0…1 for a share of passing checks, a
    diverging map centred on 0 for values of both signs (margins), log for positive values
    over more than two decades, else linear."""
    finite = values[np.isfinite(values)]
    if share:
        return Normalize(0.0, 1.0), "RdYlGn"
    if not finite.size:
        return Normalize(), "viridis"
    low, high = float(finite.min()), float(finite.max())
    if low < 0.0 < high:
        return TwoSlopeNorm(0.0, low, high), "RdBu_r"
    if low > 0.0 and high > LOG_DECADES * low:
        return LogNorm(low, high), "viridis"
    return Normalize(low, high), "viridis"
