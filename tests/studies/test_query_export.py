"""runs filters (--where, --json, --csv), export to CSV/Parquet and MLflow, report.html."""

from __future__ import annotations

import base64
import csv
import io
import json
import math
from html.parser import HTMLParser
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import xarray as xr

from studies.cli import main
from studies.pipeline import run_study
from studies.scenes import get_scene
from study_text import CAM_NOISE

STUDY = """
name = "speeds"
scene = "cam"
responses = ["max_jerk", "min_radius_of_curvature"]
design = "full_factorial"
[settings]
angle_step = {step}
[factors.base_radius]
levels = [16.0, 18.0]
units = "mm"
[factors.cam_speed]
levels = {speeds}
units = "rpm"
"""


@pytest.fixture(scope="module")
def recorded(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, str, str]:
    """Two runs: slow speeds (1000, 2000 rpm) and fast ones (4000, 6000 rpm)."""
    tmp = tmp_path_factory.mktemp("q")
    outputs = tmp / "out"
    ids = []
    for name, speeds, step in (
        ("slow", "[1000.0, 2000.0]", 0.5),
        ("fast", "[4000.0, 6000.0]", 0.25),
    ):
        path = tmp / f"{name}.toml"
        path.write_text(STUDY.format(speeds=speeds, step=step), encoding="utf-8")
        ids.append(run_study(path, outputs=outputs, progress=False).record.run_id)
    return outputs, ids[0], ids[1]


def runs_out(capsys: pytest.CaptureFixture[str], outputs: Path, *args: str) -> str:
    assert main(["runs", "--outputs", str(outputs), *args]) == 0
    return capsys.readouterr().out


def test_where_filters_on_factors_settings_and_response_summaries(
    recorded, capsys: pytest.CaptureFixture[str]
) -> None:
    outputs, slow, fast = recorded
    assert fast in runs_out(capsys, outputs, "--where", "cam_speed>=5000")
    assert slow not in runs_out(capsys, outputs, "--where", "cam_speed>=5000")
    both = runs_out(capsys, outputs, "--where", "cam_speed>=2000", "--status", "finished")
    assert slow in both
    assert fast in both
    assert slow in runs_out(capsys, outputs, "--where", "angle_step=0.5")
    assert fast not in runs_out(capsys, outputs, "--where", "angle_step=0.5")
    assert "no runs" in runs_out(capsys, outputs, "--where", "cam_speed>6000")
    assert "no runs" in runs_out(capsys, outputs, "--since", "2999-01-01")
    rows = json.loads(runs_out(capsys, outputs, "--json", "--study", "speeds", "--scene", "cam"))
    by_id = {r["run_id"]: r for r in rows}
    # values in SI: rpm → rad/s is × 2π/60, deg → rad × π/180, mm/rad^3 → m/rad^3 × 1e-3
    assert by_id[fast]["factors"]["cam_speed"] == pytest.approx([4000 * RPM, 6000 * RPM])
    assert by_id[fast]["units"]["cam_speed"] == "rad/s"
    assert by_id[fast]["declared_units"]["cam_speed"] == "rpm"
    assert by_id[slow]["settings"]["angle_step"] == pytest.approx(0.5 * math.pi / 180)
    jerk = by_id[fast]["responses"]["max_jerk"]
    assert jerk["units"] == "m/rad^3"
    assert jerk["min"] <= jerk["mean"] <= jerk["max"]
    # the summaries are those of the results file (stored in mm/rad^3)
    with xr.open_dataset(Path(by_id[fast]["folder"]) / "results.nc") as ds:
        stored_max = float(ds["max_jerk"].max())
        assert ds["max_jerk"].attrs["units"] == "mm/rad^3"
    assert jerk["max"] == pytest.approx(stored_max * 1e-3)
    # a bare number is in the scene's units (mm/rad^3), whatever the registry stores
    assert fast in runs_out(capsys, outputs, "--where", f"max_jerk.max<{stored_max * (1 + 1e-9)}")
    assert fast not in runs_out(
        capsys, outputs, "--where", f"max_jerk.max<{stored_max * (1 - 1e-9)}"
    )
    table = list(csv.DictReader(io.StringIO(runs_out(capsys, outputs, "--csv"))))
    assert {r["run_id"] for r in table} == {slow, fast}
    speeds = {r["run_id"]: [float(v) for v in r["cam_speed [rad/s]"].split("|")] for r in table}
    assert speeds[slow] == pytest.approx([1000 * RPM, 2000 * RPM])
    assert "max_jerk.max [m/rad^3]" in table[0]


RPM = 2 * math.pi / 60  # rad/s per rpm


def test_where_takes_units_defaults_and_the_status(
    recorded, capsys: pytest.CaptureFixture[str]
) -> None:
    outputs, slow, fast = recorded
    # 400 rad/s = 3820 rpm: between the slow runs' 2000 and the fast runs' 4000 rpm
    above = runs_out(capsys, outputs, "--where", "cam_speed>=400 rad/s")
    assert fast in above
    assert slow not in above
    assert slow in runs_out(capsys, outputs, "--where", "base_radius==0.016 m")
    assert slow in runs_out(capsys, outputs, "--where", "base_radius==16")  # the scene's mm
    assert "no runs" in runs_out(capsys, outputs, "--where", "base_radius==16 m")
    default = get_scene("cam").parameter("cam_width")
    assert default is not None  # a parameter neither study names: queryable at its default
    at_default = f"cam_width=={default.default} {default.units}"
    assert {slow, fast} <= set(runs_out(capsys, outputs, "--where", at_default).split())
    assert "no runs" in runs_out(capsys, outputs, "--where", f"cam_width!={default.default}")
    finished = runs_out(capsys, outputs, "--where", "status==finished", "--since", "1d")
    assert {slow, fast} <= set(finished.split())
    assert "no runs" in runs_out(capsys, outputs, "--where", "status!=finished")
    # started and finished are ISO times, compared as text (an audit: "started>=2026-12-07"
    # was refused as the number 2026 in the unknown units '-12-07')
    assert {slow, fast} <= set(runs_out(capsys, outputs, "--where", "started>=2000-01-01").split())
    assert "no runs" in runs_out(capsys, outputs, "--where", "finished<2000-01-01")


def test_runs_shows_value_columns_in_the_scenes_units(
    recorded, capsys: pytest.CaptureFixture[str]
) -> None:
    outputs, _, fast = recorded
    out = runs_out(capsys, outputs, "--columns", "cam_speed,angle_step,max_jerk.max")
    head, *lines = out.splitlines()
    assert "cam_speed [rpm]" in head
    assert "angle_step [degree]" in head
    assert "max_jerk.max [mm/rad^3]" in head
    (fast_line,) = [line for line in lines if line.startswith(fast)]
    assert " 4000|6000 " in fast_line
    assert " 0.25 " in fast_line


def test_where_reads_a_number_in_each_runs_units_and_skips_runs_it_cannot_convert_to(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # An audit's case: the cam scene's max_acceleration is in mm/rad^2, the valve scene's in
    # m/s^2, and "max_acceleration.max<5000 m/s^2" listed the cam run, compared in m/rad^2
    outputs = tmp_path / "out"
    highest = {}
    for scene, factor in (("cam", "base_radius"), ("valve", "cam_speed")):
        levels = "[16.0, 18.0]" if scene == "cam" else "[2000.0, 3000.0]"
        path = tmp_path / f"{scene}.toml"
        path.write_text(
            f'name = "{scene}_acc"\nscene = "{scene}"\nresponses = ["max_acceleration"]\n'
            f"[factors.{factor}]\nlevels = {levels}\n",
            encoding="utf-8",
        )
        result = run_study(path, outputs=outputs, progress=False)
        with xr.open_dataset(result.folder / "results.nc") as ds:
            units = ds["max_acceleration"].attrs["units"]
            highest[units] = (result.record.run_id, float(ds["max_acceleration"].max()))
    (cam, cam_max), (valve, valve_max) = highest["mm/rad^2"], highest["m/s^2"]
    assert cam_max < valve_max  # read in either scene's units, a bound between them picks one

    where = f"max_acceleration.max<{valve_max * 1.01} m/s^2"
    assert main(["runs", "--outputs", str(outputs), "--where", where]) == 0
    listed = capsys.readouterr()
    assert valve in listed.out
    assert cam not in listed.out
    assert listed.err == (
        "note: skipped 1 run whose max_acceleration.max is in 'mm/rad^2': 'm/s^2' measures "
        "acceleration\n"
    )
    # a bare number is in each run's own units: above the cam's largest in mm/rad^2, and far
    # below the valve's in m/s^2
    above = runs_out(capsys, outputs, "--where", f"max_acceleration.max>{cam_max * 0.99}")
    assert {cam, valve} <= set(above.split())
    below = runs_out(capsys, outputs, "--where", f"max_acceleration.max<{cam_max * 1.01}")
    assert cam in below
    assert valve not in below
    # --columns over both: each cell in its scene's unit, the header naming none (it named
    # the cam's mm/rad^2 above the valve's value in m/s^2)
    table = runs_out(capsys, outputs, "--columns", "max_acceleration.max").splitlines()
    assert table[0].split()[-2:] == ["max_acceleration.max", "tags"]
    rows = {line.split()[0]: line for line in table[1:]}
    assert rows[cam].split()[-1] == "mm/rad^2"
    assert rows[valve].split()[-1] == "m/s^2"
    assert main(["runs", "--outputs", str(outputs), "--where", "max_acceleration.max<5 N"]) == 2
    assert capsys.readouterr().err.startswith(
        "error: --where max_acceleration.max: 'N' measures force, max_acceleration.max is in "
    )


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--where", "cam_speed>>5"], "cannot read --where"),
        (["--where", "no_such_name>1"], "--where names 'no_such_name'"),
        (["--where", "max_jerk<1"], "filter on max_jerk.min, .mean or .max"),
        (["--since", "last week"], "is not a date or an age"),
        (["--where", "cam_speed>=80 mm"], "'mm' measures length"),
        (["--where", "cam_speed>=80 furlongs"], "unknown units 'furlongs'"),
        (["--where", "status>finished"], "use == or !="),
        (["--where", "max_jerk.max<abc"], "'abc' is not a number (a response's summary"),
        (["--where", "law>cycloidal"], "< <= > >= compare numbers"),
        (["--columns", "no_such_value"], "--columns names 'no_such_value'"),
    ],
)
def test_bad_filters_are_one_line_and_exit_2(
    recorded, args: list[str], message: str, capsys: pytest.CaptureFixture[str]
) -> None:
    outputs, _, _ = recorded
    assert main(["runs", "--outputs", str(outputs), *args]) == 2
    err = capsys.readouterr().err
    assert message in err
    assert len(err.strip().splitlines()) == 1


@pytest.mark.parametrize("file_format", ["csv", "parquet"])
def test_export_has_every_design_point_with_units(
    recorded, tmp_path: Path, file_format: str
) -> None:
    if file_format == "parquet":
        pytest.importorskip("pyarrow")
    outputs, _, fast = recorded
    to = tmp_path / f"fast.{file_format}"
    argv = ["export", fast, "--format", file_format, "--to", str(to), "--outputs", str(outputs)]
    assert main(argv) == 0
    table = pd.read_csv(to, index_col="run") if file_format == "csv" else pd.read_parquet(to)
    assert sorted(set(table["cam_speed [rpm]"])) == [4000.0, 6000.0]
    assert len(table) == 4
    (folder,) = [p for p in (outputs / "speeds").iterdir() if p.name == fast]
    with xr.open_dataset(folder / "results.nc") as ds:
        assert list(table["max_jerk [mm/rad^3]"]) == pytest.approx(ds["max_jerk"].values.tolist())


def test_export_under_noise_has_a_row_per_design_point_and_noise_case(tmp_path: Path) -> None:
    # An audit's case: a (run, noise) response was left out of the table and written to
    # <name>_curves.csv as a "curve" over the noise cases, without the noise factor's values.
    study = tmp_path / "cam_noise.toml"
    study.write_text(CAM_NOISE.format(cam_speed=1000.0), encoding="utf-8")
    outputs = tmp_path / "out"
    run_id = run_study(study, outputs=outputs, progress=False).record.run_id
    to = tmp_path / "noisy.csv"
    assert main(["export", run_id, "--to", str(to), "--outputs", str(outputs)]) == 0
    assert not (tmp_path / "noisy_curves.csv").exists()
    table = pd.read_csv(to, index_col=["run", "noise"])
    (folder,) = (outputs / "cam_noise").iterdir()
    with xr.open_dataset(folder / "results.nc") as ds:
        runs, cases = ds.sizes["run"], ds.sizes["noise"]
        assert len(table) == runs * cases
        for name in ("max_contact_stress", "max_jerk", "spring_rate_noise"):
            (column,) = [c for c in table.columns if c.split(" [")[0] == name]
            np.testing.assert_array_equal(table[column].to_numpy(), ds[name].values.reshape(-1))
        radius = table["base_radius [mm]"].to_numpy().reshape(runs, cases)
        expected = np.repeat(ds["base_radius"].values[:, None], cases, axis=1)
        np.testing.assert_array_equal(radius, expected)  # each point's value, every case


class _Page(HTMLParser):
    def __init__(self) -> None:
        super().__init__()
        self.images: list[str] = []
        self.outside: list[str] = []
        self.tables = 0

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        found = dict(attrs)
        if tag == "img":
            self.images.append(found.get("src") or "")
        if tag == "table":
            self.tables += 1
        for key in ("src", "href"):
            if found.get(key) and not str(found[key]).startswith("data:"):
                self.outside.append(str(found[key]))


def test_report_html_is_self_contained_with_every_figure(recorded) -> None:
    outputs, slow, _ = recorded
    folder = outputs / "speeds" / slow
    page = _Page()
    page.feed((folder / "report.html").read_text(encoding="utf-8"))
    figures = sorted(folder.glob("*.png"))
    assert figures
    assert len(page.images) == len(figures)
    embedded = {base64.b64decode(src.split(",", 1)[1]) for src in page.images}
    assert embedded == {f.read_bytes() for f in figures}
    assert all(src.startswith("data:image/png;base64,") for src in page.images)
    assert page.outside == []  # nothing loaded from anywhere
    assert page.tables >= 2
    assert 'addEventListener("click"' in (folder / "report.html").read_text(encoding="utf-8")


@pytest.mark.parametrize("file_format", ["csv", "parquet"])
def test_export_writes_the_curves_in_long_format(
    tmp_path: Path, file_format: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    pytest.importorskip("pyarrow")
    from studies.tracking import export

    monkeypatch.setattr(export, "CURVE_CHUNK", 2)  # 3 design points: blocks of 2 and 1
    study = tmp_path / "curved.toml"
    study.write_text(
        STUDY.format(speeds="[1000.0]", step=1.0)
        .replace("16.0, 18.0", "16.0, 18.0, 20.0")
        .replace("[settings]", 'curves = ["lift"]\n[settings]'),
        encoding="utf-8",
    )
    outputs = tmp_path / "out"
    run_id = run_study(study, outputs=outputs, progress=False).record.run_id
    to = tmp_path / f"curved.{file_format}"
    argv = ["export", run_id, "--format", file_format, "--to", str(to), "--outputs", str(outputs)]
    assert main(argv) == 0
    curves = to.with_name(f"curved_curves.{file_format}")
    table = pd.read_csv(curves) if file_format == "csv" else pd.read_parquet(curves)
    (results,) = outputs.glob(f"speeds/{run_id}/results.nc")
    with xr.open_dataset(results) as ds:
        lift, angles = ds["lift"].values, ds["cam_angle"].values
        radii = ds["base_radius"].values
        assert ds["lift"].attrs["units"] == "mm"
    assert len(table) == lift.size  # one row per design point and angle
    assert list(table["lift [mm]"]) == pytest.approx(lift.reshape(-1).tolist())
    assert list(table["cam_angle [degree]"]) == pytest.approx(np.tile(angles, 3).tolist())
    assert list(table["base_radius [mm]"]) == pytest.approx(radii.repeat(angles.size).tolist())
    assert list(table["run"]) == np.arange(3).repeat(angles.size).tolist()
