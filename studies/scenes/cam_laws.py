"""The cam lift laws every cam-driven scene shares (``cam``, ``rocker``, ``valve``): the law and
segment-shape names and their kernel codes, the six-segment profile's parameters (12V150
initial design, physics §9), and the conditions a polydyne polynomial must meet."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from engine_kernels._jit import call_small, claim
from engine_kernels.cam import kinematics as cb
from engine_kernels.cam import lift_laws, multi_segment
from studies.scenes.base import Parameter

LAWS = (
    "six_segment",
    "cycloidal",
    "harmonic",
    "modified_sine",
    "modified_trapezoid",
    "poly345",
    "poly4567",
    "polydyne",
    "table",
)
SHAPES = ("lin", "sin_full", "sin_left", "fillet")
MIN_RISE_ANGLE_DEG = 1.0
"""Smallest rise angle a study may give: below it a law is no cam, and h″ = H f″/β² overflows."""
SRC = "12V150 source"

_SEG_WIDTHS = (4.5, 11.0, 4.5, 5.0, 22.0, 23.0)
_SEG_SHAPES = ("lin", "sin_full", "lin", "sin_left", "fillet", "sin_left")
_SEG_ACCELS = (55.0, 55.0, 0.0, -12.5, -22.5, -24.5)
_SEG_AMPS = (0.0, 12.5, 0.0, 7.5, 0.0, 5.5)


def rise_angle_parameter(maximum: float, source: str) -> Parameter:
    """The rise angle β of a standard law (working half-event of the six-segment profile)."""
    return Parameter(
        "rise_angle",
        "degree",
        70.0,
        "rise duration β of a standard law; working half-event of the six-segment profile "
        "(from 1°: shorter rises are not cams, and their h″ ∝ 1/β² overflows)",
        MIN_RISE_ANGLE_DEG,
        maximum,
        source=source,
    )


def ramp_parameters(
    height: float, width: float, velocity: float, source: str
) -> tuple[Parameter, ...]:
    """The six-segment profile's lash take-up ramp: height [mm], width [degree] and end
    velocity [mm/rad] (defaults per scene; 0 height = no ramp)."""
    return (
        Parameter(
            "ramp_height",
            "mm",
            height,
            "lash take-up ramp height (0 = no ramp: ramp_width and ramp_velocity unused)",
            0.0,
            5.0,
            source=source,
        ),
        Parameter(
            "ramp_width",
            "degree",
            width,
            "ramp width (constant acceleration, then velocity)",
            0.0,
            90.0,
            source=source,
        ),
        Parameter(
            "ramp_velocity", "mm/rad", velocity, "ramp end velocity", 0.0, 100.0, source=source
        ),
    )


def drop_empty_ramps(params: np.ndarray) -> None:
    """No ramp where ``ramp_height`` is 0, as the parameter says: the rows' ramp width and end
    velocity (``cam_kinematics_batch`` parameters, SI) are set to 0. The kernel would otherwise
    build the nearest feasible ramp of that width and velocity, v·W/2 high (0.17 mm for 50°
    at 0.4 mm/rad), and lift the whole profile by it."""
    empty = params[:, cb.P_RAMP_HEIGHT] == 0.0
    params[empty, cb.P_RAMP_WIDTH] = 0.0
    params[empty, cb.P_RAMP_VELOCITY] = 0.0


def first_convex_mark(low: np.ndarray, convex: Callable[[np.ndarray], np.ndarray]) -> np.ndarray:
    """The smallest rise angle on a 0.1° mark [deg] at which each law is convex, from a
    bisection that left it concave at ``low`` [deg] and convex at most 0.1° above: the mark at
    or above ``low`` if ``convex`` (rise angles [deg] → convex or not) says so, else the next
    one. Rounding the convex end up instead could name a mark 0.1° late, one that is not the
    first convex one (an audit: 73.8° where 73.7° is convex)."""
    mark = np.ceil(np.round(low * 10.0, 9)) / 10.0
    return np.where(convex(mark), mark, mark + 0.1)


def segment_parameters() -> tuple[Parameter, ...]:
    out: list[Parameter] = []
    for k in range(6):
        n = k + 1
        out += [
            Parameter(
                f"seg{n}_width",
                "degree",
                _SEG_WIDTHS[k],
                f"width of acceleration segment {n}",
                0.0,
                90.0,
                True,
                source=SRC,
            ),
            Parameter(
                f"seg{n}_shape",
                "1",
                _SEG_SHAPES[k],
                f"shape of segment {n}",
                choices=SHAPES,
                source=SRC,
            ),
            Parameter(
                f"seg{n}_accel",
                "mm/rad^2",
                _SEG_ACCELS[k],
                f"end acceleration of segment {n} (before closure scaling)",
                -1000.0,
                1000.0,
                source=SRC,
            ),
            Parameter(
                f"seg{n}_amplitude",
                "mm/rad^2",
                _SEG_AMPS[k],
                f"bulge amplitude of segment {n} (magnitude; sign set by the segment)",
                0.0,
                1000.0,
                source=SRC,
            ),
        ]
    return tuple(out)


LAW_CODES = {
    "cycloidal": lift_laws.LAW_CYCLOIDAL,
    "harmonic": lift_laws.LAW_HARMONIC,
    "modified_sine": lift_laws.LAW_MODIFIED_SINE,
    "modified_trapezoid": lift_laws.LAW_MODIFIED_TRAPEZOID,
    "poly345": lift_laws.LAW_POLY345,
    "poly4567": lift_laws.LAW_POLY4567,
    "polydyne": lift_laws.LAW_POLYDYNE,
    "six_segment": lift_laws.LAW_SIX_SEGMENT,
    "table": -1,  # curves come from the spline of the table, not from a kernel law
}
SHAPE_CODES = {name: code for code, name in enumerate(SHAPES)}
POLYDYNE_TOLERANCE = 1e-9


def codes(values: np.ndarray, table: dict[str, int]) -> np.ndarray:
    """The kernel codes of the names ``values`` (each distinct name looked up once; a column
    of one name costs one comparison per value)."""
    values = np.asarray(values)
    if values.size and (values.strides[0] == 0 or (values == values.flat[0]).all()):
        return np.full(values.size, table[str(values.flat[0])], dtype=np.int64)
    distinct, inverse = np.unique(values.astype(str), return_inverse=True)
    return np.array([table[name] for name in distinct.tolist()], dtype=np.int64)[inverse.ravel()]


def polydyne_problems(c: np.ndarray) -> list[str]:
    """Why polydyne coefficients c_k of f(x) = Σ c_k x^k are not a rise law (empty if they are)."""
    if c.size > lift_laws.NCOEF:
        return [f"polydyne_coefficients has {c.size} terms; at most {lift_laws.NCOEF} allowed"]
    k = np.arange(c.size)
    conditions = {
        "f(0) = 0": c[0],
        "f(1) = 1": c.sum() - 1.0,
        "f'(0) = 0": c[1] if c.size > 1 else 0.0,
        "f'(1) = 0": (k * c).sum(),
    }
    bad = [name for name, residual in conditions.items() if abs(residual) > POLYDYNE_TOLERANCE]
    if bad:
        return [
            (
                f"polydyne_coefficients {c.tolist()} violate {', '.join(bad)} "
                "(f(x) = Σ c_k x^k must rise from 0 to 1 with zero end velocity)"
            )
        ]
    return []


def fitted_widths(
    p: dict[str, np.ndarray], six: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Nominal and fitted segment widths [rad] of the points (n, 6) and whether they fit their
    half-event (physics §2), the points ``six`` (indices) being six-segment cams: one kernel
    call over those (as plain Python for a few, :func:`engine_kernels._jit.call_small`)."""
    n = len(p["law"])
    widths, adjusted, fits = np.zeros((n, 6)), np.zeros((n, 6)), np.ones(n, dtype=bool)
    if six.size:
        claim(six.size)
        widths = np.stack([p[f"seg{k}_width"] for k in range(1, 7)], axis=1).astype(float)
        shapes = np.stack([codes(p[f"seg{k}_shape"][six], SHAPE_CODES) for k in range(1, 7)], 1)
        half = np.ascontiguousarray(p["rise_angle"][six], dtype=float)
        out, ok = np.empty((six.size, 6)), np.empty(six.size, dtype=bool)
        fit = multi_segment.segment_widths_batch
        call_small(fit, six.size, np.ascontiguousarray(widths[six]), shapes, half, out, ok)
        adjusted[six], fits[six] = out, ok
    return widths, adjusted, fits
