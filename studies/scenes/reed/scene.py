"""The ``reed`` scene: reed-valve natural frequencies, mode shapes and resonance margins (physics §6).

One stage, ``frequencies`` (:func:`engine_kernels.reed.reed_batch`): roots of the clamped–free
frequency equation [B1], natural frequencies [B2] of the first ``N_MODES`` modes, the engine
excitation band from the speed range, the signed margin of each mode to the band (positive
outside, negative inside), the lowest engine-order harmonic that reaches f₁ and the speed at
which it does, for every mode the lowest engine order (up to the setting ``max_order``) that
crosses it within the speed range, at which speed, and the margin to the nearest order band,
``resonance_free`` (no order crosses any mode within ±``resonance_margin``), and (as curves)
the mode shapes along the reed. ``first_mode_clear``/``all_modes_clear`` compare with the
band of the event frequency only; ``campbell.png`` shows the orders against the modes.

Orders are **engine orders**: multiples of the crankshaft frequency, as the ``crank`` scene's
``torque_order_*`` (physics §5, §6). The reed opens e times per crank revolution (e = 0.5 for a
four-stroke), so harmonic k of its event frequency is engine order k·e: a four-stroke's reed
sees orders 0.5, 1, 1.5, …, and the reference reed's 204 Hz meets order 1.5 at 8172 rpm
(n = 60 f/o). A missing crossing (no order up to ``max_order`` meets the mode in the speed
range) is the best outcome: those responses declare ``none_means = "best"``.

Materials (the ``material`` factor has string levels; E and ρ from this table):

============  =========  ===========  ==============================================
material      E [GPa]    ρ [kg/m³]    source
============  =========  ===========  ==============================================
spring_steel  208        7800         physics §6 reference reed
stainless     193        7900         AISI 301 spring-temper strip, typical handbook
                                      values (assumption)
glass_epoxy   18.6       1850         G-10/FR-4 laminate, lengthwise flexural
                                      modulus, typical datasheet values (assumption)
custom        youngs_modulus, density parameters
============  =========  ===========  ==============================================
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from engine_kernels import reed as rd
from studies.common.units import UNITS
from studies.scenes.base import Curve, CurveAxis, Parameter, Response, Scene, SceneOutput
from studies.scenes.checks import LoopOrder, on_distinct
from studies.scenes.state import RunState

if TYPE_CHECKING:
    import xarray as xr

    from studies.scenes.base import FigureBuilder

SRC = "physics §6 reference reed"
MATERIALS: dict[str, tuple[float, float]] = {
    "spring_steel": (208e9, 7800.0),
    "stainless": (193e9, 7900.0),
    "glass_epoxy": (18.6e9, 1850.0),
}
"""Young's modulus [Pa] and density [kg/m³] of the tabulated materials (module docstring)."""
OPENINGS = {"four_stroke": 0.5, "two_stroke": 1.0}
"""Reed openings per crank revolution."""
N_MODES = 4
MODE_WORDS = ("first", "second", "third", "fourth")
MIN_SLENDERNESS = 10.0
"""Smallest length/thickness for which Euler–Bernoulli beam theory is used."""

PARAMETERS: tuple[Parameter, ...] = (
    Parameter("length", "mm", 35.0, "free length l of the reed", 0.0, 1000.0, True, source=SRC),
    Parameter("width", "mm", 11.5, "width b of the reed", 0.0, 1000.0, True, source=SRC),
    Parameter("thickness", "mm", 0.3, "thickness h of the reed", 0.0, 100.0, True, source=SRC),
    Parameter(
        "material",
        "1",
        "spring_steel",
        "reed material (E, ρ from the scene's table; 'custom' uses youngs_modulus and density)",
        choices=(*MATERIALS, "custom"),
        source=SRC,
    ),
    Parameter(
        "youngs_modulus",
        "GPa",
        208.0,
        "Young's modulus E (material = 'custom')",
        0.0,
        2000.0,
        True,
        source=SRC,
    ),
    Parameter(
        "density", "kg/m^3", 7800.0, "density ρ (material = 'custom')", 0.0, 1e5, True, source=SRC
    ),
    Parameter(
        "speed_min",
        "rpm",
        1200.0,
        "lowest engine speed of the excitation band",
        0.0,
        1e5,
        True,
        source="physics §6",
    ),
    Parameter(
        "speed_max",
        "rpm",
        9000.0,
        "highest engine speed of the excitation band",
        0.0,
        1e5,
        True,
        source="physics §6",
    ),
    Parameter(
        "cycle",
        "1",
        "four_stroke",
        "engine cycle: the reed opens once per cycle",
        choices=tuple(OPENINGS),
        source="physics §6",
    ),
)

SETTINGS: tuple[Parameter, ...] = (
    Parameter(
        "shape_points",
        "1",
        51.0,
        "points along the reed for the mode-shape curves",
        2.0,
        10001.0,
        integer=True,
    ),
    Parameter(
        "max_order",
        "1",
        3.0,
        "highest engine order (multiple of the crankshaft frequency) checked against every "
        "natural frequency; a four-stroke's reed is checked at orders 0.5, 1, …, max_order",
        1.0,
        100.0,
        integer=True,
    ),
    Parameter(
        "resonance_margin",
        "1",
        0.05,
        "relative margin of resonance_free: each order band widened by it (0.05 = ±5 %)",
        0.0,
        1.0,
    ),
)

NEEDS = ("frequencies",)


def _mode_responses() -> tuple[Response, ...]:
    out: list[Response] = []
    for word in MODE_WORDS:
        out += [
            Response(f"{word}_frequency", "Hz", f"{word} natural frequency", NEEDS, "larger"),
            Response(
                f"{word}_margin",
                "Hz",
                f"margin of the {word} mode to the band of the event frequency (engine order "
                "e: 0.5 four-stroke; > 0 outside, < 0 inside; other orders: order_margin)",
                NEEDS,
                "larger",
            ),
            Response(
                f"{word}_crossing_order",
                "1",
                f"lowest engine order (≤ max_order; multiples of the crankshaft frequency) "
                f"crossing the {word} mode in the speed range (none: no crossing)",
                NEEDS,
                "larger",
                none_means="best",
                none_label="no crossing up to order {max_order:g}",
            ),
            Response(
                f"{word}_crossing_speed",
                "rpm",
                f"engine speed at which that order meets the {word} mode (none: no crossing)",
                NEEDS,
                "larger",
                none_means="best",
                none_label="no crossing up to order {max_order:g}",
            ),
            Response(
                f"{word}_order_margin",
                "Hz",
                f"margin of the {word} mode to the engine-order bands up to max_order over the "
                "speed range "
                "(> 0: distance to the nearest band; < 0: depth into the crossing order's band)",
                NEEDS,
                "larger",
            ),
        ]
    return tuple(out)


RESPONSES: tuple[Response, ...] = (
    *_mode_responses(),
    Response(
        "first_margin_ratio", "1", "first-mode margin over the first frequency", NEEDS, "larger"
    ),
    Response("band_min", "Hz", "lowest excitation frequency", NEEDS),
    Response("band_max", "Hz", "highest excitation frequency", NEEDS),
    Response(
        "first_mode_clear",
        "1",
        "first natural frequency outside the band of the event frequency (only the "
        "fundamental of the excitation: see resonance_free for the other engine orders)",
        NEEDS,
        "larger",
        flag=True,
    ),
    Response(
        "all_modes_clear",
        "1",
        f"all {N_MODES} natural frequencies outside the band of the event frequency (only the "
        "fundamental of the excitation: see resonance_free for the other engine orders)",
        NEEDS,
        "larger",
        flag=True,
    ),
    Response(
        "resonance_free",
        "1",
        f"no engine order up to max_order crosses any of the {N_MODES} modes within "
        "±resonance_margin over the speed range",
        NEEDS,
        "larger",
        flag=True,
    ),
    Response(
        "events_per_revolution",
        "1",
        "reed openings (excitation events) per crank revolution: 0.5 four-stroke, 1 two-stroke",
        NEEDS,
    ),
    Response(
        "harmonic_order",
        "1",
        "engine order of the lowest harmonic of the event frequency whose band reaches f₁ "
        "(any order; none: f₁ falls between two bands)",
        NEEDS,
        "larger",
        none_means="best",
        none_label="f₁ between two bands",
    ),
    Response(
        "resonance_speed",
        "rpm",
        "engine speed at which that order meets f₁ (none: no order reaches f₁)",
        NEEDS,
        "larger",
        none_means="best",
        none_label="no order reaches f₁",
    ),
    Response("tip_stiffness", "N/m", "static tip stiffness 3EI/l³", NEEDS, "larger"),
    Response("mass", "g", "reed mass ρ b h l", NEEDS),
)

CURVES: tuple[Curve, ...] = tuple(
    Curve(f"mode_shape_{k + 1}", "1", f"{MODE_WORDS[k]} mode shape (unit tip deflection)", NEEDS)
    for k in range(N_MODES)
)

POSITION = CurveAxis("position", "1", "position along the reed x/l from the clamp")


def material_properties(points: dict[str, np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """Young's modulus [Pa] and density [kg/m³] per design point."""
    listed = np.array([MATERIALS.get(m, (np.nan, np.nan)) for m in points["material"]])
    modulus, density = listed[:, 0], listed[:, 1]
    custom = points["material"] == "custom"
    modulus[custom] = points["youngs_modulus"][custom]
    density[custom] = points["density"][custom]
    return modulus, density


CHECKED = ("speed_min", "speed_max", "length", "thickness")
"""The parameters ``check_points`` reads."""


@dataclass(slots=True)
class ReedState(RunState):
    """Run state of a ``reed`` chunk: the kernels' arrays (SI, columns of :mod:`engine_kernels.reed`)."""

    params: np.ndarray = field(init=False)  # reed parameters (n, rd.N_PARAMS)
    out: np.ndarray = field(init=False)  # per reed (n, rd.N_OUT), rd.OUTPUTS
    modes: np.ndarray = field(init=False)  # per mode (n, rd.N_MODE_OUT, N_MODES): f [Hz], margin
    shapes: np.ndarray = field(init=False)  # mode shapes (n, N_MODES, shape points) [1]
    orders: np.ndarray = field(init=False)  # engine-order crossings (n, N_MODES, rd.N_ORDER_OUT)


class ReedScene(Scene[ReedState]):
    """Clamped–free reed valve excited by the engine (physics §6)."""

    name = "reed"
    seconds_per_point = 3e-4
    description = (
        "reed-valve natural frequencies, mode shapes and margins to the engine's "
        "excitation band (physics §6)"
    )
    parameters = PARAMETERS
    settings = SETTINGS
    responses = RESPONSES
    curves = CURVES
    curve_axis = POSITION
    stage_order = NEEDS
    state_type = ReedState

    # --- outputs beside the generic ones -----------------------------------------------------
    def figures(self) -> dict[str, FigureBuilder]:
        from studies.scenes.reed.campbell import campbell_figure  # noqa: PLC0415
        from studies.scenes.reed.figures import (  # noqa: PLC0415  (matplotlib on use)
            frequency_map_figure,
            mode_shapes_figure,
        )

        return {
            "frequency_map": frequency_map_figure,
            "mode_shapes": mode_shapes_figure,
            "campbell": campbell_figure,
        }

    def summaries(self, ds: xr.Dataset) -> list[str]:
        from studies.scenes.reed.summaries import reed_summary  # noqa: PLC0415  (xarray on use)

        return reed_summary(ds)

    def curve_coordinate(self, settings: dict[str, Any]) -> np.ndarray:
        return np.linspace(0.0, 1.0, int(settings["shape_points"]))

    def check_points(self, points: Mapping[str, np.ndarray], settings: dict[str, Any]) -> list[str]:
        return on_distinct(points, CHECKED, self._distinct_problems)

    def _distinct_problems(self, points: dict[str, np.ndarray]) -> list[str]:
        found = LoopOrder()
        mm = UNITS["mm"].to_si
        rpm = UNITS["rpm"].to_si
        lo, hi = np.asarray(points["speed_min"]), np.asarray(points["speed_max"])
        found.add(
            0,
            lo >= hi,
            [lo, hi],
            lambda i: (
                f"speed_min = {lo[i] / rpm:g} rpm must be below speed_max = {hi[i] / rpm:g} rpm"
            ),
        )
        length, h = np.asarray(points["length"]), np.asarray(points["thickness"])
        found.add(
            1,
            length < MIN_SLENDERNESS * h,
            [length, h],
            lambda i: (
                f"length/thickness = {length[i] / mm:g} mm / {h[i] / mm:g} mm = "
                f"{length[i] / h[i]:.3g} is below {MIN_SLENDERNESS:g}: the reed is not a "
                "slender beam and [B1]/[B2] do not apply"
            ),
        )
        return found.messages()

    def stage_frequencies(self, state: ReedState) -> None:
        """Modes [B1]/[B2], margins to the excitation band, shapes if asked, order crossings."""
        points, n = state.points, state.n
        state.params = params = np.empty((n, rd.N_PARAMS))
        params[:, rd.LENGTH] = points["length"]
        params[:, rd.WIDTH] = points["width"]
        params[:, rd.THICKNESS] = points["thickness"]
        params[:, rd.YOUNGS_MODULUS], params[:, rd.DENSITY] = material_properties(points)
        params[:, rd.SPEED_MIN] = points["speed_min"]
        params[:, rd.SPEED_MAX] = points["speed_max"]
        params[:, rd.OPENINGS_PER_REVOLUTION] = [OPENINGS[c] for c in points["cycle"]]
        n_points = int(state.settings["shape_points"]) if state.curves else 0
        state.out = np.empty((n, rd.N_OUT))
        state.modes = np.empty((n, rd.N_MODE_OUT, N_MODES))
        state.shapes = np.empty((n, N_MODES, n_points))
        rd.reed_batch(params, state.out, state.modes, state.shapes)
        state.orders = np.empty((n, N_MODES, rd.N_ORDER_OUT))
        frequencies = np.ascontiguousarray(state.modes[:, rd.MODE_FREQUENCY, :])
        max_order = float(state.settings["max_order"])
        margin = float(state.settings["resonance_margin"])
        rd.order_batch(frequencies, params, max_order, margin, state.orders)

    def finish(self, state: ReedState) -> SceneOutput:
        modes, orders = state.modes, state.orders
        si = dict(zip(rd.OUTPUTS, state.out.T, strict=True))
        for k, word in enumerate(MODE_WORDS):
            si[f"{word}_frequency"] = modes[:, rd.MODE_FREQUENCY, k]
            si[f"{word}_margin"] = modes[:, rd.MODE_MARGIN, k]
        si["first_mode_clear"] = (modes[:, rd.MODE_MARGIN, 0] > 0).astype(float)
        si["all_modes_clear"] = (modes[:, rd.MODE_MARGIN, :] > 0).all(axis=1).astype(float)
        for k, word in enumerate(MODE_WORDS):
            si[f"{word}_crossing_order"] = orders[:, k, rd.CROSSING_ORDER]
            si[f"{word}_crossing_speed"] = orders[:, k, rd.CROSSING_SPEED]
            si[f"{word}_order_margin"] = orders[:, k, rd.ORDER_MARGIN]
        si["resonance_free"] = orders[:, :, rd.ORDER_CLEAR].min(axis=1)
        si["events_per_revolution"] = state.params[:, rd.OPENINGS_PER_REVOLUTION]
        return SceneOutput(
            scalars={
                r: si[r] / UNITS[self.response(r).units].to_si  # type: ignore[union-attr]
                for r in state.responses
            },
            curves={c: state.shapes[:, int(c.rsplit("_", 1)[1]) - 1] for c in state.curves},
        )
