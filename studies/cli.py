"""Command line: ``python -m studies COMMAND``.

run STUDY|--all        validate, run and record a study (catalogue name or TOML path)
check STUDY [--full]   validate only, run nothing: at once, naming what it left to --full;
                       --full: every check run makes before computing
list                   the shipped studies
scenes [NAME]          document scenes: parameters, settings, responses, curves (units)
analyze RESULTS.nc     range analysis + ANOVA tables and main-effect plots beside the file
runs [--where EXPR]    the run registry, newest first, filtered (--json, --csv)
show RUN_ID            one run's record
compare RUN_A RUN_B…   what differs: definitions, code, versions, timings, responses
regress BASE RUN       exit 1 when a response moved beyond tolerance
tag RUN_ID TAG         name a run (tags work wherever a run id does); note RUN_ID TEXT
rm RUN_ID, gc          move runs to the trash (outputs/.trash); restore RUN_ID, trash
reindex                rebuild the registry from the run folders
mlflow RUN_ID --to URI log recorded runs to MLflow (e.g. sqlite:///mlflow.db)
export RUN_ID          the results (and curves) as CSV or Parquet

Exit codes: 0 done, 1 regress: a response moved, 2 bad input, 3 --strict: points did not run,
4 a file or the registry cannot be used (full disk, permissions, damage, locked), 130 Ctrl-C.
"""

from __future__ import annotations

import argparse
import contextlib
import functools
import json
import sqlite3
import sys
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

from studies.common.errors import (
    EXIT_OUTPUT_ERROR,
    EXIT_STUDY_ERROR,
    EngineError,
    StudyError,
    StudyFileError,
)
from studies.common.text_safety import TerminalText, printable_dataset
from studies.tracking.registry_file import REGISTRY, RegistryUnusable, unusable
from studies.tracking_cli import add_commands, check_mlflow, label_run, track_run

if TYPE_CHECKING:
    from concurrent.futures import Executor

    from studies.define.plan import Plan
    from studies.pipeline import RunResult
    from studies.tracking.store import RunStore

OUTPUTS_HELP = (
    "run-folder root (default: $ENGINE_STUDIES_OUTPUTS, else this checkout's outputs/ folder)"
)
EXIT_POINTS_NOT_RUN = 3
BUG = (
    "error: this is a bug in the engine or in a scene, not in your input; please report it "
    "with the traceback below"
)
EXIT_INTERRUPTED = 130  # the shell's code for a process ended by SIGINT


def main(argv: list[str] | None = None) -> int:
    """Run one command; return its exit code. What it prints passes through
    :class:`~studies.common.text_safety.TerminalText` (no escape sequences from a description)."""
    streams = sys.stdout, sys.stderr
    sys.stdout, sys.stderr = TerminalText(sys.stdout), TerminalText(sys.stderr)
    try:
        return _main(argv)
    finally:
        sys.stdout, sys.stderr = streams


def _main(argv: list[str] | None) -> int:
    """:func:`main` with user text on the terminal stripped of control characters."""
    parser = _parser()
    args = parser.parse_args(argv)
    if "outputs" in vars(args):  # absolute, so the registry never holds a relative folder
        args.outputs = (args.outputs or _default_outputs()).resolve()
    try:
        return int(args.func(args) or 0)
    except StudyFileError as exc:
        print(f"error: {exc}", file=sys.stderr)
        print(
            "(nothing was run or written; `python -m studies scenes` documents every name)",
            file=sys.stderr,
        )
        return exc.exit_code
    except BrokenPipeError:  # output piped into `head` and the like
        sys.stderr.close()
        return 0
    except sqlite3.Error as exc:  # the registry, on a path that did not say it more precisely
        outputs = getattr(args, "outputs", None) or _default_outputs()
        print(f"error: {unusable(exc, outputs / REGISTRY)}", file=sys.stderr)
        return EXIT_OUTPUT_ERROR
    except OSError as exc:  # full disk, read-only or unreadable files: one line, how to go on
        what = f"{exc.strerror}: {exc.filename}" if exc.strerror and exc.filename else str(exc)
        said = isinstance(exc, RegistryUnusable)  # its message says what was changed
        notes = "; ".join(getattr(exc, "__notes__", [])) or ("" if said else "nothing was recorded")
        print(f"error: {what}" + (f"; {notes}" if notes else ""), file=sys.stderr)
        return EXIT_OUTPUT_ERROR
    except EngineError as exc:  # the input or a run's state: one line, what to do
        notes = "; ".join(getattr(exc, "__notes__", []))
        print(f"error: {exc}" + (f"; {notes}" if notes else ""), file=sys.stderr)
        return exc.exit_code
    except KeyboardInterrupt as exc:  # Ctrl-C: one line, and how to go on
        notes = "; ".join(getattr(exc, "__notes__", [])) or "nothing was recorded"
        print(f"\ninterrupted: {notes}", file=sys.stderr)
        return EXIT_INTERRUPTED
    except Exception:
        print(BUG, file=sys.stderr)
        raise


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="python -m studies",
        description=__doc__,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    sub = p.add_subparsers(required=True, metavar="COMMAND")

    run = sub.add_parser("run", help="validate, run and record a study")
    run.add_argument("study", nargs="?", help="catalogue name or path to a TOML file")
    run.add_argument("--all", action="store_true", help="run every catalogue study")
    run.add_argument("--outputs", type=Path, help=OUTPUTS_HELP)
    run.add_argument(
        "--chunk-size",
        type=positive_int,
        default=None,
        help="design points per chunk (bounds memory; default: the runner's)",
    )
    run.add_argument("--no-progress", action="store_true", help="no progress bar")
    run.add_argument(
        "--strict",
        action="store_true",
        help=f"exit {EXIT_POINTS_NOT_RUN} when a design point gave no value for any response "
        "or check warned about it (e.g. a concave cam)",
    )
    run.add_argument(
        "--force",
        action="store_true",
        help="recompute even if an identical definition already ran on this clean commit",
    )
    run.add_argument("--resume", metavar="RUN_ID", help="finish an interrupted or failed run")
    run.add_argument(
        "--scheduler",
        metavar="ADDRESS",
        help="run chunks on a Dask cluster (scheduler address, or 'local')",
    )
    run.add_argument(
        "--mlflow",
        metavar="URI",
        help="also log the run to MLflow (tracking URI, e.g. sqlite:///mlflow.db; the [mlflow] "
        "extra); a reused run is logged too, once",
    )
    run.add_argument("--tag", action="append", default=[], help="tag the run (repeat for more)")
    run.add_argument("--note", help="add a note to the run")
    run.set_defaults(func=_cmd_run)

    check = sub.add_parser("check", help="validate a study without running it")
    check.add_argument("study")
    check.add_argument(
        "--full",
        action="store_true",
        help="also draw the samples that need scipy.stats and make the checks that need the "
        "compiler (a second or more; `run` makes them before computing anyway)",
    )
    check.set_defaults(func=_cmd_check)

    lst = sub.add_parser("list", help="list the shipped studies")
    lst.set_defaults(func=_cmd_list)

    scenes = sub.add_parser("scenes", help="document the scenes")
    scenes.add_argument("name", nargs="?")
    scenes.set_defaults(func=_cmd_scenes)

    analyze = sub.add_parser("analyze", help="tables and plots for a results.nc")
    analyze.add_argument("results", type=Path)
    analyze.add_argument("--response", action="append", help="only these responses")
    analyze.add_argument(
        "--to",
        type=Path,
        help="folder for the tables and figures (default: a new analysis-<time> folder beside "
        "the results; the run's own analysis is never overwritten)",
    )
    pooling = analyze.add_mutually_exclusive_group()
    pooling.add_argument(
        "--pool",
        action="append",
        metavar="FACTOR",
        help="pool this factor into the ANOVA error (repeat for more; overrides the study's "
        "[design] pool)",
    )
    pooling.add_argument(
        "--no-pool",
        action="store_true",
        help="pool nothing, even when the error has no degrees of freedom",
    )
    analyze.set_defaults(func=_cmd_analyze)

    add_commands(sub, OUTPUTS_HELP)

    bench = sub.add_parser("bench", help="run benchmarks (cases/s, ratios)")
    bench.add_argument("name", help="benchmark name or 'all'")
    bench.add_argument("--cases", type=int, default=20000, help="design points per timing")
    bench.add_argument(
        "--points",
        type=float,
        default=1e6,
        help="cases of the end-to-end 'study' and 'noise_study' benchmarks (e.g. 1e7)",
    )
    bench.add_argument("--step", type=float, default=0.5, help="angle step [deg]")
    bench.add_argument("--repeat", type=int, default=3, help="timed repetitions (best kept)")
    bench.add_argument("--outputs", type=Path, help=OUTPUTS_HELP)
    bench.set_defaults(func=_cmd_bench)
    return p


def positive_int(text: str) -> int:
    """An argparse type: a whole number of at least 1."""
    try:
        value = int(text)
    except ValueError:
        value = 0
    if value < 1 or str(value) != text.strip():
        msg = f"{text!r} is not a positive whole number of design points"
        raise argparse.ArgumentTypeError(msg)
    return value


def _cmd_bench(args: argparse.Namespace) -> int:
    from studies.bench.benchmarks import benchmarks, run_benchmark, summarize

    names = list(benchmarks()) if args.name == "all" else [args.name]
    for name in names:
        cases = int(args.points) if name in ("study", "noise_study") else args.cases
        path = run_benchmark(name, cases, args.step, args.repeat, args.outputs)
        figures = json.loads(path.read_text(encoding="utf-8"))["figures"]
        print(f"benchmark {name} ({cases} cases, step {args.step} deg):")
        print("\n".join(summarize(figures)))
        print(f"  all figures in {path} (bar chart: {path.with_suffix('.png').name})")
    return 0


def _figure_workers(command: Callable[[argparse.Namespace], int]) -> Callable[..., int]:
    """``command`` with the figure workers (:mod:`studies.report.figure_pool`) started
    before it imports anything heavy: they import the renderers while it computes."""

    @functools.wraps(command)
    def with_workers(args: argparse.Namespace) -> int:
        from studies.report import figure_pool

        figure_pool.warm()
        try:
            return command(args)
        finally:
            figure_pool.stop()

    return with_workers


def _cmd_run(args: argparse.Namespace) -> int:
    from studies.define.plan import plan_study

    if args.all == bool(args.study or args.resume):
        print("error: name one study, --resume RUN_ID or --all", file=sys.stderr)
        return EXIT_STUDY_ERROR
    if args.resume:
        return _resume(args)
    from studies.define.definition import catalog_names  # numpy: not for --help

    names = catalog_names() if args.all else [args.study]
    plans = [plan_study(n) for n in names]
    check_mlflow(args)
    if not args.scheduler:
        return _run_plans(args, plans, None)
    from studies.run.cluster import cluster_executor

    with cluster_executor(args.scheduler, sorted({p.definition.scene for p in plans})) as pool:
        return _run_plans(args, plans, pool)


@_figure_workers
def _resume(args: argparse.Namespace) -> int:
    from studies.pipeline import resume_run

    check_mlflow(args)
    result = resume_run(args.resume, args.outputs, progress=not args.no_progress)
    label_run(args, result.record.run_id)
    _report(result)
    track_run(args, Path(result.folder), result.record.run_id)
    return 0


def _run_plans(args: argparse.Namespace, plans: list[Plan], executor: Executor | None) -> int:
    """Run (or reuse) each plan; chunks on ``executor`` when given. A reused run imports
    nothing of the pipeline and starts no figure worker: the answer takes a plan and two
    hashes (0.6–0.9 s for isac_l9 on the 2-core machine)."""
    from studies.report import figure_pool
    from studies.tracking.store import RunStore

    runs = RunStore(args.outputs)
    try:
        flagged = sum(_run_or_reuse(args, plan, runs, executor) for plan in plans)
    finally:
        figure_pool.stop()
    if args.strict and flagged:
        print(
            f"error (--strict): {flagged} run(s) have design points that did not run or that "
            "check warned about",
            file=sys.stderr,
        )
        return EXIT_POINTS_NOT_RUN
    return 0


def _run_or_reuse(
    args: argparse.Namespace, plan: Plan, runs: RunStore, executor: Executor | None
) -> bool:
    """Reuse the finished run of an identical definition on identical code, else compute the
    plan; whether the run has design points without a value or check warned about them."""
    from studies.report import figure_pool
    from studies.run import provenance
    from studies.tracking import records

    key = records.definition_hash(plan.definition.text, plan.definition.input_files())
    code = provenance.code_hash(provenance.code(type(plan.scene)))
    earlier = None if args.force else runs.finished_identical(key, code)
    if earlier is None:
        figure_pool.warm()  # the workers import the renderers while this process computes
    warned = _warn(plan) > 0  # true of a reused result too: same definition, same code
    if earlier is None:
        result = _run_plan(args, plan, executor)
        return warned or result.record.points_without_value > 0
    label_run(args, earlier["run_id"])
    print(
        f"{plan.definition.name}: identical definition already ran on identical code "
        f"(engine and scene sources, library versions): reusing run "
        f"{earlier['run_id']} (--force recomputes)"
    )
    print(f"  {Path(earlier['folder']) / 'results.nc'}")
    track_run(args, Path(earlier["folder"]), earlier["run_id"])
    return warned or _points_without_value(Path(earlier["folder"])) > 0


def _run_plan(args: argparse.Namespace, plan: Plan, executor: Executor | None) -> RunResult:
    """Compute one plan and report it."""
    from studies.pipeline import run_plan
    from studies.run.runner import DEFAULT_CHUNK_SIZE

    result = run_plan(
        plan, args.outputs, args.chunk_size or DEFAULT_CHUNK_SIZE, not args.no_progress, executor
    )
    label_run(args, result.record.run_id)
    _report(result)
    track_run(args, result.folder, result.record.run_id)
    return result


def _points_without_value(folder: Path) -> int:
    """The design points of a finished run that gave no value (its run.json; 0 if unreadable:
    the reuse check found the run finished)."""
    try:
        record = json.loads((folder / "run.json").read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return 0
    return int(record.get("points_without_value", 0))


def _report(result: RunResult) -> None:
    r, t = result.record, result.record.timings
    print(
        f"{r.study}: {r.runs} design points ({r.design}), "
        f"compile {t['compile_s']:.2f} s, run {t['run_s']:.3f} s"
    )
    print("\n".join(f"  {f}" for f in result.files))
    if r.points_without_value:
        print(
            f"warning: {r.points_without_value} of {r.runs} design points of {r.study} gave no "
            f"value for any response (they did not run; reasons in {r.folder}/analysis.txt)",
            file=sys.stderr,
        )
    for line in r.warnings:  # a figure that could not be drawn: the numbers are complete
        print(f"warning: {r.study}: {line}", file=sys.stderr)


def _default_outputs() -> Path:
    """The outputs root (imported on use: ``check``, ``list`` and ``scenes`` need no store)."""
    from studies.tracking.records import default_outputs

    return default_outputs()


def _cmd_check(args: argparse.Namespace) -> int:
    from engine_kernels._jit import CompilerNeeded, without_compiler

    if args.full:
        return _check(args)
    try:
        with without_compiler():
            return _check(args)
    except CompilerNeeded:  # a check outside the scene's point checks calls a kernel
        args.full = True
        return _check(args)


def _check(args: argparse.Namespace) -> int:
    from studies.define.plan import noise_label, plan_study

    plan = plan_study(args.study, quick=not args.full)
    d = plan.definition
    unchecked = list(plan.unchecked)
    advice = _advice(plan, None if args.full else unchecked) if plan.drawn else []
    noise = f" x {plan.noise_cases} noise cases ({noise_label(d)})" if d.noise else ""
    print(
        f"{d.name}: OK{' as far as checked here' if unchecked else ''} — scene {d.scene}, "
        f"design {plan.design.name}, {plan.runs} runs{noise}, stages {', '.join(plan.stages)}"
    )
    for line in advice:
        print(f"warning: {d.name}: {line}", file=sys.stderr)
    for line in unchecked:
        print(f"not checked here, `check --full` and `run` check it: {line}")
    return 0


def _warn(plan: Plan) -> int:
    """Print the design points that will run but give no value or an infinite one (the
    scene's advice); return how many warnings."""
    lines = _advice(plan)
    for line in lines:
        print(f"warning: {plan.definition.name}: {line}", file=sys.stderr)
    return len(lines)


def _advice(plan: Plan, unchecked: list[str] | None = None) -> list[str]:
    """The scene's advice on the points; ``unchecked`` (a quick check): start no compiler, and
    if the advice needs it, say so there instead."""
    if unchecked is None:
        return plan.scene.point_warnings(plan.points, plan.settings)
    from studies.define.plan import quickly
    from studies.scenes.checks import at_nominal_values

    whole = "the scene's advice on the points, e.g. concave cams"
    each = "the scene's advice (e.g. concave cams) from"
    with at_nominal_values() if plan.nominal else contextlib.nullcontext():
        return quickly(
            lambda: plan.scene.point_warnings(plan.points, plan.settings), whole, each, unchecked
        )


def _cmd_list(_: argparse.Namespace) -> int:
    from studies.define.definition import catalog_names, read_study  # as above

    for name in catalog_names():
        definition, _problems = read_study(name)
        desc = definition.description.splitlines()[0] if definition else ""
        print(f"{name:<24} {desc}")
    return 0


def _cmd_scenes(args: argparse.Namespace) -> int:
    from studies.scenes import SCENES, describe_scene, get_scene

    names = [args.name] if args.name else sorted(SCENES)
    print("\n\n".join(describe_scene(get_scene(n)) for n in names))
    return 0


@_figure_workers
def _cmd_analyze(args: argparse.Namespace) -> int:
    import datetime as dt

    from studies.report.write import write_analysis
    from studies.run.results import open_results

    if not args.results.exists():
        raise StudyError(f"no such results file: {args.results}")
    stamp = dt.datetime.now(dt.UTC).strftime("%Y%m%dT%H%M%S")
    folder = args.to or args.results.parent / f"analysis-{stamp}"
    if folder.resolve() == args.results.parent.resolve():
        msg = f"--to {folder} is the run's own folder: its recorded analysis would be overwritten"
        raise StudyError(msg)
    if (folder / "run.json").exists() or (folder / "results.nc").exists():
        msg = f"--to {folder} holds a run's results: its recorded analysis would be overwritten"
        raise StudyError(msg)
    ds = printable_dataset(open_results(args.results))
    if args.no_pool or args.pool:
        ds.attrs["pool"] = json.dumps([] if args.no_pool else args.pool)
    created = not folder.exists()
    before = set(folder.iterdir()) if not created else set()
    try:
        files = write_analysis(ds, folder, args.response)
    except BaseException:  # a full disk: remove what this attempt wrote, keep the rest
        with contextlib.suppress(OSError):
            for path in set(folder.iterdir()) - before:
                with contextlib.suppress(OSError):
                    path.unlink()
            if created:
                folder.rmdir()
        raise
    print(files[0].read_text(encoding="utf-8"))
    for f in files:
        print(f"wrote {f}")
    return 0
