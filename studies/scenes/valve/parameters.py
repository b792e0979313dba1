"""Declarations of the ``valve`` scene: the rocker scene's plus dynamics, settings, responses.

Dynamics defaults are the physics §4 thesis values (drive stiffness 1.17e4 N/mm, preload 205.8 N,
camshaft 3500 rpm = 7000 rpm engine) plus values the source does not give, chosen as in the
kernel tests and marked ``assumption``: equivalent mass [V1] 0.033 kg valve group + 15 g
spring / 3 + 5e-6 kg m² rocker inertia / lb² = 0.04252 kg, drive damping 150 N s/m, spring
rate 30 N/mm, seat stiffness 5e4 N/mm with 900 N s/m of seat damping, no external damping.

**Integrator settings** (``[settings]``):

* ``integrator`` — ``lanes`` (plain fixed-step RK4, 32 cases per SIMD block, double
  precision), ``lanes_f32`` (the same in single precision, twice the lanes per vector: the
  fastest; curves, when stored, come from the double-precision one-case kernel, the outputs
  beside them still from the lanes),
  ``rk4`` (the same scheme one case per prange iteration), ``rk4_switch_aware`` (contact and
  seat switches located inside steps: fourth order, much slower per step) or ``dopri``
  (adaptive Dormand–Prince 5(4), one case per prange iteration, contact and seat switches
  located on its dense output, :mod:`engine_kernels.valvetrain.dopri.integrate`: lift tolerance
  ``DOPRI_TOLERANCE`` per step, excitation table every ``DOPRI_TABLE_DEG``, results on the
  ``angle_step`` grid);
* ``angle_step`` — the RK4 step in cam degrees (the excitation table is sampled at half of it);
* ``tolerance`` — 0 uses ``angle_step``. A positive tolerance [mm] picks the method and step
  per design point: a plain-RK4 integrator first gets one rung at ``angle_step`` (its run
  and error bar); where the bar exceeds the tolerance, ``dopri`` runs at tolerance /
  ``DOPRI_SAFETY`` with its own bar; where that bar still exceeds it, switch-aware RK4 goes
  down a ladder that halves the step, the table spacing and the sub-step together (at most
  ``MAX_HALVINGS`` times) until the bar is within it. The results of the first level that
  meets it are reported (``angle_step_used``, ``integrator_used``, ``tolerance_met``); see
  :mod:`studies.scenes.valve.error_bar`. The jump-speed search runs the chosen integrator
  on the ``angle_step`` grid: RK4 at ``angle_step`` (switch-aware when chosen), or ``dopri``
  on its own table at its per-step tolerance (:mod:`engine_kernels.valvetrain.dopri.jump`).

**Error bars**: asking for ``error_estimate`` runs each point once more with every length
halved; the bar is three times the largest lift difference over the grid. Asking for a bar of
a derived output (``max_lift_error``, ``jump_start_error``, ``seating_velocity_error``,
``bounce_height_error``) also runs a ``dopri`` companion far tighter than the run
(:mod:`studies.scenes.valve.error_bar`). Measured on two samples of 200 random points (the
six-segment cam at camshaft 500–8000 rpm, seat 1e4–1e7 N/mm, preload and drive stiffness
±30 %; every lift law at 500–9000 rpm with lash, damping, mass, spring and drive varied)
against the scipy reference (``tests/studies/test_valve_error_bar.py``): the lift bar bounds
the true error in 98.5 % and 99.5 % of points with ``lanes`` at 0.5° and in 99.5 % with
``rk4_switch_aware``; every bar, of every integrator and under a tolerance, bounds its output
in at least 95.9 % and is within 10× of it in at least 90.6 %.
"""

from __future__ import annotations

import math

import numpy as np

from engine_kernels import valvetrain as valve
from studies.scenes.base import Curve, Parameter, Response
from studies.scenes.linkage.parameters import CURVES as ROCKER_CURVES
from studies.scenes.linkage.parameters import PARAMETERS as ROCKER_PARAMETERS
from studies.scenes.linkage.parameters import RESPONSES as ROCKER_RESPONSES
from studies.scenes.linkage.parameters import TAPPET_STEP
from studies.scenes.valve.spring_parameters import (
    SPRING_PARAMETERS,
    SPRING_SETTINGS,
    SURGE_CURVES,
    SURGE_RESPONSES,
)

THESIS, ASSUMED = "physics §4 thesis", "assumption"
INTEGRATORS = ("lanes", "lanes_f32", "rk4", "rk4_switch_aware", "dopri")
DOPRI = "dopri"
DOPRI_TABLE_DEG = 1.0 / 32.0
"""Excitation table spacing of ``dopri`` [deg]: measured on 48 points of the random sample
(tests/studies/test_valve_error_bar.py), a 0.25° table held its true error at atol 1e-7 m to
a 95th percentile of 0.81 µm (max 6.1 µm), 1/16° to 0.41 µm (max 0.78 µm); 1/32° keeps the
table's share well below 1 µm, and the companion of its error bar halves it."""
DOPRI_TOLERANCE = 1e-7
"""Lift tolerance per step of ``dopri`` without a study tolerance [m] (true error over the
grid ≤ 1 µm on all 48 measured points, 95th percentile 0.34 µm)."""
DOPRI_SAFETY = 10.0
"""Under a study tolerance, ``dopri`` runs at tolerance / DOPRI_SAFETY per step [-]: the
per-step tolerance is local, the global error collects over the event (physics §4: 30–100×)."""


DOPRI_TABLE_TOLERANCE = 1e-6
"""Study tolerance [m] down to which the ``DOPRI_TABLE_DEG`` table serves; below it the
table spacing shrinks with the square root of the tolerance (see :func:`dopri_table_deg`)."""


def dopri_tolerance(tolerance: float) -> float:
    """Lift tolerance per step of ``dopri`` [m] under a study tolerance [m] (0: none)."""
    return tolerance / DOPRI_SAFETY if tolerance > 0.0 else DOPRI_TOLERANCE


def dopri_table_deg(tolerance: float) -> float:
    """Excitation table spacing of ``dopri`` [deg] under a study tolerance [m] (0: none).

    ``DOPRI_TABLE_DEG`` down to ``DOPRI_TABLE_TOLERANCE``, then halved until it is at most
    ``DOPRI_TABLE_DEG·√(tolerance/DOPRI_TABLE_TOLERANCE)``: the table's own error (cubic
    Hermite across the cam law's acceleration jumps) falls 2–4× per halving, and at 1/32° it
    was 0.02–0.03 µm on a 1e6 N/mm seat, the whole error at a 1e-4 mm tolerance.
    """
    if tolerance <= 0.0 or tolerance >= DOPRI_TABLE_TOLERANCE:
        return DOPRI_TABLE_DEG
    halvings = math.ceil(0.5 * math.log2(DOPRI_TABLE_TOLERANCE / tolerance))
    return DOPRI_TABLE_DEG / 2.0**halvings


# Lane integrators and the precision of their arithmetic (the table's dtype selects it).
LANE_PRECISION = {"lanes": np.float64, "lanes_f32": np.float32}
MAX_HALVINGS = 6
STATUS_NOT_RUN = len(valve.VALVE_STATUS_NAMES)
"""Scene status code: the kinematic linkage is invalid, so the dynamics did not run."""
JUMP_NOT_RUN = len(valve.JUMP_STATUS_NAMES)

DYNAMICS_PARAMETERS: tuple[Parameter, ...] = (
    Parameter(
        "cam_speed",
        "rpm",
        3500.0,
        "camshaft speed (engine speed / 2 for a four-stroke)",
        0.0,
        30000.0,
        True,
        source=THESIS,
    ),
    Parameter(
        "equivalent_mass",
        "kg",
        0.04252,
        "equivalent mass on the valve axis M = m_valve + m_spring/3 + I_rocker/lb² [V1]",
        0.0,
        10.0,
        True,
        source=ASSUMED,
    ),
    Parameter(
        "drive_stiffness",
        "N/mm",
        1.17e4,
        "drive stiffness k of rocker and chain on the valve axis",
        0.0,
        1e7,
        source=THESIS,
    ),
    Parameter("drive_damping", "N*s/m", 150.0, "drive damping b", 0.0, 1e6, source=ASSUMED),
    Parameter("spring_rate", "N/mm", 30.0, "valve-spring rate ks", 0.0, 1e5, source=ASSUMED),
    Parameter("spring_preload", "N", 205.8, "valve-spring preload Ps0", 0.0, 1e5, source=THESIS),
    Parameter(
        "seat_stiffness",
        "N/mm",
        5e4,
        "valve-seat contact stiffness kz (seat pre-compressed by Ps0/kz)",
        0.0,
        1e8,
        True,
        source=ASSUMED,
    ),
    Parameter("seat_damping", "N*s/m", 900.0, "valve-seat damping bz", 0.0, 1e6, source=ASSUMED),
    Parameter(
        "external_damping",
        "N*s/m",
        0.0,
        "external damping γ on the valve",
        0.0,
        1e6,
        source=ASSUMED,
    ),
)

PARAMETERS = ROCKER_PARAMETERS + DYNAMICS_PARAMETERS + SPRING_PARAMETERS

INTEGRATOR = Parameter(
    "integrator",
    "1",
    "lanes",
    "RK4 variant: lanes (SIMD blocks), lanes_f32 (the same in single precision), rk4 (one "
    "case per iteration), rk4_switch_aware; or dopri (adaptive Dormand-Prince 5(4) with "
    "located switches, reported on the angle_step grid)",
    choices=INTEGRATORS,
)
ANGLE_STEP = Parameter(
    "angle_step",
    "degree",
    0.5,
    "RK4 step in cam angle (excitation every half step; must divide 2 deg)",
    0.001,
    2.0,
    True,
)
WINDOW_SETTINGS: tuple[Parameter, ...] = (
    Parameter(
        "closing_window",
        "degree",
        30.0,
        "integration continues this far past valve closure (bounces, settling)",
        0.0,
        180.0,
    ),
    Parameter(
        "max_substeps",
        "1",
        float(valve.DEFAULT_MAX_SUBSTEPS),
        "largest number of RK4 sub-steps per step the stability guard may use",
        1.0,
        1e5,
        integer=True,
    ),
    Parameter(
        "jump_speed_low", "rpm", 500.0, "jump speed search: lowest camshaft speed", 0.0, 1e5, True
    ),
    Parameter(
        "jump_speed_high",
        "rpm",
        15000.0,
        "jump speed search: highest camshaft speed",
        0.0,
        1e5,
        True,
    ),
    Parameter(
        "jump_speed_tolerance",
        "1",
        1e-3,
        "jump speed: relative width of the final bisection bracket (the integrator's own "
        "error in where the valve separates adds to it: lanes at 0.5 deg was within 1e-5 to "
        "3.7e-4 of an independent DOP853 reference at 6 random points, tolerance mode alike)",
        1e-9,
        0.5,
    ),
)
TOLERANCE = Parameter(
    "tolerance",
    "mm",
    0.0,
    "if > 0: halve the step per design point until the error bar is at most this (see "
    "studies.scenes.valve.error_bar); 0 = use angle_step",
    0.0,
    10.0,
)
SETTINGS: tuple[Parameter, ...] = (
    INTEGRATOR,
    ANGLE_STEP,
    TOLERANCE,
    TAPPET_STEP,
    *WINDOW_SETTINGS,
    *SPRING_SETTINGS,
)

DYN = ("tappet", "rocker", "dynamics")
ON_GRID = (
    ", read at the angle_step grid points (the peak between them can be larger: refine "
    "angle_step to converge it)"
)
IN_WINDOW = " in the integration window (to the closing angle + closing_window)"
UNSETTLED = (
    "{IN_WINDOW}; NaN: unknown, when the window ended the valve's energy could still {what} "
    "(multi-mass spring: it was off its seat): raise closing_window"
)
JUMP = ("tappet", "rocker", "jump_speed")

DYNAMIC_RESPONSES: tuple[Response, ...] = (
    Response(
        "max_lift", "mm", "maximum actual valve lift y (located between grid points)", DYN, "larger"
    ),
    Response("max_opening_velocity", "m/s", f"largest valve velocity (opening){ON_GRID}", DYN),
    Response(
        "max_closing_velocity",
        "m/s",
        f"most negative valve velocity (closing){ON_GRID}",
        DYN,
        "larger",
    ),
    Response("max_acceleration", "m/s^2", f"largest valve acceleration{ON_GRID}", DYN),
    Response(
        "min_acceleration", "m/s^2", f"most negative valve acceleration{ON_GRID}", DYN, "larger"
    ),
    Response(
        "follows_cam",
        "1",
        "no separation: the drive force stays > 0 while the valve is off its seat",
        DYN,
        "larger",
        flag=True,
    ),
    Response(
        "jump_start",
        "degree",
        "cam angle where separation first starts, located between grid points (NaN: none)",
        DYN,
        none_means="best",
        none_label="no separation",
    ),
    Response("jump_duration", "degree", "cam angle over which the valve is separated", DYN),
    Response("jump_max_gap", "mm", "largest gap y − Y while separated", DYN),
    Response(
        "bounce_count",
        "1",
        "seat contacts lost again after the first closure (on a very stiff seat a contact "
        "lasts about one RK4 sub-step, and RK4 takes energy out at each: with little seat "
        "damping the RK4 integrators count too few bounces, and a finer angle_step does not "
        "show it: 17 at 0.5 deg and 20 at 1/16 deg where dopri counts 599 and an independent "
        "DOP853 reference 608 at 500 rpm, seat 1e8 N/mm, no seat damping; and they may call "
        "settled a valve dopri finds still bouncing: use integrator = dopri for bounce counts)"
        + UNSETTLED.format(IN_WINDOW=IN_WINDOW, what="lift it off its seat"),
        DYN,
    ),
    Response(
        "bounce_height",
        "mm",
        "largest bounce height off the seat"
        + UNSETTLED.format(IN_WINDOW=IN_WINDOW, what="lift it above its largest bounce"),
        DYN,
    ),
    Response(
        "seating_velocity", "m/s", f"valve speed at the first closure{IN_WINDOW} (NaN: none)", DYN
    ),
    Response("max_contact_force", "N", f"largest drive (rocker–valve) force{ON_GRID}", DYN),
    Response(
        "substeps",
        "1",
        "RK4 sub-steps per step used by the stability guard (dopri: its accepted steps in all)",
        DYN,
    ),
    Response(
        "step_ratio",
        "1",
        "largest |h λ| per sub-step (RK4 bound about 2.6; dopri: of its steps, whose error "
        "control keeps them stable, with no such bound)",
        DYN,
    ),
    Response("mode_transitions", "1", "contact and seat mode changes on the grid", DYN),
    Response(
        "status",
        "1",
        "run status of the dynamics (not_run: the kinematic chain is invalid)",
        DYN,
        codes=(*valve.VALVE_STATUS_NAMES, "not_run"),
    ),
    Response("run_ok", "1", "dynamics ran and finished with status ok", DYN, "larger", flag=True),
    Response(
        "error_estimate",
        "mm",
        "error bar of the lift over the grid: 3 max|y(h) − y(h/2)|, the companion run with "
        "every length halved (step, table spacing, sub-step); never NaN for a finished point",
        DYN,
    ),
    Response(
        "step_halving_difference",
        "mm",
        "max|y(h) − y(h/2)| over the grid, the companion with every length halved",
        DYN,
    ),
    Response("max_lift_error", "mm", "error bar of max_lift (against a dopri companion)", DYN),
    Response(
        "jump_start_error",
        "degree",
        "error bar of jump_start (against a dopri companion; inf: the runs disagree)",
        DYN,
    ),
    Response(
        "seating_velocity_error",
        "m/s",
        "error bar of seating_velocity (against a dopri companion)",
        DYN,
    ),
    Response(
        "bounce_height_error", "mm", "error bar of bounce_height (against a dopri companion)", DYN
    ),
    Response(
        "integration_error",
        "mm",
        "RK4 part of the error bar: 3 max|y − y'| against a run with twice the sub-steps on the "
        "same excitation table",
        DYN,
    ),
    Response(
        "excitation_error",
        "mm",
        "excitation part of the error bar: the Hermite table of the kinematic chain at half "
        "the step against one at a quarter (same sub-step length)",
        DYN,
    ),
    Response(
        "angle_step_used",
        "degree",
        "RK4 step used (picked per point with a tolerance)",
        DYN,
        used_for="angle_step",
    ),
    Response(
        "integrator_used",
        "1",
        "integrator of the reported results (picked per point with a tolerance)",
        DYN,
        codes=INTEGRATORS,
        used_for="integrator",
    ),
    Response(
        "tolerance_met",
        "1",
        "the error bar is within the tolerance (1 when no tolerance is set)",
        DYN,
        "larger",
        flag=True,
    ),
    Response(
        "jump_speed",
        "rpm",
        "jump speed: lowest camshaft speed at which the valve separates (scan + bisection)",
        JUMP,
        "larger",
    ),
    Response(
        "jump_speed_status",
        "1",
        "jump speed search status (at_lower_bound: already separated at the lowest speed; "
        "not_run: the kinematic chain is invalid)",
        JUMP,
        codes=(*valve.JUMP_STATUS_NAMES, "not_run"),
    ),
)
RESPONSES = ROCKER_RESPONSES + DYNAMIC_RESPONSES + SURGE_RESPONSES

DYNAMIC_CURVES: tuple[Curve, ...] = (
    Curve("actual_lift", "mm", "actual valve lift y (NaN outside the integration window)", DYN),
    Curve("actual_velocity", "m/s", "actual valve velocity", DYN),
    Curve("actual_acceleration", "m/s^2", "actual valve acceleration", DYN),
    Curve("drive_force", "N", "drive (rocker–valve) contact force", DYN),
    Curve("seat_force", "N", "valve-seat contact force", DYN),
)
CURVES = ROCKER_CURVES + DYNAMIC_CURVES + SURGE_CURVES
