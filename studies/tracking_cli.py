"""The tracking commands of ``python -m studies``: runs, show, compare, regress, tag, note, rm,
restore, trash, gc, reindex, mlflow, export. Wherever a RUN_ID is asked for, a tag or a unique
prefix of the id works too (the id itself always wins over a tag).

Exit codes: 0 done, 1 ``regress`` found a response beyond tolerance, 2 bad input (unknown run
or tag, no shared responses, a --where that does not parse, a tagged or running run to ``rm``),
4 the registry or a file cannot be used (damaged, locked past the wait, read-only, full disk),
with one line on stderr saying what to do (a damaged registry: ``reindex``).
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any

from studies.common.errors import EXIT_OUTPUT_ERROR, RunNotFound, RunStateError, StudyError

if TYPE_CHECKING:
    from studies.tracking.store import RunStore

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
    runs.add_argument(
        "--since", metavar="WHEN", help="started on or after: an ISO date or an age (30d, 12h)"
    )
    runs.add_argument("--tag", help="only the run with this tag")
    runs.add_argument(
        "--where",
        action="append",
        metavar="EXPR",
        help='e.g. "cam_speed>=5000", "bore>=80 mm", "max_jerk.max<900", "status==finished", '
        "\"integrator=rk4\" (numbers in each run's scene's units unless one follows; a run "
        "whose units it does not convert to is skipped; repeat: all hold)",
    )
    runs.add_argument(
        "--columns",
        metavar="NAMES",
        help="comma-separated values to show as columns, in the scene's units "
        '(e.g. "cam_speed,bore,max_jerk.max")',
    )
    shape = runs.add_mutually_exclusive_group()
    shape.add_argument("--json", action="store_true", help="JSON, with every recorded value")
    shape.add_argument("--csv", action="store_true", help="CSV, one line per run")

    command("show", "show one run's record", _show).add_argument("run_id")

    compare = command("compare", "what differs between runs (the first is the reference)", _compare)
    compare.add_argument("run_ids", nargs="+", metavar="RUN_ID")
    compare.add_argument("--plot", action="store_true", help="overlay main effects per response")
    compare.add_argument("--to", type=Path, help="folder for the --plot figures")
    _tolerance_options(compare, "a response moved where a point differs beyond")

    regress = command("regress", "exit 1 when a response moved beyond tolerance", _regress)
    regress.add_argument(
        "baseline", metavar="BASELINE", help="a run (id, prefix or tag) or a results .nc file"
    )
    regress.add_argument("run_id", metavar="RUN", help="a run or a results .nc file")
    _tolerance_options(regress, "a point fails beyond")

    tag = command("tag", "tag a run (a tag names one run: it moves)", _tag)
    tag.add_argument("run_id")
    tag.add_argument("tag")
    tag.add_argument("--remove", action="store_true", help="remove the tag instead")

    note = command("note", "add a note to a run", _note)
    note.add_argument("run_id")
    note.add_argument("text")

    rm = command("rm", "move a run to the trash (outputs/.trash; `restore` undoes it)", _rm)
    rm.add_argument("run_id")
    rm.add_argument("--force", action="store_true", help="remove a tagged run too")

    restore = command("restore", "bring a run back from the trash", _restore)
    restore.add_argument("run_id", help="its id, a unique prefix, or a tag it had")

    command("trash", "list the runs in the trash", _trash)

    gc = command(
        "gc", "move runs older than AGE to the trash; delete what was trashed before AGE", _gc
    )
    gc.add_argument("--older-than", required=True, metavar="AGE", help="e.g. 30d, 12h, 2w")
    gc.add_argument(
        "--keep-tagged",
        action="store_true",
        help="never remove a tagged run, nor delete one from the trash",
    )
    gc.add_argument("--dry-run", action="store_true", help="list what would be removed")

    command("reindex", "rebuild the registry from the run folders (keeps the old one)", _reindex)

    mlflow = command("mlflow", "log recorded runs to MLflow (each once)", _mlflow)
    mlflow.add_argument("run_ids", nargs="+", metavar="RUN_ID")
    mlflow.add_argument(
        "--to", required=True, metavar="URI", help="tracking URI, e.g. sqlite:///mlflow.db"
    )

    export = command(
        "export", "a run's results as CSV or Parquet (curves in a second, long table)", _export
    )
    export.add_argument("run_id")
    export.add_argument("--format", choices=("csv", "parquet"), default="csv")
    export.add_argument("--to", type=Path, help="file to write (default: in the run folder)")


def _tolerance_options(parser: argparse.ArgumentParser, meaning: str) -> None:
    parser.add_argument(
        "--rtol", type=float, default=None, help=f"{meaning} this relative tolerance (1e-7)"
    )
    parser.add_argument("--atol", type=float, default=None, help="absolute tolerance (0)")
    parser.add_argument(
        "--tolerances", type=Path, help="TOML: [response] rtol = …, atol = … (per response)"
    )


def _tolerances(args: argparse.Namespace) -> tuple[Any, dict[str, Any]]:
    """(the default Tolerance, the per-response ones) of --rtol, --atol and --tolerances."""
    from studies.compare import tolerances

    per_response = tolerances.read_tolerances(args.tolerances) if args.tolerances else {}
    default = tolerances.Tolerance(
        tolerances.DEFAULT_RTOL if args.rtol is None else args.rtol,
        tolerances.DEFAULT_ATOL if args.atol is None else args.atol,
    )
    return default, per_response


def _store(args: argparse.Namespace) -> RunStore:
    """The run store of ``--outputs`` (imported on use)."""
    from studies.tracking.store import RunStore

    return RunStore(args.outputs)


def _runs(args: argparse.Namespace) -> int:
    from studies.tracking import query

    store = _store(args)
    rows, skipped = query.find_runs(
        store, args.study, args.scene, args.status, args.since, args.where, args.tag
    )
    for line in skipped:  # on stderr: --json and --csv stay whole on stdout
        print(f"note: {line}", file=sys.stderr)
    if args.json or args.csv:
        rows = query.with_values(store, rows)
        print(query.as_json(rows) if args.json else query.as_csv(rows), end="\n" * args.json)
        return 0
    if not rows:
        print(f"no runs recorded under {args.outputs} match")
        return 0
    columns = [c.strip() for c in (args.columns or "").split(",") if c.strip()]
    if columns:
        rows = query.with_values(store, rows)
        query.check_columns(rows, columns)
    print(query.as_table(rows, columns))
    for r in rows:
        if r["status"] in ("interrupted", "failed"):
            print(f"resume {r['run_id']}: {store.resume_command(r['run_id'])}")
    return 0


def _show(args: argparse.Namespace) -> int:
    from studies.tracking.liveness import current_status

    store = _store(args)
    row = store.resolve_run(args.run_id)
    status, record = current_status(row)
    if record is None:
        raise RunStateError(
            f"run {row['run_id']} is in the registry but its folder {row['folder']} is gone"
        )
    record["status"], record["folder"] = status, row["folder"]  # where it is now
    tags, notes = store.tags_and_notes()
    record["tags"] = tags.get(row["run_id"], [])
    record["notes"] = notes.get(row["run_id"], [])
    print(json.dumps(record, indent=2))
    if status in ("interrupted", "failed"):
        print(f"resume it with: {store.resume_command(row['run_id'])}")
    return 0


def _compare(args: argparse.Namespace) -> int:
    from studies.compare.runs import compare, format_comparison, load_run

    store = _store(args)
    runs = [load_run(store, ref) for ref in args.run_ids]
    default, per_response = _tolerances(args)
    comparison = compare(runs, default, per_response)
    print(format_comparison(comparison))
    if args.plot:
        from studies.compare.plots import save_overlays

        folder = args.to or args.outputs / "compare" / "-vs-".join(x.run_id for x in runs)
        for path in save_overlays(comparison, folder):
            print(f"wrote {path}")
    return 0


def _regress(args: argparse.Namespace) -> int:
    from studies.compare import regress
    from studies.compare.runs import load_results

    default, per_response = _tolerances(args)
    store = _store(args)
    baseline_id, baseline = load_results(store, args.baseline)
    run_id, run = load_results(store, args.run_id)
    checks = regress.check_results(run, baseline, per_response, default)
    print(f"{run_id} against baseline {baseline_id}:")
    print(regress.format_checks(checks))
    return 0 if all(c.ok for c in checks) else EXIT_REGRESSED


def _tag(args: argparse.Namespace) -> int:
    store = _store(args)
    if args.remove:
        if not store.remove_tag(args.tag):
            raise RunNotFound(f"no tag {args.tag!r} under {args.outputs}")
        print(f"removed tag {args.tag}")
        return 0
    row = store.resolve_run(args.run_id)
    moved = store.set_tag(row["run_id"], args.tag)
    print(f"tagged {row['run_id']} {args.tag}" + (f" (moved from {moved})" if moved else ""))
    return 0


def _note(args: argparse.Namespace) -> int:
    from studies.tracking.records import now

    store = _store(args)
    row = store.resolve_run(args.run_id)
    store.add_note(row["run_id"], now(), args.text)
    print(f"noted on {row['run_id']}")
    return 0


def _rm(args: argparse.Namespace) -> int:
    store = _store(args)
    row = store.resolve_run(args.run_id)
    where = store.remove(row, args.force)
    if where is None:
        print(f"removed {row['run_id']} from the registry (its folder was gone already)")
    else:
        undo = f"python -m studies restore {row['run_id']} --outputs {args.outputs}"
        print(f"moved {row['run_id']} to the trash ({where}); undo with: {undo}")
    return 0


def _restore(args: argparse.Namespace) -> int:
    entry, folder, lost = _store(args).restore(args.run_id)
    print(f"restored {entry.run_id} to {folder}")
    for tag in lost:
        print(f"  tag {tag} names another run now: left there")
    return 0


def _trash(args: argparse.Namespace) -> int:
    found = _store(args).trash_entries()
    for e in found:
        tags = f" tags: {' '.join(e.tags())}" if e.tags() else ""
        removed = e.removed.isoformat(timespec="seconds")
        print(f"{e.run_id:<30} {e.study:<20} removed {removed}{tags}")
    print(f"{len(found)} run(s) in the trash under {args.outputs}")
    return 0


def _gc(args: argparse.Namespace) -> int:
    from studies.tracking.housekeeping import parse_age

    age = parse_age(args.older_than)
    done = _store(args).collect_garbage(age, args.keep_tagged, args.dry_run)
    move, delete = ("would move", "would delete") if args.dry_run else ("moved", "deleted")
    for row in done.trashed:
        print(f"{move} {row['run_id']} ({row['study']}, started {row['started']}) to the trash")
    for e in done.purged:
        print(f"{delete} {e.run_id} ({e.study}, trashed {e.removed:%Y-%m-%d %H:%M}) for good")
    print(f"{move} {len(done.trashed)} run(s) to the trash, {delete} {len(done.purged)} from it")
    for line in done.refused:
        sys.stderr.write(f"error: {line}\n")
    return EXIT_OUTPUT_ERROR if done.refused else 0


def _reindex(args: argparse.Namespace) -> int:
    done = _store(args).reindex()
    print(
        f"reindexed {done.runs} run(s), {done.tags} tag(s) and {done.notes} note(s) from the run "
        f"folders under {args.outputs}"
    )
    if done.kept_as is not None:
        print(f"the old registry is kept as {done.kept_as}")
    for line in done.skipped:
        print(f"skipped {line}")
    return 0


def _mlflow(args: argparse.Namespace) -> int:
    from studies.tracking.liveness import current_status
    from studies.tracking.mlflow_export import check_store, log_run

    store = _store(args)
    rows = [store.resolve_run(ref) for ref in args.run_ids]
    unfinished = [r["run_id"] for r in rows if current_status(r)[0] != "finished"]
    if unfinished:
        raise RunStateError(f"only finished runs are logged: {', '.join(unfinished)} is not")
    check_store(args.to)
    tags, notes = store.tags_and_notes()
    for row in rows:
        run_id = row["run_id"]
        mlflow_id, new = log_run(
            args.to, Path(row["folder"]), tags.get(run_id, []), notes.get(run_id, [])
        )
        print(f"{run_id}: {'logged' if new else 'already logged'} as MLflow run {mlflow_id}")
    return 0


def _export(args: argparse.Namespace) -> int:
    from studies.tracking.export import export_results

    row = _store(args).resolve_run(args.run_id)
    results = Path(row["folder"]) / "results.nc"
    if not results.exists():
        raise RunStateError(f"run {row['run_id']} has no results.nc: nothing to export")
    to = args.to or results.with_suffix(f".{args.format}")
    for path in export_results(results, to, args.format):
        print(f"wrote {path}")
    return 0


def check_mlflow(args: argparse.Namespace) -> None:
    """``run --mlflow``, before anything runs: a store MLflow refuses records nothing."""
    if args.mlflow:
        from studies.tracking.mlflow_export import check_store

        check_store(args.mlflow)


def label_run(args: argparse.Namespace, run_id: str) -> None:
    """``run --tag/--note``: tag and note the run, before anything about it is printed (a
    pipe closed by ``| head`` ends the command at the next print)."""
    from studies.tracking.records import now

    store = _store(args)
    for tag in args.tag:
        store.set_tag(run_id, tag)
    if args.note:
        store.add_note(run_id, now(), args.note)


def track_run(args: argparse.Namespace, folder: Path, run_id: str) -> None:
    """``run --tag/--mlflow``: say the run's new tags (:func:`label_run` set them), then log
    it to MLflow."""
    store = _store(args)
    for tag in args.tag:
        print(f"  tagged {tag}")
    if args.mlflow:
        from studies.tracking.mlflow_export import log_run

        tags, notes = store.tags_and_notes()
        try:
            mlflow_id, new = log_run(
                args.mlflow, folder, tags.get(run_id, []), notes.get(run_id, [])
            )
        except (ValueError, OSError) as exc:
            msg = (
                f"run {run_id} is recorded, but its MLflow export failed ({exc}); log it "
                f"later with: python -m studies mlflow {run_id} --to {args.mlflow} "
                f"--outputs {args.outputs}"
            )
            raise StudyError(msg) from None
        verb = "logged to" if new else "already logged to"
        print(f"  {verb} MLflow at {args.mlflow} as run {mlflow_id}")
