"""The two random samples of valve design points the error bars are checked on, and their
scipy reference (tests/studies/test_valve_error_bar.py, tests/studies/refresh_error_bar_reference.py).

Sample ``A`` (issue #15, seed 15): the valve scene's defaults (six-segment cam, 0.05 mm lash)
with camshaft 500…8000 rpm, seat stiffness 1e4…1e7 N/mm (log-uniform), spring preload and drive
stiffness ±30 % around the thesis values.

Sample ``B`` (issue #26, seed 26): every lift law of the valve scene, each at a rise angle
2…40° (at most 140°) above the angle from which its cam is convex at 8 mm of valve lift
(``CONVEX_FROM_DEG``, found by bisection with the scene's own convexity check), valve lift 5…8 mm, lash 0.01…0.25 mm, camshaft
500…9000 rpm, seat 9.2e3…1.45e7 N/mm (log-uniform), preload 150…300 N, drive stiffness
8e3…1.5e4 N/mm, equivalent mass 30…60 g, spring rate 20…40 N/mm, damping on the drive
20…300, on the seat 20…2000 (log-uniform) and external 0…50 N·s/m.

Reference: scipy's event-restarted DOP853 at rtol 1e-10
(:mod:`studies.scenes.valve.reference.valve_ivp`, every solver step scanned for a switch it
stepped over) on the chain's lift tabulated every ``acc.REFERENCE_TABLE_DEG`` (1/512°) and
clipped at the lash as the kernels clip it; its outputs located on its dense output
(:mod:`studies.scenes.valve.reference.valve_outputs`).
"""

from __future__ import annotations

import hashlib
import math
from pathlib import Path
from typing import Any

import numpy as np

from engine_kernels.valvetrain.valve.observations import nose_position
from studies.define.plan import plan_text
from studies.scenes.valve.reference import accuracy as acc
from studies.scenes.valve.reference.valve_ivp import table_excitation, valve_reference
from studies.scenes.valve.reference.valve_outputs import reference_outputs
from studies.scenes.valve.scene import valve_rows
from study_text import scene_study

REFERENCE_FILE = Path(__file__).parent / "studies" / "data" / "valve_error_bar_reference.nc"
"""The stored reference of both samples (made by tests/studies/refresh_error_bar_reference.py)."""
SIZE = 200
SEEDS = {"A": 15, "B": 26}
RPM = math.pi / 30.0
CONVEX_FROM_DEG = {
    "cycloidal": 85.13,
    "harmonic": 74.21,
    "modified_sine": 78.84,
    "modified_trapezoid": 77.5,
    "poly345": 81.25,
    "poly4567": 93.2,
    "polydyne": 72.66,
}
"""Rise angle [deg] from which each standard law is convex at 8 mm of valve lift (the
six-segment profile keeps its 70° half event)."""
OUTPUTS = ("max_lift", "jump_start", "seating_velocity", "bounce_height")
REFERENCE_RTOL = 1e-10


def sample_plan(responses: list[str], integrator: str, tolerance: float) -> Any:
    """A valve study with the given responses and accuracy settings (its points are replaced
    by a sample's)."""
    text = scene_study(
        "valve",
        responses=str(responses).replace("'", '"'),
        curves='["actual_lift"]',
        settings=f'integrator = "{integrator}"\ntolerance = {tolerance}',
        factors="[factors.cam_speed]\nlevels = [3000.0, 3500.0]",
    )
    return plan_text(text)


def exp10(x: np.ndarray) -> np.ndarray:
    """10**x by the C library's pow, value by value: NumPy's vectorised power gives other last
    bits on AVX-512 machines than on AVX2 ones, and a sample must be the same on every CPU."""
    return np.array([10.0**v for v in x.tolist()])


def sample_points(plan: Any, name: str) -> dict[str, np.ndarray]:
    """The ``SIZE`` design points of sample ``name`` (SI units, as the plan holds them)."""
    rng = np.random.default_rng(SEEDS[name])
    n = SIZE
    points = {k: np.repeat(v[:1], n, axis=0) for k, v in plan.points.items()}
    if name == "A":
        points["cam_speed"] = rng.uniform(500.0, 8000.0, n) * RPM
        points["seat_stiffness"] = exp10(rng.uniform(4.0, 7.0, n)) * 1e3
        points["spring_preload"] = points["spring_preload"] * rng.uniform(0.7, 1.3, n)
        points["drive_stiffness"] = points["drive_stiffness"] * rng.uniform(0.7, 1.3, n)
        return points
    laws = np.array(["six_segment", *CONVEX_FROM_DEG], dtype=object)
    law = laws[rng.integers(0, laws.size, n)]
    points["law"] = law.astype(points["law"].dtype)
    points["valve_lift"] = rng.uniform(5.0, 8.0, n) * 1e-3
    rise = [
        70.0
        if k == "six_segment"
        else rng.uniform(CONVEX_FROM_DEG[k] + 2.0, min(CONVEX_FROM_DEG[k] + 40.0, 140.0))
        for k in law
    ]
    points["rise_angle"] = np.radians(rise)
    points["lash"] = rng.uniform(0.01, 0.25, n) * 1e-3
    points["cam_speed"] = rng.uniform(500.0, 9000.0, n) * RPM
    points["seat_stiffness"] = exp10(rng.uniform(math.log10(9.2e3), math.log10(1.45e7), n)) * 1e3
    points["spring_preload"] = rng.uniform(150.0, 300.0, n)
    points["drive_stiffness"] = rng.uniform(8e3, 1.5e4, n) * 1e3
    points["equivalent_mass"] = rng.uniform(0.03, 0.06, n)
    points["drive_damping"] = rng.uniform(20.0, 300.0, n)
    points["seat_damping"] = exp10(rng.uniform(math.log10(20.0), math.log10(2000.0), n))
    points["external_damping"] = rng.uniform(0.0, 50.0, n)
    points["spring_rate"] = rng.uniform(20.0, 40.0, n) * 1e3
    return points


def reference_of(
    plan: Any, points: dict[str, np.ndarray], which: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """The reference of the points ``which``: lift [m] on the plan's curve axis (NaN outside
    each point's integration window) and (max lift [m], jump start [rad], seating velocity
    [m/s], bounce height [m]) per point (``OUTPUTS``)."""
    scene = plan.scene
    subset = {k: v[which] for k, v in points.items()}
    state = scene.start(subset, plan.settings, [], [])
    axis = scene.curve_coordinate(plan.settings)
    lift = np.full((which.size, axis.size), np.nan)
    outputs = np.full((which.size, len(OUTPUTS)), np.nan)
    for key, idx in state.groups.items():
        if not scene.linkage_valid(state, key):
            continue
        table, step, start = scene.excitation(
            state, key, 2.0 * acc.REFERENCE_TABLE_DEG, unclipped=True
        )
        nose = start + nose_position(table) * step
        first, last = scene.window(state, key)
        inside = (axis >= first) & (axis <= last)
        excitation = table_excitation(table, step, start)
        for i, row in zip(idx, valve_rows(subset, idx), strict=True):
            solution = valve_reference(
                excitation, row, np.radians(axis[inside]), rtol=REFERENCE_RTOL
            )
            lift[i, inside] = solution.lift
            found = reference_outputs(solution, row, nose)
            outputs[i] = [getattr(found, name) for name in OUTPUTS]
    return lift, outputs


def points_digest(points: dict[str, np.ndarray]) -> str:
    """SHA-256 of a sample's parameter rows, cam laws and cam shapes: ties a stored reference
    to the points it was solved for."""
    rows = valve_rows(points, slice(None))
    shapes = np.stack(
        [np.asarray(points[k], dtype=float) for k in ("valve_lift", "rise_angle", "lash")]
    )
    digest = hashlib.sha256(np.ascontiguousarray(rows).tobytes())
    digest.update(np.ascontiguousarray(shapes).tobytes())
    digest.update(",".join(map(str, points["law"])).encode())
    return digest.hexdigest()
