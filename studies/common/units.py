"""Engineering units accepted in study files, and their conversion to SI.

Kernels work in SI; studies are written in the units engineers use (mm, deg, rpm, MPa, N/mm).
Each unit maps to a physical dimension and the factor that converts it to the SI unit of that
dimension. Conversion happens once, at the boundary between a study and the kernels.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, NamedTuple, TypeVar

from studies.common.errors import StudyError

if TYPE_CHECKING:
    import numpy as np


class Unit(NamedTuple):
    dimension: str
    to_si: float


CANONICAL: dict[str, Unit] = {
    "1": Unit("dimensionless", 1.0),
    "m": Unit("length", 1.0),
    "mm": Unit("length", 1e-3),
    "um": Unit("length", 1e-6),
    "rad": Unit("angle", 1.0),
    "degree": Unit("angle", math.pi / 180.0),
    "rad/s": Unit("angular speed", 1.0),
    "rpm": Unit("angular speed", 2.0 * math.pi / 60.0),
    "rad/s^2": Unit("angular acceleration", 1.0),
    "m/s": Unit("speed", 1.0),
    "m/s^2": Unit("acceleration", 1.0),
    "s": Unit("time", 1.0),
    "ms": Unit("time", 1e-3),
    "h": Unit("time", 3600.0),
    "Hz": Unit("frequency", 1.0),
    "N": Unit("force", 1.0),
    "kN": Unit("force", 1e3),
    "N/m": Unit("stiffness", 1.0),
    "N/mm": Unit("stiffness", 1e3),
    "N*s/m": Unit("damping", 1.0),
    "Pa": Unit("pressure", 1.0),
    "kPa": Unit("pressure", 1e3),
    "bar": Unit("pressure", 1e5),
    "MPa": Unit("pressure", 1e6),
    "GPa": Unit("pressure", 1e9),
    "1/Pa": Unit("compliance", 1.0),
    "1/GPa": Unit("compliance", 1e-9),
    "Pa*s": Unit("viscosity", 1.0),
    "mPa*s": Unit("viscosity", 1e-3),
    "kg": Unit("mass", 1.0),
    "g": Unit("mass", 1e-3),
    "kg*m^2": Unit("moment of inertia", 1.0),
    "kg/m^3": Unit("density", 1.0),
    "W": Unit("power", 1.0),
    "kW": Unit("power", 1e3),
    "N*m": Unit("torque", 1.0),
    "J": Unit("energy", 1.0),
    "kJ": Unit("energy", 1e3),
    "m^4": Unit("second moment of area", 1.0),
    "mm^4": Unit("second moment of area", 1e-12),
    "m/rad": Unit("length per angle", 1.0),
    "mm/rad": Unit("length per angle", 1e-3),
    "m/rad^2": Unit("length per angle^2", 1.0),
    "mm/rad^2": Unit("length per angle^2", 1e-3),
    "m/rad^3": Unit("length per angle^3", 1.0),
    "mm/rad^3": Unit("length per angle^3", 1e-3),
}
# Short forms engineers write, accepted in study files and stored under their UDUNITS names.
ALIASES: dict[str, str] = {"deg": "degree", "-": "1"}
UNITS: dict[str, Unit] = CANONICAL | {a: CANONICAL[c] for a, c in ALIASES.items()}


def canonical(unit: str) -> str:
    """The UDUNITS name of an accepted unit (``deg`` → ``degree``, ``-`` → ``1``)."""
    return ALIASES.get(unit, unit)


def compatible_units(unit: str) -> list[str]:
    """Every accepted unit with the same dimension as ``unit``."""
    dim = UNITS[unit].dimension
    return [name for name, u in CANONICAL.items() if u.dimension == dim]


Number = TypeVar("Number", float, "np.ndarray")


def to_si(value: Number, unit: str) -> Number:
    """``value`` (a number or an array) in ``unit`` converted to SI. A decimal submultiple (mm,
    g, ms, 1/GPa …) divides by its whole-number inverse instead of multiplying by an inexact
    1e-3: the quotient is correctly rounded, so ``86 mm`` and ``0.086 m`` give the same double,
    bit for bit."""
    inverse = _inverse(unit)
    return value / inverse if inverse else value * UNITS[unit].to_si


def from_si(value: Number, unit: str) -> Number:
    """An SI value (a number or an array) expressed in ``unit``: the inverse of :func:`to_si`."""
    inverse = _inverse(unit)
    return value * inverse if inverse else value / UNITS[unit].to_si


def _inverse(unit: str) -> int:
    """1/factor of a unit whose factor to SI is the reciprocal of a whole number, else 0."""
    factor = UNITS[unit].to_si
    inverse = round(1.0 / factor) if factor < 1.0 else 0
    return inverse if inverse > 1 and inverse * factor == 1.0 else 0


def si_unit(unit: str) -> str:
    """The SI unit of the dimension ``unit`` measures (``mm`` → ``m``, ``rpm`` → ``rad/s``)."""
    dimension = UNITS[unit].dimension
    return next(n for n, u in CANONICAL.items() if u.dimension == dimension and u.to_si == 1.0)


def conversion_factor(from_unit: str, to_unit: str) -> float:
    """Factor f such that value_in_to_unit = f * value_in_from_unit (same dimension)."""
    a, b = UNITS[from_unit], UNITS[to_unit]
    if a.dimension != b.dimension:
        msg = f"cannot convert {from_unit!r} ({a.dimension}) to {to_unit!r} ({b.dimension})"
        raise StudyError(msg)
    return a.to_si / b.to_si
