"""A process that registers, removes, restores and collects runs, for the concurrent-registry
test. It lives in an importable module (tests/ is on the path) so that a spawned process can
unpickle it: the test module itself is imported by file path and has no importable name in a
child process.

Writer ``w`` makes :data:`RUNS_EACH` runs; what it does with run ``i`` depends on ``i % 5``:

    0  kept                    1  removed (stays in the trash)
    2  removed, then restored  3  tagged ``w<w>-<i>`` and noted, kept
    4  started in 2020: every writer's ``gc --older-than 365d --keep-tagged`` moves it to the
       trash, and from there every writer's purge pass deletes it (racing the others)

The purge pass also deletes the restored runs' trash entries it finds, so a restore may lose
that race: it must then fail cleanly and leave nothing half-done.
"""

from __future__ import annotations

import contextlib
import datetime as dt
from pathlib import Path

from studies.tracking import records, trash
from studies.tracking.liveness import lock_folder
from studies.tracking.store import RunStore

RUNS_EACH = 25
OLD = "2020-01-01T00:00:00+00:00"
AGE = dt.timedelta(days=365)


def run_id(writer: int, i: int) -> str:
    return f"20260101T{writer:03d}{i:06d}-abcdef"


def register_many(outputs: str, writer: int) -> None:
    root = Path(outputs)
    for i in range(RUNS_EACH):
        folder = root / "many" / run_id(writer, i)
        folder.mkdir(parents=True)
        started = OLD if i % 5 == 4 else records.now()
        record = records.RunRecord(
            run_id=folder.name, study="many", scene="cam", design="sweep", runs=1,
            status="running", started=started, git_commit="c", git_dirty=False,
            definition_sha256="d", folder=str(folder),
        )  # fmt: skip
        lock = lock_folder(folder)
        assert lock is not None, f"{folder} is new: no one else can hold it"
        with lock:  # as a live run holds it
            record.write()
            RunStore(root).register(record)
            record.status = "finished"
            record.write()
            RunStore(root).register(record)
        row = {"run_id": folder.name, "study": "many", "folder": str(folder)}
        if i % 5 in (1, 2):
            RunStore(root).remove(row)
        if i % 5 == 2:
            with contextlib.suppress(KeyError):  # another writer's purge pass took it first
                RunStore(root).restore(folder.name)
        if i % 5 == 3:
            RunStore(root).set_tag(folder.name, f"w{writer}-{i}")
            RunStore(root).add_note(folder.name, records.now(), f"note of w{writer}-{i}")
        if i % 5 == 0:
            RunStore(root).collect_garbage(AGE, keep_tagged=True)
            for entry in RunStore(root).trash_entries():
                if int(entry.run_id[12:18]) % 5 in (2, 4):
                    trash.purge(entry)
