"""The renderers (analysis.txt, report.md, figures) compute no statistics: with the analysis
Dataset computed once, every statistics function is replaced by one that fails, and every
output is still written."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from results_datasets import CATALOG, l27_dataset, study_dataset
from studies.analysis import analyze as analysis
from studies.analysis import prediction, sensitivity, statistics, sums_of_squares, taguchi, tradeoff
from studies.define.plan import plan_text
from studies.report import markdown_report, plots
from studies.report import text as analysis_text
from studies.run.results import build_dataset
from studies.run.runner import evaluate

FACTORIAL = """
name = "factorial"
scene = "cam"
responses = ["max_jerk", "max_contact_stress"]
[factors.base_radius]
levels = [16.0, 18.0, 20.5]
units = "mm"
[factors.cam_speed]
levels = [1000.0, 1300.0, 1600.0]
[factors.seg2_width]
levels = [7.0, 9.0]
"""

STATISTICS = [
    (statistics, "anova"),
    (statistics, "range_analysis"),
    (analysis, "anova"),
    (analysis, "range_analysis"),
    (analysis, "analyze"),
    (taguchi, "anova"),
    (taguchi, "anova_table"),
    (prediction, "predict"),
    (prediction, "predict_optimum"),
    (tradeoff, "predict_optimum"),
    (tradeoff, "tradeoff"),
    (taguchi, "interaction_means"),
    (taguchi, "interaction_anova"),
    (taguchi, "signal_to_noise"),
    (taguchi, "with_sn"),
    (taguchi, "with_means"),
    (sums_of_squares, "term_sums_of_squares"),
    (sensitivity, "decompose"),
]


def factorial_dataset() -> xr.Dataset:
    plan = plan_text(FACTORIAL)
    return build_dataset(plan, evaluate(plan, progress=False), {})


CASES = {
    "L9 with S/N and a trade-off": lambda: study_dataset(CATALOG / "isac_l9.toml", seed=3),
    "L27 with an interaction": l27_dataset,
    "L27 replicated": lambda: l27_dataset(replicates=3),
    "full factorial": factorial_dataset,
}


@pytest.mark.parametrize("make", CASES.values(), ids=CASES.keys())
def test_renderers_read_the_analysis_only(
    make, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    ds = make()
    responses = json.loads(ds.attrs.get("responses", '["force"]'))
    an = analysis.analyze(ds, responses)

    def fails(*args, **kwargs):
        msg = "a renderer computed a statistic"
        raise AssertionError(msg)

    for module, name in STATISTICS:
        monkeypatch.setattr(module, name, fails)
    done = json.loads(an.attrs["analysed"])
    shown = [r for r in responses if r in done or f"{r}_mean" in done]
    texts = [analysis_text.format_tables(an, taguchi.mean_name(ds, r)) for r in shown]
    assert all("ANOVA of" in t for t in texts)
    figures = plots.save_main_effects(an, [taguchi.mean_name(ds, r) for r in shown], tmp_path)
    sn = [r for r in shown if taguchi.sn_name(r) in an["response"].values]
    figures += plots.save_sn_plots(an, sn, tmp_path)
    figures += plots.save_interaction_plots(an, [taguchi.mean_name(ds, r) for r in shown], tmp_path)
    figures += plots.save_maps(an, shown, tmp_path)
    text = markdown_report.report_text(ds, an, responses, [f.name for f in figures])
    assert "## " in text
    assert all(f.stat().st_size > 1000 for f in figures)
    if "first_order" in an:
        assert np.isfinite(an["first_order"].values).any()
        assert "Variance decomposition" in text
