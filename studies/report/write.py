"""What a run writes beside its results: ``analysis.txt``, ``report.md`` and the figures.

The analysis is computed once (:func:`studies.analysis.analyze.analyze`, saved as ``analysis.nc``);
everything else renders it. Orthogonal-array and full-factorial runs get range analysis and
ANOVA per response (interaction columns as terms), main-effect, S/N and interaction plots, and
for full factorials the variance decomposition and a map over the strongest factor pair;
Saltelli designs their Sobol' indices, Sobol' and Latin-hypercube samples moments, quantiles
and correlations; sweeps get a table and a response-vs-factor plot per swept factor. ``report.md``
(:mod:`studies.report.markdown_report`) adds S/N ratios, the optimum and the confirmation (arrays) or
refinement (full factorials) study;
``report.html`` (:mod:`studies.report.html`) is the same report as one self-contained page.
"""

from __future__ import annotations

import json
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import xarray as xr

from studies.analysis import analyze as analysis
from studies.analysis import taguchi
from studies.analysis.missing import nothing_to_analyse
from studies.common.errors import StudyError
from studies.common.figure_layout import save_figures
from studies.define.sampling import SAMPLING_DESIGNS
from studies.report import html as html_report
from studies.report import markdown_report, plots
from studies.report import text as analysis_text
from studies.report.figure_pool import Drawing
from studies.report.uncertainty import noise_report, sample_report, sobol_report
from studies.run.results import NOISE, is_scalar
from studies.scenes import SCENES, get_scene


def write_analysis(
    ds: xr.Dataset,
    folder: Path,
    responses: list[str] | None = None,
    pool: list[str] | None = None,
    timings: dict[str, float] | None = None,
    problems: list[str] | None = None,
) -> list[Path]:
    """Analyse once and save ``analysis.nc`` first (the numbers are on disk before anything is
    drawn), then render ``analysis.txt``, ``report.md`` and the PNG figures into ``folder``;
    return the paths (text first). ``timings`` gets the seconds of each phase:
    ``analysis_s``, ``figures_s`` and ``report_s`` (the texts). A figure that fails to draw
    costs that figure only: the report leaves it out and ``problems`` gets one line saying
    which and why.

    A response that is NaN in every run (e.g. ``jump_start`` when no design point separates)
    gets a line saying so instead of tables and figures.
    """
    clock = Phases(timings if timings is not None else {})
    drawing = Drawing(clock.timings, problems if problems is not None else [])
    names = responses or json.loads(ds.attrs.get("responses", "[]")) or list(ds.data_vars)
    scalar = [r for r in names if r in ds and is_scalar(ds[r])]
    missing = [r for r in names if r not in ds]
    if missing:
        raise StudyError(
            f"responses not in the results: {', '.join(missing)} "
            f"(available: {', '.join(map(str, ds.data_vars))})"
        )
    folder.mkdir(parents=True, exist_ok=True)
    with clock("analysis_s"):
        ds = analysis.with_level_codes(ds)  # once, for the analysis and the renderers
        an = analysis.analyze(ds, scalar, pool)
        nc = analysis.write_analysis_nc(an, folder)
    done = json.loads(an.attrs["analysed"])
    means = {r: taguchi.mean_name(ds, r) for r in scalar}  # under noise: <r>_mean per run
    analysed = [r for r in scalar if means[r] in done]
    header = _header(ds) + not_run_line(an, "\n")
    body = _design_outputs(ds, an, analysed, means, folder, drawing)
    status = json.loads(an.attrs.get("status_responses", "[]"))
    body += [analysis_text.wrap(analysis_text.status_line(an, r)) for r in status]
    body += [
        analysis_text.wrap(_no_value_note(ds[r]))
        for r in scalar
        if r not in analysed and r not in status
    ]
    scene_name = str(ds.attrs.get("scene", ""))
    if NOISE in ds.dims:
        body.append(analysis_text.wrap(NOISE_SUMMARIES))
    elif scene_name in SCENES:  # a plugin scene that is not installed here: generic outputs only
        scene = get_scene(scene_name)
        body += scene.summaries(ds)
        for name, build in scene.figures().items():
            drawing.add(save_figures, ds, folder, {name: build})
    with clock("report_s"):
        text_path = folder / "analysis.txt"
        text_path.write_text("\n\n".join([header, *body]) + "\n", encoding="utf-8")
    figures = drawing.paths()
    with clock("report_s"):
        reports = markdown_report.write_report(ds, an, folder, scalar, figures)
        page = html_report.write_html(reports[0], figures)
    return [text_path, *reports, page, nc, *figures]


class Phases:
    """Seconds spent per phase, added up into ``timings`` (``with clock("report_s"): …``)."""

    def __init__(self, timings: dict[str, float]) -> None:
        self.timings = timings

    @contextmanager
    def __call__(self, phase: str) -> Iterator[None]:
        start = time.perf_counter()
        try:
            yield
        finally:
            spent = time.perf_counter() - start
            self.timings[phase] = self.timings.get(phase, 0.0) + spent


def _design_outputs(
    ds: xr.Dataset,
    an: xr.Dataset,
    analysed: list[str],
    means: dict[str, str],
    folder: Path,
    drawing: Drawing,
) -> list[str]:
    """The design's own text blocks (sweep, Saltelli, sample or array/factorial); its figures
    go to ``drawing``, one job per response so that they are drawn side by side."""
    design = ds.attrs.get("design")
    if design == "sweep":
        for r in analysed:
            drawing.add(plots.save_sweep_plots, ds, [r], folder)
        return [analysis_text.format_sweep(ds, analysed)]
    if design == "saltelli":
        drawing.add(sobol_report.save_tornado, an, folder)
        return sobol_report.sobol_text(an)
    if design in SAMPLING_DESIGNS:
        drawing.add(sample_report.save_correlations, an, folder)
        return sample_report.sample_text(an)
    body = [noise_report.robust_text(ds, an)] if noise_report.has_noise(an) else []
    body += [analysis_text.format_tables(an, means[r]) for r in analysed]
    varying = [means[r] for r in analysed if int(an["varies"].sel(response=means[r]))]
    for r in varying:
        drawing.add(plots.save_main_effects, an, [r], folder)
    if noise_report.has_noise(an):
        drawing.add(noise_report.save_noise_figures, ds, an, folder)
    for r in [r for r in analysed if f"{r}_sn" in an["response"].values]:
        drawing.add(plots.save_sn_plots, an, [r], folder)
    for r in analysed:
        drawing.add(plots.save_interaction_plots, an, [means[r]], folder)
    for r in varying:
        drawing.add(plots.save_maps, an, [r], folder)
    return body


NOISE_SUMMARIES = (
    "The scene's own summaries and figures describe single points; under noise they are not "
    "drawn (the statistics over the noise cases are above)."
)


def not_run_line(an: xr.Dataset, before: str = "") -> str:
    """A sentence on the design points that gave no value for any response ("" if none)."""
    without = int(an.attrs.get("points_without_value", 0))
    if not without:
        return ""
    return (
        f"{before}{without} of {an.attrs['points']} design points gave no value for any "
        "response (they did not run: the reasons are listed further down where the scene "
        "records them)"
    )


def _no_value_note(y: xr.DataArray) -> str:
    """A response that is NaN (or ±inf) in every run is a result (no jump anywhere, a concave
    cam everywhere), not an error."""
    meaning = y.attrs.get("long_name", y.name)
    return f"{y.name} ({meaning}): {nothing_to_analyse(y)}, so there is nothing to analyse."


def _header(ds: xr.Dataset) -> str:
    title = ds.attrs.get("title", "results")
    run = ds.attrs.get("run_id", "")
    return (
        f"{title}\nrun {run} — design {ds.attrs.get('design', '?')}, "
        f"{ds.sizes['run']} design points, commit {ds.attrs.get('git_commit', '?')[:10]}"
        f"{' (dirty)' if ds.attrs.get('git_dirty') else ''}"
    )
