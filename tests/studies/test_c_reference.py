"""The C reference of the valve lane kernel does the same work as the Numba lanes.

``python -m studies bench valve`` compares the Numba lane kernel with this C kernel
(``studies/scenes/valve/reference/valve_lanes.c``) as "a C -O3 kernel of this form"; the comparison is
only fair if both compute the same thing. Expected values: the Numba lane kernel, itself
checked against the one-case kernel and scipy (tests/engine_kernels/test_valve_lanes.py).
The two differ only in where the compilers fuse multiply-adds, so continuous outputs agree
to round-off and counts and statuses exactly. Skipped where no C compiler is installed.
"""

from __future__ import annotations

import math
import os
from pathlib import Path

import numpy as np
import pytest

from engine_kernels import valvetrain as valve
from engine_kernels.valvetrain.valve import lane_batch as valve_lanes
from studies.scenes.valve.reference import c_valve

RPM = 2 * math.pi / 60
MASS = 0.033 + 0.015 / 3 + 5e-6 / 33.28e-3**2
PARAMS = np.array([3500 * RPM, MASS, 1.17e7, 150.0, 3.0e4, 205.8, 5.0e7, 900.0, 0.0, 0.0, 0.0])
COUNTS = (valve.O_BOUNCE_COUNT, valve.O_TRANSITIONS, valve.O_STATUS, valve.O_JUMP_DURATION)
CONTINUOUS = tuple(
    i
    for i in range(len(valve.VALVE_OUTPUT_NAMES))
    if i not in (*COUNTS, valve.O_SUBSTEPS, valve.O_STEP_RATIO, valve.O_ERROR_ESTIMATE)
)


def event_table(step_deg=0.5, height=4e-3, half=1.4):
    """1 − cos cam event, rows Y [m], Y' [m/rad], Y'' at half the RK4 step (physics §9)."""
    theta = np.radians(np.arange(-100.0, 110.0 + step_deg / 4, step_deg / 2))
    wave = math.pi / half
    inside = np.abs(theta) < half
    rows = (
        np.where(inside, height * (1 + np.cos(wave * theta)), 0.0),
        np.where(inside, -height * wave * np.sin(wave * theta), 0.0),
        np.where(inside, -height * wave**2 * np.cos(wave * theta), 0.0),
    )
    return np.stack(rows), math.radians(step_deg / 2), theta[0]


@pytest.fixture(scope="module")
def library():
    try:
        return c_valve.build(np.dtype(np.float64))
    except c_valve.CompilerMissing as error:
        pytest.skip(str(error))


def test_c_reference_matches_numba_lanes(library):
    # 70 cases from following the cam to jump and bounce: two full blocks and a partial one.
    rng = np.random.default_rng(3)
    rows = np.tile(PARAMS, (70, 1))
    rows[:, valve.P_SPEED] = rng.uniform(2000, 9000, 70) * RPM
    rows[:, valve.P_SPRING_RATE] = rng.uniform(1e4, 6e4, 70)
    rows[:, valve.P_SEAT_DAMPING] = rng.uniform(0.0, 900.0, 70)
    table, step, start = event_table()
    numba_out = np.empty((70, len(valve.VALVE_OUTPUT_NAMES)))
    valve_lanes.valve_response_lanes(table, step, start, rows, valve.valve_settings(), numba_out)
    assert (numba_out[:, valve.O_SUBSTEPS] == 1).all()  # the C kernel takes no sub-steps
    assert (numba_out[:, valve.O_BOUNCE_COUNT] > 0).any()
    assert (numba_out[:, valve.O_JUMP_DURATION] > 0).any()
    assert (numba_out[:, valve.O_JUMP_DURATION] == 0).any()
    for kernel in ("valve_lanes", "valve_one_case"):
        c_out = np.empty_like(numba_out)
        c_valve.valve_response_c(library, kernel, table, step, start, rows, c_out)
        np.testing.assert_array_equal(c_out[:, COUNTS], numba_out[:, COUNTS])
        np.testing.assert_allclose(
            c_out[:, CONTINUOUS], numba_out[:, CONTINUOUS], rtol=1e-9, atol=1e-12
        )


def test_a_source_the_compiler_rejects_fails_instead_of_skipping(monkeypatch, tmp_path):
    # Only a missing compiler skips the comparison above; a compiler that rejects the source
    # (or its flags) is an error, so a broken C reference cannot pass as a skip.
    broken = tmp_path / "valve_lanes.c"
    broken.write_text("this is not C\n", encoding="utf-8")
    monkeypatch.setattr(c_valve, "SOURCE", broken)
    with pytest.raises(c_valve.CompileFailed, match=r"valve_lanes\.c"):
        c_valve.build(np.dtype(np.float64))


def test_missing_compiler_is_reported(monkeypatch):
    monkeypatch.setenv("CC", "no-such-compiler-here")
    with pytest.raises(c_valve.CompilerMissing, match="no-such-compiler-here"):
        c_valve.build(np.dtype(np.float64))


def test_the_cache_folder_is_private_to_this_user(monkeypatch, tmp_path):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))
    folder = c_valve.cache_folder()
    assert folder == tmp_path / "cache" / "engine_studies"
    assert folder.stat().st_mode & 0o777 == 0o700
    assert folder.stat().st_uid == os.getuid()


def test_the_library_is_built_in_the_private_cache_folder(library):
    assert Path(library._name).parent == c_valve.cache_folder()


def test_a_cache_folder_others_can_write_is_refused(monkeypatch, tmp_path):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    (tmp_path / "engine_studies").mkdir(mode=0o777)
    (tmp_path / "engine_studies").chmod(0o777)  # mkdir's mode is cut by the umask
    with pytest.raises(c_valve.UnsafeCacheFolder, match=r"writable by other users \(mode 777\)"):
        c_valve.cache_folder()


def test_a_cache_folder_that_is_a_link_is_refused(monkeypatch, tmp_path):
    (tmp_path / "elsewhere").mkdir(mode=0o700)
    (tmp_path / "engine_studies").symlink_to(tmp_path / "elsewhere")
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    with pytest.raises(c_valve.UnsafeCacheFolder, match="is not a folder of this user"):
        c_valve.cache_folder()


def test_a_library_another_user_owns_is_not_loaded(monkeypatch, tmp_path):
    """Issue 25: a .so another user put in the private folder would run as this user."""
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    planted = c_valve.cache_folder() / "valve_c_0123456789abcdef.so"
    planted.write_bytes(b"\x7fELF")
    try:
        os.chown(planted, os.getuid() + 1, -1)
    except PermissionError:
        pytest.skip("only root can give a file to another user")
    with pytest.raises(c_valve.UnsafeCacheFolder, match="is not a file of this user"):
        c_valve._check_owned(planted)


def test_a_library_others_can_write_is_not_loaded(monkeypatch, tmp_path):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    planted = c_valve.cache_folder() / "valve_c_0123456789abcdef.so"
    planted.write_bytes(b"\x7fELF")
    planted.chmod(0o666)
    with pytest.raises(c_valve.UnsafeCacheFolder, match=r"writable by other users \(mode 666\)"):
        c_valve._check_owned(planted)
