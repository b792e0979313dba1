"""Commands that need no scene import no Numba and no xarray (issue #29 item 5, #28 item 5):
``--help`` and the registry commands start in a fraction of the time of a study run. Checked in
a fresh interpreter through ``sys.modules``, the only honest witness of what was imported."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

HEAVY = ("numba", "xarray", "matplotlib", "scipy", "pandas", "netCDF4")
PROBE = """
import contextlib, io, sys
from studies.cli import main
with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
    try:
        main(sys.argv[1:])
    except SystemExit:  # argparse ends --help and usage errors this way: not what is measured
        pass
print(" ".join(m for m in {heavy!r} if m in sys.modules))
"""


@pytest.mark.parametrize(
    "argv",
    [["--help"], ["runs"], ["show", "nothing"], ["tag", "nothing", "keep"], ["trash"]],
    ids=["--help", "runs", "show", "tag", "trash"],
)
def test_a_command_that_needs_no_scene_imports_no_numba(argv: list[str], tmp_path: Path) -> None:
    outputs = ["--outputs", str(tmp_path / "outputs")] if argv != ["--help"] else []
    probe = PROBE.format(heavy=HEAVY)
    done = subprocess.run(
        [sys.executable, "-c", probe, *argv, *outputs],
        capture_output=True,
        text=True,
        check=True,
        timeout=120,
    )
    assert done.stdout.strip() == "", f"{argv} imported {done.stdout.strip()}"


def test_every_built_in_scene_is_found_under_its_own_name() -> None:
    from studies.scenes import BUILT_IN

    assert {name: BUILT_IN[name].name for name in BUILT_IN} == {name: name for name in BUILT_IN}


@pytest.mark.parametrize(
    "study",
    ["isac_l9", "ohc125_dynamics", "crank_lambda_sweep", "reed_resonance", "luffing_sizing"],
)
def test_check_imports_no_xarray_pandas_or_matplotlib(study: str) -> None:
    # check needs the scene's kernels (numba, which loads scipy's BLAS) and nothing that only
    # results, analysis and figures use: their import was most of a check's start-up.
    probe = PROBE.format(heavy=("xarray", "pandas", "matplotlib", "netCDF4"))
    done = subprocess.run(
        [sys.executable, "-c", probe, "check", study],
        capture_output=True,
        text=True,
        check=True,
        timeout=120,
    )
    assert done.stdout.strip() == "", f"check {study} imported {done.stdout.strip()}"


def test_the_figure_server_starts_before_anything_heavy_is_imported() -> None:
    # run and analyze start the figure server first so that it imports matplotlib while the
    # study computes; a heavy import on the way to it (xarray through the results module
    # held it back 0.5 s) delays every figure.
    probe = f"import sys\nimport studies.report.figure_pool\nprint(*(m for m in {HEAVY!r} if m in sys.modules))"
    done = subprocess.run(
        [sys.executable, "-c", probe],
        capture_output=True,
        text=True,
        check=True,
        timeout=120,
    )
    assert done.stdout.strip() == "", f"figure_pool imported {done.stdout.strip()}"


FULL_OUTPUT = """
import runpy, sys

class Full:  # takes every write, fails at the flush: output redirected to a full disk
    def write(self, text):
        return len(text)

    def flush(self):
        raise OSError(28, "No space left on device")

sys.stdout = Full()
sys.argv = ["studies", "scenes", "cam"]
runpy.run_module("studies", run_name="__main__")
"""


def test_output_lost_at_the_final_flush_is_one_line_and_a_failure() -> None:
    """The process ends without the interpreter's teardown (studies/__main__.py), so the last
    flush of the output is the command's own: a full disk there is reported, not exit 0."""
    done = subprocess.run(
        [sys.executable, "-c", FULL_OUTPUT],
        check=False,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert done.returncode == 4, done.stderr
    assert done.stderr.splitlines() == [
        "error: the output could not be written: [Errno 28] No space left on device"
    ]
