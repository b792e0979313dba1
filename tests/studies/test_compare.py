"""compare: what differs between runs, from their folders and the registry alone."""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from studies.cli import main
from studies.compare.plots import overlay_figure
from studies.compare.runs import compare, load_run
from studies.compare.tolerances import Tolerance
from studies.define.definition import find_study
from studies.pipeline import run_study
from studies.tracking.store import RunStore
from study_text import CAM_NOISE

CAM = """
name = "cam_grid"
scene = "cam"
responses = ["max_jerk", "min_radius_of_curvature"]
design = "full_factorial"
[factors.base_radius]
levels = {base_radius}
[factors.cam_speed]
levels = [1000.0, 1300.0]
"""


def valve_study(reference_rtol: str) -> str:
    """valve_step_accuracy cut to two design points, with the reference tolerance given."""
    text = find_study("valve_step_accuracy").read_text(encoding="utf-8")
    for old, new in (
        (
            r'levels = \["lanes", "lanes_f32", "rk4", "rk4_switch_aware", "dopri"\]',
            'levels = ["rk4", "lanes"]',
        ),
        (r"levels = \[1.0, 0.5, 0.25, 0.125\]", "levels = [1.0]"),
        (r"levels = \[3500.0, 6000.0\]", "levels = [3500.0]"),
        (r"levels = \[5e4, 2e5\]", "levels = [5e4]"),
        (r"reference_rtol = 1e-10", f"reference_rtol = {reference_rtol}"),
    ):
        text, count = re.subn(old, new, text)
        assert count == 1, old
    return text


def run_text(tmp_path: Path, outputs: Path, name: str, text: str) -> str:
    path = tmp_path / f"{name}.toml"
    path.write_text(text, encoding="utf-8")
    return run_study(path, outputs=outputs, progress=False).record.run_id


@pytest.mark.slow
def test_runs_differing_in_one_setting_name_it_and_the_responses_it_moved(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    outputs = tmp_path / "out"
    a = run_text(tmp_path, outputs, "a", valve_study("1e-10"))
    b = run_text(tmp_path, outputs, "b", valve_study("1e-5"))
    c = compare([load_run(RunStore(outputs), a), load_run(RunStore(outputs), b)])
    assert [(d.kind, d.name, d.values) for d in c.definition] == [
        ("setting", "reference_rtol", ["1e-10", "1e-05"])
    ]
    moved = set(c.moved())
    # the reference moved, so the error against it did; cost_per_case is a wall-clock timing
    assert "reference_error" in moved
    assert moved <= {"reference_error", "cost_per_case"}
    assert {"max_lift", "error_estimate", "step_halving_difference"}.isdisjoint(moved)

    assert main(["compare", a, b, "--outputs", str(outputs)]) == 0
    out = capsys.readouterr().out
    assert re.search(r"setting reference_rtol\s+1e-10 → 1e-05", out)
    assert "reference_error [mm]" in out
    assert "moved: reference_error" in out


def test_different_designs_compare_on_their_common_points(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    outputs = tmp_path / "out"
    a = run_text(tmp_path, outputs, "a", CAM.format(base_radius="[16.0, 18.0, 20.0]"))
    b = run_text(tmp_path, outputs, "b", CAM.format(base_radius="[18.0, 20.0, 22.0, 24.0]"))
    c = compare([load_run(RunStore(outputs), a), load_run(RunStore(outputs), b)])
    assert c.matched_on == ["base_radius", "cam_speed"]
    # common points: base radius 18 and 20 at both speeds; same definition there, same values
    assert {ch.points for ch in c.changes} == {4}
    assert c.moved() == []
    assert [(d.kind, d.name) for d in c.definition] == [("factor", "base_radius")]

    assert (
        main(["compare", a, b, "--plot", "--to", str(tmp_path / "fig"), "--outputs", str(outputs)])
        == 0
    )
    assert sorted(p.name for p in (tmp_path / "fig").iterdir()) == [
        "compare_max_jerk.png",
        "compare_min_radius_of_curvature.png",
    ]
    # the legend names what differs between the runs, not their ids
    legend = overlay_figure(c, "max_jerk").axes[0].get_legend()
    assert [t.get_text() for t in legend.get_texts()] == [
        "base_radius [16, 18, 20] mm",
        "base_radius [18, 20, 22, 24] mm",
    ]
    assert "points" in capsys.readouterr().out


def test_three_runs_name_the_run_whose_code_differs(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # An audit's case: with three runs or more, compare said "source changed" and not whose.
    outputs = tmp_path / "out"
    a, b, c = (
        run_text(tmp_path, outputs, n, CAM.format(base_radius="[16.0, 18.0]")) for n in "abc"
    )
    for run_id, source in ((a, "1" * 64), (b, "2" * 64), (c, "1" * 64)):  # b: edited code
        path = Path(RunStore(outputs).find_run(run_id)["folder"]) / "run.json"
        record = json.loads(path.read_text(encoding="utf-8"))
        record["code"]["engine"]["source_sha256"] = source
        path.write_text(json.dumps(record), encoding="utf-8")
    assert main(["compare", a, b, c, "--outputs", str(outputs)]) == 0
    (line,) = [x for x in capsys.readouterr().out.splitlines() if "code engine" in x]
    assert line.endswith(f"source changed in {b} 22222222 (reference {a} 11111111)")


def test_bad_input_is_one_line_and_exit_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    outputs = tmp_path / "out"
    a = run_text(tmp_path, outputs, "a", CAM.format(base_radius="[16.0, 18.0]"))
    other = CAM.format(base_radius="[30.0, 32.0]")
    b = run_text(tmp_path, outputs, "b", other)
    no_shared = other.replace('["max_jerk", "min_radius_of_curvature"]', '["max_contact_stress"]')
    c = run_text(tmp_path, outputs, "c", no_shared.replace("cam_grid", "cam_stress"))
    cases = {
        ("compare", a, "no_such_tag"): "no run or tag 'no_such_tag'",
        ("compare", a, b): "no design point in common",
        ("compare", a, c): "the runs share no response",
        ("compare", a): "at least two runs",
    }
    for argv, message in cases.items():
        assert main([*argv, "--outputs", str(outputs)]) == 2, argv
        err = capsys.readouterr().err
        assert message in err, (argv, err)
        assert "Traceback" not in err
    assert len(RunStore(outputs).list_runs()) == 3


SPELLED = """
name = "spelled"
scene = "cam"
responses = ["max_jerk", "min_radius_of_curvature", "max_contact_stress"]
design = "full_factorial"
[parameters]
lift = {lift}
[factors.base_radius]
levels = {base_radius}
{units}
[factors.cam_speed]
levels = [1000.0, 1300.0]
"""


def test_runs_differing_only_in_how_units_are_written_are_identical(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    outputs = tmp_path / "out"
    in_mm = SPELLED.format(lift="10.8", base_radius="[16.0, 20.5]", units="")
    in_m = SPELLED.format(
        lift='{value = 0.0108, units = "m"}', base_radius="[0.016, 0.0205]", units='units = "m"'
    )
    a = run_text(tmp_path, outputs, "a", in_mm)
    b = run_text(tmp_path, outputs, "b", in_m)

    def indexed(run_id: str) -> list[tuple]:
        return sorted(tuple(v.values()) for v in RunStore(outputs).run_values(run_id))

    # the registry: every value the same, in SI (lift 10.8 mm = 0.0108 m)
    assert indexed(a) == indexed(b)
    lift = [v for v in RunStore(outputs).run_values(a) if v["name"] == "lift"]
    assert [(v["num"], v["units"], v["declared_units"]) for v in lift] == [(0.0108, "m", "mm")]

    # compare: nothing differs, and no response moved even with zero tolerance
    c = compare(
        [load_run(RunStore(outputs), a), load_run(RunStore(outputs), b)], Tolerance(0.0, 0.0)
    )
    assert (c.definition, c.code, c.versions) == ([], [], [])
    assert c.moved() == []
    assert {ch.points for ch in c.changes} == {4}
    assert main(["compare", a, b, "--rtol", "0", "--outputs", str(outputs)]) == 0
    out = capsys.readouterr().out
    assert "definitions, code and versions: identical" in out
    assert "moved: none" in out

    # regress: within a zero tolerance
    assert main(["regress", a, b, "--rtol", "0", "--outputs", str(outputs)]) == 0
    assert "all within tolerance" in capsys.readouterr().out


def test_noise_runs_compare_regress_and_are_found_by_their_response_summaries(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # was: compare "the runs share no response: …: none", regress "the run has none of the
    # baseline's responses ()" (both exit 2), and runs --where "which no run records"
    outputs = tmp_path / "out"
    a = run_text(tmp_path, outputs, "a", CAM_NOISE.format(cam_speed=1000))
    b = run_text(tmp_path, outputs, "b", CAM_NOISE.format(cam_speed=1500))
    folders = {r["run_id"]: Path(r["folder"]) for r in RunStore(outputs).list_runs()}
    with xr.open_dataset(folders[a] / "results.nc") as ds:
        before = ds["max_contact_stress"].values  # run × noise, the same design in both runs
    with xr.open_dataset(folders[b] / "results.nc") as ds:
        after = ds["max_contact_stress"].values
    assert before.shape == (2, 4)
    rel = np.abs(after - before) / np.abs(before)

    assert main(["compare", a, b, "--outputs", str(outputs)]) == 0
    out = capsys.readouterr().out
    assert "matched on base_radius in SI and the noise case" in out
    # every design point × noise case moved; the largest changes are numpy's
    max_abs, max_rel = re.search(
        r"max_contact_stress \[MPa\] +\S+ +8/8 +(\S+) +(\S+)", out
    ).groups()
    assert float(max_abs) == pytest.approx(np.abs(after - before).max(), rel=5e-4)
    assert float(max_rel) == pytest.approx(rel.max(), rel=5e-3)
    assert "moved: max_contact_stress" in out

    def regress(rtol: float) -> int:
        return main(["regress", a, b, "--rtol", repr(float(rtol)), "--outputs", str(outputs)])

    assert regress(rel.max() * (1 - 1e-6)) == 1
    assert "FAILED: max_contact_stress moved beyond tolerance" in capsys.readouterr().out
    assert regress(rel.max() * (1 + 1e-6)) == 0
    assert "all within tolerance" in capsys.readouterr().out

    # the registry summarises every value: the largest is that of some noise case
    top = float(before.max())
    for where, found in ((f"<{top * (1 + 1e-9)!r}", True), (f"<{top * (1 - 1e-9)!r}", False)):
        assert (
            main(["runs", "--outputs", str(outputs), "--where", f"max_contact_stress.max{where}"])
            == 0
        )
        assert (a in capsys.readouterr().out) is found
