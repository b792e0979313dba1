"""Command line: ``python -m studies COMMAND``.

run STUDY|--all        validate, run and record a study (catalogue name or TOML path)
check STUDY            validate only: list every problem, run nothing
list                   the shipped studies
scenes [NAME]          document scenes: parameters, settings, responses, curves (units)
analyze RESULTS.nc     range analysis + ANOVA tables and main-effect plots beside the file
runs [--where EXPR]    the run registry, newest first, filtered (--json, --csv)
show RUN_ID            one run's record
compare RUN_A RUN_B…   what differs: definitions, code, versions, timings, responses
regress BASE RUN       exit 1 when a response moved beyond tolerance
tag RUN_ID TAG         name a run (tags work wherever a run id does); note RUN_ID TEXT
rm RUN_ID, gc          remove runs (folder and registry rows together)
export RUN_ID          the results as CSV or Parquet
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import TYPE_CHECKING

from studies.definition import StudyError, catalog_names, read_study
from studies.tracking_cli import add_commands

if TYPE_CHECKING:
    from studies.plan import Plan
    from studies.study_run import RunResult

EXIT_STUDY_ERROR = 2
OUTPUTS_HELP = (
    "run-folder root (default: $ENGINE_STUDIES_OUTPUTS, else this checkout's outputs/ folder)"
)
EXIT_POINTS_NOT_RUN = 3
EXIT_OUTPUT_ERROR = 4  # a file could not be written or read (full disk, permissions, damage)
EXIT_INTERRUPTED = 130  # the shell's code for a process ended by SIGINT


def main(argv: list[str] | None = None) -> int:
    from studies.tracking import default_outputs

    parser = _parser()
    args = parser.parse_args(argv)
    if "outputs" in vars(args):  # absolute, so the registry never holds a relative folder
        args.outputs = (args.outputs or default_outputs()).resolve()
    try:
        return int(args.func(args) or 0)
    except StudyError as exc:
        print(f"error: {exc}", file=sys.stderr)
        print(
            "(nothing was run or written; `python -m studies scenes` documents every name)",
            file=sys.stderr,
        )
        return EXIT_STUDY_ERROR
    except (FileNotFoundError, ValueError, KeyError) as exc:
        message = exc.args[0] if isinstance(exc, KeyError) and exc.args else exc
        print(f"error: {message}", file=sys.stderr)
        return EXIT_STUDY_ERROR
    except BrokenPipeError:  # output piped into `head` and the like
        sys.stderr.close()
        return 0
    except OSError as exc:  # full disk, read-only or unreadable files: one line, how to go on
        what = f"{exc.strerror}: {exc.filename}" if exc.strerror and exc.filename else str(exc)
        notes = "; ".join(getattr(exc, "__notes__", [])) or "nothing was recorded"
        print(f"error: {what}; {notes}", file=sys.stderr)
        return EXIT_OUTPUT_ERROR
    except KeyboardInterrupt as exc:  # Ctrl-C: one line, and how to go on
        notes = "; ".join(getattr(exc, "__notes__", [])) or "nothing was recorded"
        print(f"\ninterrupted: {notes}", file=sys.stderr)
        return EXIT_INTERRUPTED


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
        help="also log the run to MLflow (tracking URI, e.g. file:./mlruns; optional extra)",
    )
    run.set_defaults(func=_cmd_run)

    check = sub.add_parser("check", help="validate a study without running it")
    check.add_argument("study")
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
        help="design points of the end-to-end 'study' benchmark (e.g. 1e7)",
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
    from studies.bench import BENCHMARKS, run_benchmark, summarize

    names = list(BENCHMARKS) if args.name == "all" else [args.name]
    for name in names:
        cases = int(args.points) if name == "study" else args.cases
        path = run_benchmark(name, cases, args.step, args.repeat, args.outputs)
        figures = json.loads(path.read_text(encoding="utf-8"))["figures"]
        print(f"benchmark {name} ({cases} cases, step {args.step} deg):")
        print("\n".join(summarize(figures)))
        print(f"  all figures in {path} (bar chart: {path.with_suffix('.png').name})")
    return 0


def _cmd_run(args: argparse.Namespace) -> int:
    from studies import provenance, tracking
    from studies.plan import plan_study
    from studies.runner import DEFAULT_CHUNK_SIZE, dask_executor
    from studies.study_run import resume_run, run_plan

    if args.resume:
        result = resume_run(args.resume, args.outputs, progress=not args.no_progress)
        _report(result, args.mlflow)
        return 0
    if args.all == bool(args.study):
        print("error: name one study or use --all", file=sys.stderr)
        return EXIT_STUDY_ERROR
    names = catalog_names() if args.all else [args.study]
    plans = [plan_study(n) for n in names]
    commit, dirty = provenance.git_state()
    executor = dask_executor(args.scheduler) if args.scheduler else None
    flagged = 0
    for plan in plans:
        key = tracking.definition_hash(plan.definition.text, plan.definition.input_files())
        earlier = (
            None if args.force or dirty else tracking.finished_identical(args.outputs, key, commit)
        )
        if earlier is not None:
            print(
                f"{plan.definition.name}: identical definition already ran on commit "
                f"{commit[:10]}: reusing run {earlier['run_id']} (--force recomputes)"
            )
            print(f"  {Path(earlier['folder']) / 'results.nc'}")
            continue
        warned = _warn(plan) > 0
        result = run_plan(
            plan,
            args.outputs,
            args.chunk_size or DEFAULT_CHUNK_SIZE,
            not args.no_progress,
            executor,
        )
        _report(result, args.mlflow)
        flagged += warned or result.record.points_without_value > 0
    if args.strict and flagged:
        print(
            f"error (--strict): {flagged} run(s) have design points that did not run or that "
            "check warned about",
            file=sys.stderr,
        )
        return EXIT_POINTS_NOT_RUN
    return 0


def _report(result: RunResult, mlflow_uri: str | None = None) -> None:
    r = result.record
    t = r.timings
    print(
        f"{r.study}: {r.runs} design points ({r.design}), "
        f"compile {t['compile_s']:.2f} s, run {t['run_s']:.3f} s"
    )
    for f in result.files:
        print(f"  {f}")
    if r.points_without_value:
        print(
            f"warning: {r.points_without_value} of {r.runs} design points of {r.study} gave no "
            f"value for any response (they did not run; reasons in {r.folder}/analysis.txt)",
            file=sys.stderr,
        )
    if mlflow_uri:
        from studies.mlflow_export import log_run

        print(f"  logged to MLflow at {mlflow_uri} as run {log_run(mlflow_uri, r)}")


def _cmd_check(args: argparse.Namespace) -> int:
    from studies.plan import plan_study

    plan = plan_study(args.study)
    d = plan.definition
    print(
        f"{d.name}: OK — scene {d.scene}, design {plan.design.name}, {plan.runs} runs, "
        f"stages {', '.join(plan.stages)}"
    )
    _warn(plan)
    return 0


def _warn(plan: Plan) -> int:
    """Print the design points that will run but give no value or an infinite one (the
    scene's advice); return how many warnings."""
    lines = plan.scene.point_warnings(plan.points, plan.settings)
    for line in lines:
        print(f"warning: {plan.definition.name}: {line}", file=sys.stderr)
    return len(lines)


def _cmd_list(_: argparse.Namespace) -> int:
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


def _cmd_analyze(args: argparse.Namespace) -> int:
    import datetime as dt

    from studies.report import write_analysis
    from studies.results import open_results

    if not args.results.exists():
        raise FileNotFoundError(f"no such results file: {args.results}")
    stamp = dt.datetime.now(dt.UTC).strftime("%Y%m%dT%H%M%S")
    folder = args.to or args.results.parent / f"analysis-{stamp}"
    if folder.resolve() == args.results.parent.resolve():
        msg = f"--to {folder} is the run's own folder: its recorded analysis would be overwritten"
        raise ValueError(msg)
    ds = open_results(args.results)
    if args.no_pool or args.pool:
        ds.attrs["pool"] = json.dumps([] if args.no_pool else args.pool)
    files = write_analysis(ds, folder, args.response)
    print(files[0].read_text(encoding="utf-8"))
    for f in files:
        print(f"wrote {f}")
    return 0
