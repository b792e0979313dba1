"""The summed memory of a process tree (studies/bench/tree_memory.py), which the study benchmark
reports beside the run process's own peak.

Expected values: what the processes allocate and touch (100 MB each in a parent and its child,
held together for a second), plus at most the interpreters' own memory.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from studies.bench.study import run_command
from studies.bench.tree_memory import TreePeak

HOLD = """
import subprocess, sys
held = b"\\x01" * (100 << 20)
subprocess.run([sys.executable, "-c", "import time; held = b'\\\\x01' * (100 << 20); time.sleep(1.5)"], check=True)
"""


pytestmark = pytest.mark.skipif(
    not Path("/proc/self/smaps_rollup").exists(), reason="Linux /proc only"
)


def test_the_peak_adds_up_a_process_and_its_child() -> None:
    process = subprocess.Popen([sys.executable, "-c", HOLD])
    tree = TreePeak(process.pid)
    _, status, _ = os.wait4(process.pid, 0)
    process.returncode = os.waitstatus_to_exitcode(status)  # reaped here, not by Popen
    peak = tree.stop()
    assert process.returncode == 0
    assert peak is not None
    assert tree.processes == 2
    # two 100 MB blocks and two interpreters of ~10 MB each; PSS counts a page that a child
    # still shares with this test's process (forked, not yet replaced by exec) in part only
    assert 200 <= peak <= 350


def test_the_study_benchmark_reports_both_peaks() -> None:
    """wait4's peak is one process's (either one; the child's may include this test's process
    as forked before its exec), the tree's is both together."""
    wall, own, tree = run_command([sys.executable, "-c", HOLD])
    assert wall > 1.5
    assert own >= 100
    assert tree is not None
    assert 200 <= tree <= 350
