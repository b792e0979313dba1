"""The command line documents scenes, lists and checks studies."""

from __future__ import annotations

import pytest

from studies.cli import main
from studies.scenes import SCENES, get_scene


def test_scenes_documents_every_name_with_units(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["scenes"]) == 0
    out = capsys.readouterr().out
    for name in SCENES:
        scene = get_scene(name)
        assert f"scene {name}:" in out
        for item in (*scene.parameters, *scene.settings, *scene.responses, *scene.curves):
            assert item.name in out
    assert "base_radius                  mm" in out


def test_list_shows_the_catalogue(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["list"]) == 0
    out = capsys.readouterr().out
    assert "isac_l9" in out
    assert "isac_sweep" in out


def test_check_reports_design_and_stages(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["check", "isac_l9"]) == 0
    assert "9 runs, stages kinematics, geometry, loads" in capsys.readouterr().out


def test_unknown_study_is_exit_code_2(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["check", "no_such_study"]) == 2
    assert "no study named 'no_such_study'" in capsys.readouterr().err


def test_bench_summary_lines() -> None:
    from studies.bench.benchmarks import summarize

    figures = {
        "kernel": {"window_lanes": {"cases": 10, "seconds": 0.5, "cases_per_s": 20.0}},
        "scene_lanes_over_one_case": 3.14159,
        "c_reference": "skipped: no compiler",
    }
    lines = summarize(figures)
    assert lines[0] == "  kernel:"
    assert lines[1].split() == ["window_lanes", "20.0", "cases/s"]
    assert lines[2].split() == ["scene_lanes_over_one_case", "3.14", "×"]
    assert lines[3].split()[0] == "c_reference"
    assert lines[3].endswith("skipped: no compiler")


def test_bench_figure_has_one_bar_per_timing(tmp_path) -> None:
    from studies.bench.plots import save_bench_figure, source, timings

    figures = {
        "kernel": {
            "window_lanes": {"cases_per_s": 9.0e5},
            "window_c_lanes": {"cases_per_s": 7.0e5},
            "window_lanes_over_c_lanes": 1.3,
        },
        "scipy_dop853_rtol_1e-10": {"cases_per_s": 3.5},
    }
    rows = timings(figures)
    assert rows == [
        ("kernel: window_lanes", 9.0e5),
        ("kernel: window_c_lanes", 7.0e5),
        ("scipy_dop853_rtol_1e-10", 3.5),
    ]
    assert [source(name) for name, _ in rows] == [
        "Numba kernels and study engine",
        "C reference (studies/reference)",
        "scipy reference",
    ]
    path = save_bench_figure("test", figures, tmp_path / "bench.png")
    assert path is not None
    assert path.stat().st_size > 1000
    assert save_bench_figure("empty", {"c_reference": "skipped"}, tmp_path / "none.png") is None


def test_the_noise_bench_study_computes_a_million_cases_with_noise_on_every_design_point() -> None:
    from studies.bench.study import NOISE, NOISE_CASES, noise_study_text
    from studies.define.plan import plan_text

    plan = plan_text(noise_study_text(10**6))
    assert plan.cases == 16 * 4 * 4 * 4 * NOISE_CASES == 1_048_576
    assert plan.noise_cases == NOISE_CASES
    assert set(plan.noise_values) == set(NOISE)
    factors = {f.name for f in plan.definition.factors}
    for name, half_width in NOISE.items():  # relative uniform tolerances about each nominal
        nominal = plan.factor_values(name)[:, None] if name in factors else 0.04252  # kg
        ratio = plan.noise_values[name] / nominal
        assert 1 - half_width / 100 <= ratio.min() < ratio.max() <= 1 + half_width / 100


def test_bench_study_runs_the_valve_study_end_to_end() -> None:
    from studies.bench.study import bench_study, level_counts

    assert level_counts(10**6) == (40, 25, 25, 40)
    assert level_counts(10**7) == (100, 40, 50, 50)
    figures = bench_study(16, 0.5, 1)
    assert figures["points"] == figures["results_nc_cases"] == 16
    assert figures["end_to_end"]["seconds"] > figures["compute"]["seconds"] > 0
    assert figures["wall_over_compute"] > 1
    assert figures["peak_rss_mb"] > 0
