"""Numba is imported on the first kernel call, not on import (engine_kernels._jit), and
``call_small`` runs few evaluations as plain Python with the compiled answers.

Each case runs in a fresh interpreter: in the test process Numba is bound long before."""

from __future__ import annotations

import json
import subprocess
import sys
import textwrap

import numpy as np

from engine_kernels.cam import kinematics as cb
from engine_kernels.cam import lift_laws
from engine_kernels.valvetrain import rocker_batches
from studies.scenes.cam_radius import angle_grid

GEOMETRY_MM = [12.5, 30.0, 39.61, 30.28, 33.28, 10.0, 1.65, 0.05]  # ohc125 rocker (physics §3)


def run_fresh(code: str) -> str:
    done = subprocess.run(
        [sys.executable, "-c", textwrap.dedent(code)],
        capture_output=True,
        text=True,
        check=False,
        timeout=600,
    )
    assert done.returncode == 0, done.stderr
    return done.stdout


def test_importing_the_cli_and_every_scene_does_not_import_numba():
    out = run_fresh(
        """
        import sys
        import studies.cli
        from studies.scenes import SCENES
        for name in SCENES:
            SCENES[name]
        print(sorted(SCENES), "numba" in sys.modules)
        """
    )
    assert out.strip().endswith("False")


def test_checking_a_shipped_cam_and_valve_study_starts_no_compiler():
    out = run_fresh(
        """
        import sys
        from engine_kernels import _jit
        from studies.cli import main
        codes = [main(["check", name]) for name in ("isac_l9", "ohc125_dynamics")]
        print(codes, _jit.bound(), "numba" in sys.modules)
        """
    )
    assert out.strip().splitlines()[-1] == "[0, 0] False False"


def test_plain_python_answers_equal_the_compiled_ones():
    # Reference: the same kernels compiled, in this process (Numba bound by the suite).
    lifts = np.array([0.002, 0.007815, 0.009, 0.5])  # m; 0.5 m: asin(> 1), NaN when compiled
    geometry = np.tile(np.array(GEOMETRY_MM) / 1e3, (lifts.size, 1))
    compiled = np.empty(lifts.size)
    rocker_batches.tappet_lift_for_valve_lift_batch(lifts, geometry, compiled)
    assert np.isnan(compiled[-1])
    params = np.zeros((3, cb.N_PARAMS))
    params[:, cb.P_LAW] = [0, 1, 2]
    params[:, cb.P_CAM_SPEED] = 1.0
    params[:, cb.P_BASE_RADIUS] = 0.02
    params[:, cb.P_LIFT] = 0.008
    params[:, cb.P_RISE_ANGLE] = np.radians(70.0)
    shapes = np.zeros((3, 6), dtype=np.int64)
    coefficients = np.zeros((3, lift_laws.NCOEF))
    radius = np.empty(3)
    cb.min_radius_of_curvature_batch(params, shapes, coefficients, angle_grid(0.5), radius)
    out = run_fresh(
        f"""
        import json
        import numpy as np
        from engine_kernels import _jit
        from engine_kernels._jit import call_small
        from engine_kernels.cam import kinematics as cb
        from engine_kernels.valvetrain import rocker_batches
        from studies.scenes.cam_radius import angle_grid
        lifts = np.array({lifts.tolist()})
        geometry = np.tile(np.array({GEOMETRY_MM}) / 1e3, (lifts.size, 1))
        nose = np.empty(lifts.size)
        call_small(rocker_batches.tappet_lift_for_valve_lift_batch, 4, lifts[:3], geometry[:3],
                   nose[:3])
        first_bound = _jit.bound()
        params = np.array({params.tolist()})
        shapes = np.zeros((3, 6), dtype=np.int64)
        radius = np.empty(3)
        grid = angle_grid(0.5)
        call_small(cb.min_radius_of_curvature_batch, 3 * grid.size, params, shapes,
                   np.zeros((3, {lift_laws.NCOEF})), grid, radius)
        second_bound = _jit.bound()
        call_small(rocker_batches.tappet_lift_for_valve_lift_batch, 4, lifts, geometry, nose)
        bound = [first_bound, second_bound, _jit.bound()]
        print(json.dumps({{"nose": nose.tolist(), "radius": radius.tolist(), "bound": bound}}))
        """
    )
    got = json.loads(out.strip().splitlines()[-1])
    np.testing.assert_allclose(got["nose"], compiled, rtol=1e-13)
    np.testing.assert_allclose(got["radius"], radius, rtol=1e-12)
    # plain Python for the valid calls; the unreachable lift raised there and ran compiled
    assert got["bound"] == [False, False, True]


def test_without_compiler_spends_one_budget_and_never_binds_numba():
    # Witness: the counts asked for (the budget is a sum of them) and sys.modules.
    out = run_fresh(
        f"""
        import sys
        import numpy as np
        from engine_kernels import _jit
        from engine_kernels._jit import CompilerNeeded, call_small, without_compiler
        from engine_kernels.valvetrain import rocker_batches
        kernel = rocker_batches.tappet_lift_for_valve_lift_batch
        lifts, out = np.array([0.005]), np.empty(1)
        geometry = np.array([{GEOMETRY_MM}]) / 1e3
        seen = []
        def attempt(work):
            try:
                call_small(kernel, work, lifts, geometry, out)
                seen.append(work)
            except CompilerNeeded as exc:
                seen.append(-exc.work)
        with without_compiler(10):
            attempt(4)
            with without_compiler(100):  # nested: draws on the outer 6 left
                attempt(5)
                attempt(2)
            attempt(1)  # 10 - 4 - 5 = 1 left
            attempt(1)
            try:
                kernel(lifts, geometry, out)
            except CompilerNeeded as exc:
                seen.append(("direct", exc.work))
        print(seen, _jit.bound(), "numba" in sys.modules)
        """
    )
    assert out.strip().splitlines()[-1] == "[4, 5, -2, 1, -1, ('direct', 0)] False False"
