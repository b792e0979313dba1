"""Smallest radius of curvature of many cam laws at once: the convexity checks of the ``cam``,
``rocker`` and ``valve`` scenes [C1].

ρ = r0 + h + h'' on a cam-angle grid. A rise-return law's lift is its rise H times a shape
that depends only on the law, its rise angle β and (polydyne) coefficients: h = H·f(θ; β),
h'' = H·f''(θ; β). So for H > 0 the smallest radius is r0 + H·min(f + f''), and one kernel row
per distinct (law, β, coefficients) serves every base radius and lift: a check over lift and
base radius costs as many kernel rows as there are rise angles. The other laws (six-segment,
invalid input) are evaluated row by row, on a grid coarsened so that no more than
:data:`SCAN_BUDGET` angles are evaluated (never coarser than :data:`COARSEST_SCAN_DEG`).
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from engine_kernels._jit import call_small, claim
from engine_kernels.cam import kinematics as cb
from engine_kernels.cam.lift_laws import LAW_POLYDYNE, LAW_SIX_SEGMENT, N_RISE_LAWS
from studies.scenes.checks import distinct, take

HALF_TURN_DEG = 180.0
SCAN_BUDGET = 4_000_000
"""Cam angles × laws scanned row by row before the grid coarsens (``check`` stays fast; a run
computes every point on the study's own grid whatever the check saw)."""
COARSEST_SCAN_DEG = 2.0


def turn_deg(step_deg: float) -> np.ndarray:
    """Cam angles −180 … 180 deg every ``step_deg`` (180 a multiple of it) [deg]: the cam
    scene's curve axis and the grid its convexity is scanned on."""
    count = round(HALF_TURN_DEG / step_deg)
    return np.linspace(-HALF_TURN_DEG, HALF_TURN_DEG, 2 * count + 1)


def angle_grid(step_deg: float) -> np.ndarray:
    """:func:`turn_deg` in radians [rad]."""
    return np.radians(turn_deg(step_deg))


def scan_step_deg(laws: int, step_deg: float) -> float:
    """The grid step [deg] to scan ``laws`` laws row by row: ``step_deg`` unless that exceeds
    :data:`SCAN_BUDGET` angle evaluations, then coarser, up to :data:`COARSEST_SCAN_DEG`. A
    coarser grid can only miss a marginally concave cam, never call a convex one concave."""
    wanted = 2.0 * HALF_TURN_DEG * laws / SCAN_BUDGET
    if wanted <= step_deg:
        return step_deg
    return HALF_TURN_DEG / math.floor(HALF_TURN_DEG / min(wanted, COARSEST_SCAN_DEG))


KernelRows = Callable[[np.ndarray], tuple[np.ndarray, np.ndarray, np.ndarray]]
"""``rows(idx)``: the ``cam_kinematics_batch`` inputs (params, shapes, coefficients) of cams
``idx``."""


def min_radii(
    law: np.ndarray,
    lift: np.ndarray,
    beta: np.ndarray,
    base: np.ndarray,
    coefficients: np.ndarray,
    rows: KernelRows,
    step_deg: float,
) -> tuple[np.ndarray, str]:
    """min ρ = r0 + h + h'' [m] of n cams on the grid of ``step_deg`` [deg]: their law codes,
    lifts H [m], rise angles β [rad], base radii r0 [m] and polydyne coefficients (n, k),
    and ``rows`` for the kernel inputs of those that are evaluated as they are (NaN where the
    input is invalid). Also what to say when those were too many for the grid and were
    scanned on a coarser one (:func:`scan_step_deg`), else ""."""
    scaled = (
        (law >= 0)
        & (law < N_RISE_LAWS)
        & (law != LAW_SIX_SEGMENT)
        & (beta > 0.0)
        & (lift > 0.0)
        & np.isfinite(lift)
        & np.isfinite(base)
    )
    out = np.empty(law.size)
    some = np.flatnonzero(scaled)
    if some.size:
        polydyne = law[some] == LAW_POLYDYNE
        shaping = (
            [np.where(polydyne[:, None], take(coefficients, some), 0.0)] if polydyne.any() else []
        )
        first, group = distinct([law[some], beta[some], *shaping])
        params, shapes, coeffs = rows(some[first])
        params[:, cb.P_LIFT], params[:, cb.P_BASE_RADIUS] = 1.0, 0.0
        shape = np.empty(first.size)
        grid = angle_grid(step_deg)
        call_small(
            cb.min_radius_of_curvature_batch,
            first.size * grid.size,
            params,
            shapes,
            coeffs,
            grid,
            shape,
        )
        out[some] = base[some] + lift[some] * shape[group]
    rest = np.flatnonzero(~scaled)
    step = scan_step_deg(rest.size, step_deg)
    claim(rest.size * angle_grid(step).size)
    if rest.size:
        radius = np.empty(rest.size)
        grid = angle_grid(step)
        call_small(
            cb.min_radius_of_curvature_batch, rest.size * grid.size, *rows(rest), grid, radius
        )
        out[rest] = radius
    if step == step_deg:
        return out, ""
    return out, f" ({rest.size} cams of other laws scanned every {step:.2g} degree)"
