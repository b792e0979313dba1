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

from studies.tracking import registry, store, trash
from studies.tracking.housekeeping import collect_garbage, remove_run, restore_run
from studies.tracking.liveness import lock_folder

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
        started = OLD if i % 5 == 4 else store.now()
        record = store.RunRecord(
            run_id=folder.name, study="many", scene="cam", design="sweep", runs=1,
            status="running", started=started, git_commit="c", git_dirty=False,
            definition_sha256="d", folder=str(folder),
        )  # fmt: skip
        lock = lock_folder(folder)
        assert lock is not None, f"{folder} is new: no one else can hold it"
        with lock:  # as a live run holds it
            record.write()
            store.register(root, record)
            record.status = "finished"
            record.write()
            store.register(root, record)
        row = {"run_id": folder.name, "study": "many", "folder": str(folder)}
        if i % 5 in (1, 2):
            remove_run(root, row)
        if i % 5 == 2:
            with contextlib.suppress(KeyError):  # another writer's purge pass took it first
                restore_run(root, folder.name)
        if i % 5 == 3:
            registry.set_tag(root, folder.name, f"w{writer}-{i}")
            registry.add_note(root, folder.name, store.now(), f"note of w{writer}-{i}")
        if i % 5 == 0:
            collect_garbage(root, AGE, keep_tagged=True)
            for entry in trash.entries(root):
                if int(entry.run_id[12:18]) % 5 in (2, 4):
                    trash.purge(entry)
