"""A process that registers runs, for the concurrent-registry test. It lives in an importable
module (tests/ is on the path) so that a spawned process can unpickle it: the test module
itself is imported by file path and has no importable name in a child process."""

from __future__ import annotations

from pathlib import Path

from studies import tracking

RUNS_EACH = 25


def register_many(outputs: str, writer: int) -> None:
    for i in range(RUNS_EACH):
        folder = Path(outputs) / "many" / f"{writer}-{i}"
        folder.mkdir(parents=True)
        record = tracking.RunRecord(
            run_id=f"{writer}-{i}", study="many", scene="cam", design="sweep", runs=1,
            status="running", started=tracking.now(), git_commit="c", git_dirty=False,
            definition_sha256="d", folder=str(folder),
        )  # fmt: skip
        tracking.register(Path(outputs), record)
        record.status = "finished"
        tracking.register(Path(outputs), record)
