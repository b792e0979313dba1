"""A HOME that is not a folder (an audit): matplotlib cannot make its configuration folder, and
each process that imports it (the command and its figure worker) said so in two lines: four
lines on stderr for one run. The command line gives them one temporary folder and says so in
one line (studies.common.matplotlib_folder); the run and its figures are as usual."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path


def test_a_home_that_is_not_a_folder_is_one_line_and_the_run_is_whole(tmp_path: Path) -> None:
    temporary = tmp_path / "tmp"
    temporary.mkdir()
    env = {k: v for k, v in os.environ.items() if k not in ("MPLCONFIGDIR", "XDG_CONFIG_HOME")}
    env |= {"HOME": os.devnull, "TMPDIR": str(temporary)}
    done = subprocess.run(
        [sys.executable, "-m", "studies", "run", "isac_l9", "--outputs", str(tmp_path / "out"),
         "--no-progress"],
        capture_output=True, text=True, check=False, env=env, timeout=600,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    (line,) = done.stderr.strip().splitlines()
    assert line.startswith(f"note: matplotlib's folder {os.devnull}/.config/matplotlib ")
    assert "MPLCONFIGDIR" in line
    assert list((tmp_path / "out").glob("isac_l9/*/*.png"))  # figures drawn as usual
    assert not list(temporary.iterdir())  # the temporary folder is gone with the command
