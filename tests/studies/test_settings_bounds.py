"""Settings that scale memory are estimated before anything is allocated (issue 25,
"Unbounded work"): a crank ``angle_step`` of 1e-7° (53.6 GiB measured before a MemoryError)
or 1e-300°, a valve ``tolerance`` of 1e-12 mm (a run killed past 22 GB here) are refused by
``check`` and ``run`` alike, with the memory and time estimates, and nothing is written; a
setting that fits one design point but not a whole chunk makes the chunks smaller."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest

from studies.cli import main
from studies.define import plan as planning
from studies.define.plan import plan_text
from studies.scenes import get_scene
from studies.tracking.store import RunStore

GB = 1e9
CRANK = 'name = "fine"\nscene = "crank"\nresponses = ["max_piston_velocity"]\n'
CRANK += "[factors.engine_speed]\nlevels = [1000.0, 2000.0]\n"
VALVE = 'name = "fine"\nscene = "valve"\nresponses = ["max_lift"]\n'
VALVE += "[factors.cam_speed]\nlevels = [1000.0, 2000.0]\n"


@pytest.mark.parametrize(
    ("study", "setting", "needs"),
    [
        (CRANK, "angle_step = 1e-7", "need about 1.38e+03 GB for a single design point"),
        (CRANK, "angle_step = 1e-300", "need about 1.38e+296 GB for a single design point"),
        (VALVE, "tolerance = 1e-12", "need about 24.2 GB for a single design point"),
    ],
    ids=["crank-1e-7", "crank-1e-300", "valve-1e-12mm"],
)
@pytest.mark.parametrize("command", ["check", "run"])
def test_a_setting_that_cannot_fit_is_refused_with_its_estimate(
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
    study: str,
    setting: str,
    needs: str,
    command: str,
) -> None:
    monkeypatch.setattr(planning, "available_memory", lambda: 22 * GB)
    path = tmp_path / "fine.toml"
    path.write_text(study + f"[settings]\n{setting}\n")
    outputs = tmp_path / "out"
    extra = ["--outputs", str(outputs), "--no-progress"] if command == "run" else []
    assert main([command, str(path), *extra]) == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err
    (problem,) = [line[4:] for line in err.splitlines() if line.startswith("  - ")]
    name, value = setting.split(" = ")
    assert problem.startswith(f"settings {name} = {float(value):g} {needs}")
    assert problem.endswith("22 GB of memory available: use a coarser setting")
    assert " to compute 2 points" in problem
    assert not outputs.exists()


def test_the_estimate_follows_the_grid_in_closed_form() -> None:
    """Crank: 720°/step values per array (1° → 720), 24 + curves float64 arrays per point."""
    scene = get_scene("crank")
    work = scene.work_estimate({"angle_step": math.radians(1.0)}, [], ["torque"])
    assert work.per_point == pytest.approx(720 * 8 * 25)


def test_a_fine_cam_grid_runs_in_smaller_chunks(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """0.002° cam steps: 180 001 angles x 12 arrays x 8 B = 17.3 MB a point; with 0.25 GB
    available (0.2 GB usable) a chunk holds 11 points instead of 2048."""
    monkeypatch.setattr(planning, "available_memory", lambda: 0.25 * GB)
    text = (
        'name = "fine_cam"\nscene = "cam"\nresponses = ["max_jerk"]\n'
        "[settings]\nangle_step = 0.002\n[factors.cam_speed]\n"
        f"levels = [{', '.join(str(1000.0 + i) for i in range(30))}]\n"
    )
    assert plan_text(text).max_chunk == int(0.2 * GB / (180001 * 8 * 12))
    study = tmp_path / "fine_cam.toml"
    study.write_text(text)
    outputs = tmp_path / "out"
    assert main(["run", str(study), "--outputs", str(outputs), "--no-progress"]) == 0
    (row,) = RunStore(outputs).list_runs()
    record = json.loads((Path(row["folder"]) / "run.json").read_text())
    assert record["chunk_size"] == 11
