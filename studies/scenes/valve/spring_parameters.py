"""Declarations of the valve scene's spring model ladder [V4]: parameters, settings, responses.

Two rungs model the valve spring (physics §4):

* ``spring_model = "lumped"`` (the default, the cheap rung) — the thesis's single degree of
  freedom: one third of the spring's mass on the valve (``equivalent_mass`` [V1]), the spring
  force at the retainer always the static ``Ps0 + ks·y``;
* ``spring_model = "multi_mass"`` — the spring as ``spring_masses`` = N coil masses joined by
  N+1 segments with internal damping and coil clash at solid length
  (:mod:`engine_kernels.valvetrain.spring_chain.model`). The valve-side mass is
  ``equivalent_mass − spring_mass/3``, so both rungs describe the same valve train. Surge —
  the spring's standing waves — changes the force at the retainer, can bring jump early and
  clash coils.

Asking for a spring response (``SURGE_RESPONSES``) runs the multi-mass model whatever
``spring_model`` says (the lumped rung has no surge to report); the other dynamic responses
come from the rung ``spring_model`` names, so a study that asks for none of these never runs
the chain. Responses and curves the chain kernel does not observe are listed in
``CHAIN_UNOBSERVED``; ``check`` refuses them under ``multi_mass``.
"""

from __future__ import annotations

from engine_kernels import valvetrain as valve
from studies.scenes.base import Curve, Parameter, Response

ASSUMED = "assumption"
SPRING_MODELS = ("lumped", "multi_mass")
SURGE = ("tappet", "rocker", "surge")

SPRING_PARAMETERS: tuple[Parameter, ...] = (
    Parameter(
        "spring_mass",
        "kg",
        0.015,
        "valve-spring mass m_s (its third is part of equivalent_mass [V1])",
        0.0,
        1.0,
        True,
        source=ASSUMED,
    ),
    Parameter(
        "spring_damping_ratio",
        "1",
        0.02,
        "modal damping ratio of the spring's first surge mode (multi-mass model)",
        0.0,
        1.0,
        source=ASSUMED,
    ),
    Parameter(
        "clash_travel",
        "mm",
        9.5,
        "spring compression from installed to solid length (coil clash beyond it)",
        0.0,
        1e3,
        True,
        source=ASSUMED,
    ),
    Parameter(
        "clash_stiffness",
        "N/mm",
        1e4,
        "stiffness of the one-sided coil-on-coil stop at solid length",
        0.0,
        1e7,
        source=ASSUMED,
    ),
    Parameter(
        "clash_damping",
        "N*s/m",
        10.0,
        "damping of the coil-on-coil stop",
        0.0,
        1e6,
        source=ASSUMED,
    ),
)

SPRING_MODEL = Parameter(
    "spring_model",
    "1",
    "lumped",
    "valve-spring model: lumped (m_s/3 on the valve, the thesis model) or multi_mass "
    "(a chain of spring_masses coil masses: surge, coil clash)",
    choices=SPRING_MODELS,
)
SPRING_MASSES = Parameter(
    "spring_masses",
    "1",
    8.0,
    "coil masses N of the multi-mass spring (resolves about N/2 surge modes)",
    1.0,
    24.0,
    integer=True,
)
REVOLUTIONS = Parameter(
    "revolutions",
    "1",
    1.0,
    "camshaft revolutions integrated for the spring responses: 1 = the valve event only; "
    "R > 1 repeats the cam and takes surge amplitude and retainer force over the last "
    "revolution (steady-state surge: the order resonances j·n_cam/60 = f_1)",
    1.0,
    64.0,
    integer=True,
)
SPRING_SETTINGS: tuple[Parameter, ...] = (SPRING_MODEL, SPRING_MASSES, REVOLUTIONS)

SURGE_RESPONSES: tuple[Response, ...] = (
    Response(
        "surge_amplitude",
        "mm",
        "largest coil displacement off the spring's static deflection line (multi-mass model)",
        SURGE,
    ),
    Response(
        "min_retainer_force_ratio",
        "1",
        "smallest spring force at the retainer / static spring force Ps0 + ks·y",
        SURGE,
        "larger",
    ),
    Response(
        "max_retainer_force_deviation",
        "N",
        "largest |retainer force − static spring force|",
        SURGE,
    ),
    Response(
        "surge_frequency",
        "Hz",
        "first surge frequency f_1 of the spring with both ends held: the N-mass chain's [V4] "
        "(lumped rung: the continuous spring's (1/2)·√(ks/m_s), which it does not model)",
        SURGE,
        "larger",
    ),
    Response("coil_clash_count", "1", "segment closures to solid length (coil clash)", SURGE),
    Response(
        "surge_status",
        "1",
        "run status of the multi-mass spring model (not_run: the kinematic chain is invalid)",
        SURGE,
        codes=(*valve.VALVE_STATUS_NAMES, "not_run"),
    ),
)
SURGE_CURVES: tuple[Curve, ...] = (
    Curve("retainer_force", "N", "spring force at the retainer (multi-mass model)", SURGE),
    Curve("spring_surge", "mm", "coil displacement off the static deflection line", SURGE),
)

CHAIN_UNOBSERVED = frozenset(
    {
        "max_acceleration",
        "min_acceleration",
        "mode_transitions",
        "error_estimate",
        "step_halving_difference",
        "jump_start_error",
        "seating_velocity_error",
        "bounce_height_error",
        "max_lift_error",
        "integration_error",
        "excitation_error",
        "integrator_used",
        "tolerance_met",
        "actual_acceleration",
        "seat_force",
    }
)
"""Dynamic responses and curves of the lumped rung that the multi-mass kernel does not give."""
