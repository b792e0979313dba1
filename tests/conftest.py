"""Figures are drawn in the test's own process unless a test starts the figure workers
(tests/studies/test_figure_pool.py): a monkeypatched renderer then acts where it is patched."""

from __future__ import annotations

import pytest

from studies.report.figure_pool import ENVIRONMENT


@pytest.fixture(autouse=True)
def figures_drawn_here(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv(ENVIRONMENT, "0")
