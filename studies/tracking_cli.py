"""The tracking commands of ``python -m studies``: runs, show, compare, regress, tag, note, rm,
gc, export. Wherever a RUN_ID is asked for, a tag or a unique prefix of the id works too.

Exit codes: 0 done, 1 ``regress`` found a response beyond tolerance, 2 bad input (unknown run
or tag, no shared responses, a --where that does not parse), with one line on stderr.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

EXIT_REGRESSED = 1


def add_commands(sub: Any, outputs_help: str) -> None:
    """Add the tracking subcommands to the subparsers ``sub``."""

    def command(name: str, help_text: str, func: Any) -> argparse.ArgumentParser:
        p = sub.add_parser(name, help=help_text)
        p.add_argument("--outputs", type=Path, help=outputs_help)
        p.set_defaults(func=func)
        return p

    runs = command("runs", "list and filter recorded runs", _runs)
    runs.add_argument("--study")
    runs.add_argument("--scene")
    runs.add_argument("--status", help="finished, running, interrupted, failed or missing")
    runs.add_argument("--since", metavar="DATE", help="started on or after (ISO date)")
    runs.add_argument("--tag", help="only the run with this tag")
    runs.add_argument(
        "--where",
        action="append",
        metavar="EXPR",
        help='e.g. "cam_speed>=5000", "max_jerk.max<900", "integrator=rk4" (repeat: all hold)',
    )
    shape = runs.add_mutually_exclusive_group()
    shape.add_argument("--json", action="store_true", help="JSON, with every recorded value")
    shape.add_argument("--csv", action="store_true", help="CSV, one line per run")

    command("show", "show one run's record", _show).add_argument("run_id")

    compare = command("compare", "what differs between runs (the first is the reference)", _compare)
    compare.add_argument("run_ids", nargs="+", metavar="RUN_ID")
    compare.add_argument("--plot", action="store_true", help="overlay main effects per response")
    compare.add_argument("--to", type=Path, help="folder for the --plot figures")

    regress = command("regress", "exit 1 when a response moved beyond tolerance", _regress)
    regress.add_argument("baseline", metavar="BASELINE")
    regress.add_argument("run_id", metavar="RUN_ID")
    regress.add_argument("--rtol", type=float, default=None, help="relative tolerance (1e-7)")
    regress.add_argument("--atol", type=float, default=None, help="absolute tolerance (0)")
    regress.add_argument("--tolerances", type=Path, help="TOML: [response] rtol = …, atol = …")

    tag = command("tag", "tag a run (a tag names one run: it moves)", _tag)
    tag.add_argument("run_id")
    tag.add_argument("tag")
    tag.add_argument("--remove", action="store_true", help="remove the tag instead")

    note = command("note", "add a note to a run", _note)
    note.add_argument("run_id")
    note.add_argument("text")

    command("rm", "remove a run: its folder and registry rows", _rm).add_argument("run_id")

    gc = command("gc", "remove old runs", _gc)
    gc.add_argument("--older-than", required=True, metavar="AGE", help="e.g. 30d, 12h, 2w")
    gc.add_argument("--keep-tagged", action="store_true", help="never remove a tagged run")
    gc.add_argument("--dry-run", action="store_true", help="list what would be removed")

    export = command("export", "a run's results as CSV or Parquet", _export)
    export.add_argument("run_id")
    export.add_argument("--format", choices=("csv", "parquet"), default="csv")
    export.add_argument("--to", type=Path, help="file to write (default: in the run folder)")


def _runs(args: argparse.Namespace) -> int:
    from studies import query
    from studies.tracking import resume_command

    rows = query.find_runs(
        args.outputs, args.study, args.scene, args.status, args.since, args.where, args.tag
    )
    if args.json or args.csv:
        rows = query.with_values(args.outputs, rows)
        print(query.as_json(rows) if args.json else query.as_csv(rows), end="\n" * args.json)
        return 0
    if not rows:
        print(f"no runs recorded under {args.outputs} match")
        return 0
    print(query.as_table(rows))
    for r in rows:
        if r["status"] in ("interrupted", "failed"):
            print(f"resume {r['run_id']}: {resume_command(r['run_id'], args.outputs)}")
    return 0


def _show(args: argparse.Namespace) -> int:
    from studies import registry
    from studies.tracking import current_status, resolve_run, resume_command

    row = resolve_run(args.outputs, args.run_id)
    status, record = current_status(row)
    if record is None:
        raise FileNotFoundError(
            f"run {row['run_id']} is in the registry but its folder {row['folder']} is gone"
        )
    record["status"] = status
    tags, notes = registry.tags_and_notes(args.outputs)
    record["tags"] = tags.get(row["run_id"], [])
    record["notes"] = notes.get(row["run_id"], [])
    print(json.dumps(record, indent=2))
    if status in ("interrupted", "failed"):
        print(f"resume it with: {resume_command(row['run_id'], args.outputs)}")
    return 0


def _compare(args: argparse.Namespace) -> int:
    from studies.compare import compare, format_comparison, load_run

    runs = [load_run(args.outputs, ref) for ref in args.run_ids]
    comparison = compare(runs)
    print(format_comparison(comparison))
    if args.plot:
        from studies.compare_plots import save_overlays

        folder = args.to or args.outputs / "compare" / "-vs-".join(x.run_id for x in runs)
        for path in save_overlays(comparison, folder):
            print(f"wrote {path}")
    return 0


def _regress(args: argparse.Namespace) -> int:
    from studies import regress
    from studies.compare import load_run

    tolerances = regress.read_tolerances(args.tolerances) if args.tolerances else {}
    baseline = load_run(args.outputs, args.baseline)
    run = load_run(args.outputs, args.run_id)
    default = regress.Tolerance(
        regress.DEFAULT_RTOL if args.rtol is None else args.rtol,
        regress.DEFAULT_ATOL if args.atol is None else args.atol,
    )
    checks = regress.check_results(run.results, baseline.results, tolerances, default)
    print(f"run {run.run_id} against baseline {baseline.run_id}:")
    print(regress.format_checks(checks))
    return 0 if all(c.ok for c in checks) else EXIT_REGRESSED


def _tag(args: argparse.Namespace) -> int:
    from studies import registry
    from studies.tracking import resolve_run

    if args.remove:
        if not registry.remove_tag(args.outputs, args.tag):
            raise KeyError(f"no tag {args.tag!r} under {args.outputs}")
        print(f"removed tag {args.tag}")
        return 0
    row = resolve_run(args.outputs, args.run_id)
    moved = registry.set_tag(args.outputs, row["run_id"], args.tag)
    print(f"tagged {row['run_id']} {args.tag}" + (f" (moved from {moved})" if moved else ""))
    return 0


def _note(args: argparse.Namespace) -> int:
    from studies import registry
    from studies.tracking import now, resolve_run

    row = resolve_run(args.outputs, args.run_id)
    registry.add_note(args.outputs, row["run_id"], now(), args.text)
    print(f"noted on {row['run_id']}")
    return 0


def _rm(args: argparse.Namespace) -> int:
    from studies.housekeeping import remove_run
    from studies.tracking import resolve_run

    row = resolve_run(args.outputs, args.run_id)
    remove_run(args.outputs, row)
    print(f"removed {row['run_id']} ({row['folder']})")
    return 0


def _gc(args: argparse.Namespace) -> int:
    from studies.housekeeping import collect_garbage, parse_age

    rows = collect_garbage(args.outputs, parse_age(args.older_than), args.keep_tagged, args.dry_run)
    verb = "would remove" if args.dry_run else "removed"
    for row in rows:
        print(f"{verb} {row['run_id']} ({row['study']}, started {row['started']})")
    print(f"{verb} {len(rows)} run(s)")
    return 0


def _export(args: argparse.Namespace) -> int:
    from studies.export import export_results
    from studies.tracking import resolve_run

    row = resolve_run(args.outputs, args.run_id)
    results = Path(row["folder"]) / "results.nc"
    if not results.exists():
        raise FileNotFoundError(f"run {row['run_id']} has no results.nc: nothing to export")
    to = args.to or results.with_suffix(f".{args.format}")
    print(f"wrote {export_results(results, to, args.format)}")
    return 0
