"""report.md, the S/N and interaction figures, and what a run writes for orthogonal-array studies.

Datasets are built as :mod:`studies.run.results` lays them out, with synthetic responses, so the
report is checked without running kernels. Expected best levels come from numpy level means
(direct computation); figure data from numpy cell means and the S/N definition; the study
structure from the shipped TOML files read with tomllib.
"""

from __future__ import annotations

import json
import re
import tomllib
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from results_datasets import CATALOG, l27_dataset, study_dataset
from studies.analysis.analyze import analyze
from studies.define import designs
from studies.report.markdown_report import report_text, write_report
from studies.report.plots import interaction_figure, sn_figure
from studies.report.write import write_analysis

PNG = b"\x89PNG\r\n\x1a\n"


def oa_studies() -> list[Path]:
    """Shipped studies whose design is an orthogonal array (or auto), without [noise] (the
    noise study ohc125_robust runs end to end in test_check_then_run; its statistics are
    checked in test_noise)."""
    out = []
    for path in sorted(CATALOG.glob("*.toml")):
        study = tomllib.loads(path.read_text(encoding="utf-8"))
        kind = study.get("design", {}).get("type", "")
        if kind not in ("full_factorial", "sweep", "") and "noise" not in study:
            out.append(path)
    return out


def links(text: str) -> list[str]:
    return re.findall(r"!\[[^\]]*\]\(([^)]+)\)", text)


def tables_are_well_formed(text: str) -> None:
    """Every Markdown table row has as many cells as its header."""
    block: list[str] = []
    for line in [*text.splitlines(), ""]:
        if line.startswith("|"):
            block.append(line)
            continue
        if block:
            widths = {len(re.split(r"(?<!\\)\|", row)) for row in block}
            assert len(widths) == 1, block
            assert set(block[1]) <= set("|-"), block[1]
        block = []


def section(text: str, title: str) -> str:
    start = text.index(title)
    end = text.find("\n## ", start + len(title))
    return text[start : end if end > 0 else None]


def test_there_is_a_shipped_orthogonal_array_study() -> None:
    assert "isac_l9" in [p.stem for p in oa_studies()]


@pytest.mark.parametrize("path", oa_studies(), ids=lambda p: p.stem)
def test_write_analysis_writes_report_and_every_figure(path: Path, tmp_path: Path) -> None:
    ds = study_dataset(path)
    responses = json.loads(ds.attrs["responses"])
    files = write_analysis(ds, tmp_path)
    names = {f.name for f in files}
    assert files[0].name == "analysis.txt"
    assert {"report.md", "confirmation.toml"} <= names
    for r in responses:
        assert {f"main_effects_{r}.png", f"sn_{r}.png"} <= names
    for f in files:
        if f.suffix == ".png":
            assert f.read_bytes().startswith(PNG)
    text = (tmp_path / "report.md").read_text(encoding="utf-8")
    shown = links(text)
    assert sorted(shown) == sorted(n for n in names if n.endswith(".png"))
    assert all((tmp_path / n).exists() for n in shown)
    tables_are_well_formed(text)
    for title in ["## Design", "## Runs", "### ANOVA", "### Predicted optimum",
                  "## Confirmation run"]:  # fmt: skip
        assert title in text, title
    # Best levels of each response, from numpy level means (smaller is better).
    factors = json.loads(ds.attrs["factors"])
    for r in responses:
        block = section(text, f"## {r}:")
        optimum = block[block.index("### Predicted optimum") :]
        y = ds[r].values
        for f in factors:
            lv = ds[f"{f}_level"].values
            best = int(np.argmin([y[lv == v].mean() for v in np.unique(lv)]))
            value = ds[f].values[lv == best][0]
            assert f"| {f} | {best + 1} | {value:g}" in optimum, (r, f)
    study = tomllib.loads((tmp_path / "confirmation.toml").read_text(encoding="utf-8"))
    assert study["design"] == {"type": "full_factorial"}
    assert set(study["factors"]) == set(factors)
    assert all(len(v["levels"]) == 1 for v in study["factors"].values())


def test_report_shows_interactions_dummy_levels_and_their_figures(tmp_path: Path) -> None:
    ds = l27_dataset()
    files = write_analysis(ds, tmp_path, ["force"])
    names = {f.name for f in files}
    assert "interaction_force_A_x_B.png" in names
    assert "confirmation.toml" not in names  # no study text to build a runnable study from
    text = (tmp_path / "report.md").read_text(encoding="utf-8")
    tables_are_well_formed(text)
    design = section(text, "## Design")
    assert "| 3 | 3 | A_x_B | interaction A x B |" in design
    assert "| 4 | 3 | A_x_B_2 | interaction A x B |" in design
    assert "E | factor, dummy level (column level → factor level: 3 → 1)" in design
    assert "### Interactions" in text
    assert "![A x B](interaction_force_A_x_B.png)" in text
    # The two-way table holds the cell means (numpy).
    y, a, b = ds["force"].values, ds["A_level"].values, ds["B_level"].values
    assert f"| 30 mm | {y[(a == 2) & (b == 0)].mean():.4g} |" in text
    analysis_txt = (tmp_path / "analysis.txt").read_text(encoding="utf-8")
    assert "A_x_B_2" in analysis_txt  # interaction columns are ANOVA terms there too


def test_report_of_a_replicated_response_uses_run_means() -> None:
    ds = l27_dataset(replicates=3)
    text = report_text(ds, analyze(ds, ["force"]), ["force"])
    tables_are_well_formed(text)
    assert "over 3 observation(s) per run" in text
    assert "force (mean over replicates)" in text
    means = ds["force"].values.mean(axis=1)
    assert f"| {means[0]:.4g} |" in section(text, "## Runs")


@pytest.mark.parametrize(
    ("array", "factors", "empty", "left"),
    [("L9", "ABC", 2, 0), ("L18", "ABCDEF", 4, 2)],  # L18: 17 dof, columns 1 + 7 x 2 = 15
)
def test_the_error_row_says_where_its_dof_come_from(
    array: str, factors: str, empty: int, left: int, tmp_path: Path
) -> None:
    # Counted by hand: the empty columns' dof are (levels - 1) each; what the array's columns
    # leave is runs - 1 - Σ columns' dof (an L18's first two columns interact in 2 dof).
    counts = {f: 2 if (array == "L18" and f == "A") else 3 for f in factors}
    levels = "".join(
        f"[factors.{f}]\nlevels = {[10.0 * (i + 1) for i in range(n)]}\n" for f, n in counts.items()
    )
    study = tmp_path / "s.toml"
    study.write_text(
        f'name = "s"\nscene = "cam"\nresponses = ["y"]\n[design]\ntype = "{array}"\n{levels}',
        encoding="utf-8",
    )
    ds = study_dataset(study)
    an = analyze(ds, ["y"])
    text = report_text(ds, an, ["y"])
    assert int(an.dof.sel(response="y", source="error")) == empty + left
    expected = f"Error from the empty column(s) {', '.join(json.loads(ds.attrs['error_columns']))}"
    expected += f" ({empty} dof)" + (
        f" and the {left} dof the array's columns leave" if left else ""
    )
    assert expected + ". " in text


def test_an_sn_without_a_finite_value_is_left_out_and_a_flag_beyond_0_1_is_said() -> None:
    # max_jerk made negative in every run with larger is better: its larger-the-better S/N is
    # -inf in every run (defined for y > 0 only), which stopped the whole analysis with "no
    # finite value"; it is left out. max_contact_stress made a pass/fail flag (1 in 7 of 9
    # runs): by hand the additive prediction at the best levels exceeds 1 (grand mean 7/9 plus
    # two effects of 2/9), which the report must not state as a pass rate.
    ds = study_dataset(CATALOG / "isac_l9.toml", seed=3)
    ds["max_jerk"] = -ds["max_jerk"] - 1.0
    ds["max_jerk"].attrs["better"] = "larger"
    flag = np.ones(9)
    flag[[0, 1]] = 0.0
    ds["max_contact_stress"] = ("run", flag, {"flag_values": [-1, 0, 1],
                                              "flag_meanings": "not_evaluated fails passes",
                                              "better": "larger", "units": "1"})  # fmt: skip
    responses = ["max_jerk", "max_contact_stress"]
    an = analyze(ds, responses)
    assert "max_jerk_sn" not in json.loads(an.attrs["analysed"])
    text = report_text(ds, an, responses)
    predicted = float(an.predicted.sel(response="max_contact_stress"))
    assert predicted > 1.0
    assert "lies outside the flag's range 0 (fail) … 1 (pass)" in text
    assert "max_jerk is ≤ 0 in every run" in text


def test_a_smaller_is_better_response_below_zero_gets_no_sn_and_the_report_says_why() -> None:
    # max_jerk shifted to take negative values in some runs: its smaller-the-better S/N (the
    # distance from 0) would rate -y as y, so the analysis leaves it out and the report says so.
    ds = study_dataset(CATALOG / "isac_l9.toml", seed=3)
    ds["max_jerk"] = ds["max_jerk"] - float(ds["max_jerk"].median())
    an = analyze(ds, ["max_jerk"])
    assert "max_jerk_sn" not in json.loads(an.attrs["analysed"])
    text = report_text(ds, an, ["max_jerk"])
    assert "No S/N ratio: the smaller-the-better S/N measures the distance from 0" in text


def test_several_responses_get_a_tradeoff_summary() -> None:
    ds = study_dataset(CATALOG / "isac_l9.toml", seed=3)
    responses = json.loads(ds.attrs["responses"])
    text = report_text(ds, analyze(ds, responses), responses)
    block = section(text, "## Trade-off summary")
    tables_are_well_formed(block)
    for f in json.loads(ds.attrs["factors"]):
        assert f"| {f} |" in block


def test_sweep_report(tmp_path: Path) -> None:
    design = designs.sweep({"a": 3, "b": 2}, {"a": 1, "b": 0})
    coords = {
        "a": ("run", np.array([1.0, 2.0, 3.0])[design.levels["a"]], {"units": "mm"}),
        "b": ("run", np.array([5.0, 6.0])[design.levels["b"]], {"units": "deg"}),
        "swept_factor": ("run", design.labels["swept_factor"]),
    }
    y = np.array([1.0, 2.0, 3.0, 4.0])
    ds = xr.Dataset({"y": ("run", y, {"units": "MPa"})}, coords=coords)
    ds.attrs = {"design": "sweep", "factors": json.dumps(["a", "b"]), "responses": '["y"]'}
    files = write_analysis(ds, tmp_path)
    text = (tmp_path / "report.md").read_text(encoding="utf-8")
    tables_are_well_formed(text)
    assert "### a" in text
    assert "| a [mm] | y [MPa] |" in text
    assert links(text) == ["sweep_y.png"]
    assert {f.name for f in files} >= {"analysis.txt", "report.md", "sweep_y.png"}


def test_write_report_links_only_existing_figures(tmp_path: Path) -> None:
    ds = study_dataset(CATALOG / "isac_l9.toml")
    an = analyze(ds, ["max_jerk"])
    paths = write_report(ds, an, tmp_path, ["max_jerk"], [tmp_path / "main_effects_max_jerk.png"])
    assert [p.name for p in paths] == ["report.md", "confirmation.toml"]
    assert links(paths[0].read_text(encoding="utf-8")) == ["main_effects_max_jerk.png"]


def test_interaction_figure_plots_cell_means_with_units() -> None:
    ds = l27_dataset()
    ax = interaction_figure(analyze(ds, ["force"]), "force", "A", "B").axes[0]
    assert ax.get_xlabel() == "A [mm]"
    assert ax.get_ylabel() == "force [N]"
    lines = ax.get_lines()
    assert [line.get_label() for line in lines] == ["B = 10 deg", "B = 20 deg", "B = 30 deg"]
    y, a, b = ds["force"].values, ds["A_level"].values, ds["B_level"].values
    for j, line in enumerate(lines):
        np.testing.assert_allclose(line.get_xdata(), [10.0, 20.0, 30.0])
        expected = [y[(a == i) & (b == j)].mean() for i in range(3)]
        np.testing.assert_allclose(line.get_ydata(), expected, rtol=1e-12)
    text_levels = l27_dataset(pair=("C", "A"))
    ax_c = interaction_figure(analyze(text_levels, ["force"]), "force", "C", "A").axes[0]
    assert ax_c.get_xlabel() == "C"  # text levels: their names at level numbers
    np.testing.assert_allclose(ax_c.get_lines()[0].get_xdata(), [1, 2, 3])
    assert [t.get_text() for t in ax_c.get_xticklabels()] == ["lin", "sin", "cyc"]


def test_sn_figure_plots_level_means_of_the_sn_ratio() -> None:
    ds = l27_dataset(replicates=3)
    fig = sn_figure(analyze(ds, ["force"]), "force")
    ax = fig.axes[0]
    assert ax.get_ylabel() == "S/N ratio [dB]"
    assert "smaller is better" in fig.get_suptitle()
    y = ds["force"].values
    sn = -10 * np.log10((y**2).mean(axis=1))  # smaller-is-better definition
    a = ds["A_level"].values
    np.testing.assert_allclose(
        ax.get_lines()[0].get_ydata(), [sn[a == i].mean() for i in range(3)], rtol=1e-12
    )


def test_analyze_command_writes_report_and_figures(tmp_path: Path) -> None:
    from studies.cli import main

    ds = study_dataset(CATALOG / "isac_l9.toml")
    path = tmp_path / "results.nc"
    ds.to_netcdf(path, engine="netcdf4")
    assert main(["analyze", str(path), "--to", str(tmp_path / "analysis")]) == 0
    names = {p.name for p in (tmp_path / "analysis").iterdir()}
    assert {"analysis.txt", "report.md", "confirmation.toml"} <= names
    for r in json.loads(ds.attrs["responses"]):
        assert {f"main_effects_{r}.png", f"sn_{r}.png"} <= names


def test_full_factorial_report_shows_the_observed_run_and_no_sn(tmp_path: Path) -> None:
    design = designs.full_factorial({"a": 3, "b": 2})
    a, b = design.levels["a"], design.levels["b"]
    coords = {
        "a": ("run", np.array([1.0, 2.0, 3.0])[a], {"units": "mm"}),
        "a_level": ("run", a),
        "b": ("run", np.array([5.0, 6.0])[b], {"units": "deg"}),
        "b_level": ("run", b),
    }
    y = (a + 1.0) * (b + 2.0)  # smallest at a = 0, b = 0: run 1, value 2
    flat = np.full(6, 7.0)
    ds = xr.Dataset(
        {"y": ("run", y, {"units": "MPa", "better": "smaller"}),
         "flat": ("run", flat, {"units": "N", "better": "smaller"})},
        coords=coords,
    )  # fmt: skip
    ds.attrs = {"design": "full_factorial", "factors": '["a", "b"]', "responses": '["y", "flat"]'}
    files = write_analysis(ds, tmp_path)
    assert not [f for f in files if f.name.startswith("sn_")]  # one deterministic run each
    text = (tmp_path / "report.md").read_text(encoding="utf-8")
    tables_are_well_formed(text)
    # The best computed point, not a model prediction: run 1 holds y = 2 MPa (the grid's min).
    assert "Best y: **2 MPa** in run 1" in text
    assert "confidence interval" not in text
    assert "## Confirmation run" not in text
    assert "### Signal-to-noise ratio" not in text
    assert "Does not vary over the runs (7 N in every run with a value)" in text
    assert "## Trade-off summary" not in text  # only one response varies


def test_a_run_number_in_the_report_is_the_header_s_index_into_results() -> None:
    # The header says run k is index k - 1 of results.nc's run; the best run named in the text
    # must then hold the smallest value there (numpy's argmin over a random response).
    design = designs.full_factorial({"a": 4, "b": 3})
    a, b = design.levels["a"], design.levels["b"]
    y = np.random.default_rng(20261210).permutation(12) + 1.0
    coords = {
        "a": ("run", a * 1.0),
        "a_level": ("run", a),
        "b": ("run", b * 1.0),
        "b_level": ("run", b),
    }
    ds = xr.Dataset({"y": ("run", y, {"units": "MPa", "better": "smaller"})}, coords=coords)
    ds.attrs = {"design": "full_factorial", "factors": '["a", "b"]', "responses": '["y"]'}
    text = report_text(ds, analyze(ds, ["y"]), ["y"])
    assert "numbered from 1 here (run k is index k − 1 of `run` in results.nc)" in text
    named = int(re.search(r"Best y: \*\*1 MPa\*\* in run (\d+)", text).group(1))
    assert named - 1 == int(np.argmin(y))


@pytest.mark.parametrize("design", ["L9", "sweep"])
def test_response_nan_in_every_run_is_reported_not_fatal(design: str, tmp_path: Path) -> None:
    # No design point separating leaves jump_start NaN everywhere: a result to state, while
    # the other responses are analysed as usual.
    if design == "sweep":
        levels = designs.sweep({"a": 3}, {"a": 1}).levels["a"]
        coords = {
            "a": ("run", np.array([1.0, 2.0, 3.0])[levels], {"units": "mm"}),
            "a_level": ("run", levels),
            "swept_factor": ("run", ["a"] * levels.size),
        }
        ds = xr.Dataset({"y": ("run", levels * 2.0, {"units": "MPa"})}, coords=coords)
        ds.attrs = {"design": "sweep", "factors": json.dumps(["a"])}
    else:
        ds = study_dataset(CATALOG / "isac_l9.toml")
    long_name = "cam angle where separation first starts (NaN: none)"
    ds["jump_start"] = ("run", np.full(ds.sizes["run"], np.nan), {"long_name": long_name})
    analysed = [str(r) for r in ds.data_vars if r != "jump_start"]
    ds.attrs["responses"] = json.dumps([*analysed, "jump_start"])
    files = write_analysis(ds, tmp_path)
    text = (tmp_path / "analysis.txt").read_text(encoding="utf-8")
    assert f"jump_start ({long_name}): NaN in every design point" in text
    assert all(r in text for r in analysed)
    assert not any("jump_start" in f.name for f in files)
    report = (tmp_path / "report.md").read_text(encoding="utf-8")
    assert "NaN in every design point: not analysed" in report


def test_a_figure_that_fails_costs_that_figure_only_and_each_phase_is_timed(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """analysis.nc is written before the figures and does not depend on them; a figure kind
    that fails to draw is left out of the report with one line saying why, the others are
    drawn; the seconds of the analysis, the figures and the texts are reported apart."""
    from studies.report import plots

    ds = study_dataset(CATALOG / "isac_l9.toml")
    timings: dict[str, float] = {}
    complete = {p.name for p in write_analysis(ds, tmp_path / "ok", timings=timings)}
    assert set(timings) == {"analysis_s", "figures_s", "report_s"}
    assert all(t > 0 for t in timings.values())

    def broken(*args: object, **kwargs: object) -> list[Path]:
        raise RuntimeError("no display")

    monkeypatch.setattr(plots, "save_main_effects", broken)
    problems: list[str] = []
    written = {p.name for p in write_analysis(ds, tmp_path / "broken", problems=problems)}
    assert problems == ["broken drew nothing: RuntimeError: no display"]
    main_effects = {n for n in complete if n.startswith("main_effects_")}
    assert main_effects  # the complete run drew them
    assert written == complete - main_effects
    report = (tmp_path / "broken" / "report.md").read_text(encoding="utf-8")
    assert "main_effects_" not in report
    assert "sn_" in report  # the other figures are still drawn and embedded
    saved = xr.open_dataset(tmp_path / "broken" / "analysis.nc")
    expected = xr.open_dataset(tmp_path / "ok" / "analysis.nc")
    xr.testing.assert_identical(saved, expected)


def test_the_error_row_counts_only_the_runs_with_a_value(tmp_path: Path) -> None:
    # An audit: with runs left out (no value) the note still counted the empty column's
    # nominal dof ("e4 (2 dof)") where the table, like statsmodels, had 1 from a pooled term.
    # Expected: statsmodels' residual dof of the same terms over the runs that have a value.
    import pandas as pd
    from statsmodels.formula.api import ols

    study = tmp_path / "s.toml"
    levels = "".join(f"[factors.{f}]\nlevels = [10.0, 20.0, 30.0]\n" for f in "ABC")
    study.write_text(
        f'name = "s"\nscene = "cam"\nresponses = ["y"]\n[design]\ntype = "L9"\n{levels}',
        encoding="utf-8",
    )
    ds = study_dataset(study)
    codes = {f: ds[f"{f}_level"].values for f in ("A", "B", "C", "e4")}
    y = codes["A"] + 2.0 * codes["B"] + 3.0 * codes["C"] + 0.1 * codes["e4"]
    ds["y"].values[:] = np.where(np.arange(9) == 0, np.nan, y)  # run 1 has no value
    ds["y"].attrs["better"] = "smaller"  # level 1 of every factor is best; run 1 is there
    an = analyze(ds, ["y"])
    text = report_text(ds, an, ["y"])
    kept = ds.isel(run=slice(1, None))
    frame = {f"x{f}": kept[f"{f}_level"].values for f in "ABC"} | {"y": kept["y"].values}
    residual = int(ols("y ~ C(xA) + C(xB) + C(xC)", pd.DataFrame(frame)).fit().df_resid)
    assert residual == int(an.dof.sel(response="y", source="error")) == 1
    assert f"Error from the {residual} dof the terms leave over the 8 runs with a value. " in text
    assert "e4 (2 dof)" not in text
    assert "C at level 1 (runs 6, 8)" in text  # the runs with a value its effect rests on
