"""Numbers that must not look wrong (issue 23, item 7): a pooled ANOVA whose shares add up to
more than 100 %, a "best level" for a range of 0, dimensionless levels printed "0.35 1", and
analysis.txt lines hundreds of characters long for a factor with many levels."""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import xarray as xr

from results_datasets import CATALOG, study_dataset
from studies.define import designs
from studies.report.write import write_analysis


def grid(counts: dict[str, int], y: np.ndarray, units: dict[str, str]) -> xr.Dataset:
    design = designs.full_factorial(counts)
    coords = {}
    for f, n in counts.items():
        values = np.linspace(0.25, 0.25 + 0.05 * (n - 1), n)
        coords[f] = ("run", values[design.levels[f]], {"units": units[f]})
        coords[f"{f}_level"] = ("run", design.levels[f])
    data = {
        "y": ("run", y(design.levels) if callable(y) else y, {"units": "N", "better": "smaller"})
    }
    return xr.Dataset(
        data,
        coords=coords,
        attrs={
            "design": "full_factorial",
            "factors": json.dumps(list(counts)),
            "responses": '["y"]',
        },
    )


def test_pooled_shares_are_not_counted_twice(tmp_path: Path) -> None:
    ds = study_dataset(CATALOG / "isac_l9.toml", seed=3)
    ds.attrs["pool"] = json.dumps(["seg6_amplitude"])
    write_analysis(ds, tmp_path, ["max_jerk"])
    report = (tmp_path / "report.md").read_text(encoding="utf-8")
    anova = report[report.index("### ANOVA") :]
    table = anova[anova.index("| source") :].split("\n\n")[0]
    rows = table.splitlines()[2:]
    shares = {row.split("|")[1].strip(): row.split("|")[-2].strip() for row in rows}
    pooled = shares.pop("seg6_amplitude (pooled)")
    assert re.fullmatch(r"\(\d+\.\d\)", pooled)  # its share, in parentheses ...
    assert float(pooled.strip("()")) > 0.5  # ... large enough to show a double count
    total = float(shares.pop("total"))
    # Factors + error (which holds the pooled SS) add up to the total, within rounding.
    assert abs(sum(float(v) for v in shares.values()) - total) <= 0.05 * len(shares)
    assert "counted inside the error row" in anova
    text = (tmp_path / "analysis.txt").read_text(encoding="utf-8")
    assert "(pooled)" in text
    assert "counted inside the error row" in text


def test_a_range_of_zero_has_no_best_level(tmp_path: Path) -> None:
    ds = grid({"a": 3, "b": 2}, lambda lv: 1.0 + lv["a"], {"a": "mm", "b": "mm"})  # b: no effect
    write_analysis(ds, tmp_path)
    text = (tmp_path / "analysis.txt").read_text(encoding="utf-8")
    b_row = next(line for line in text.splitlines() if line.strip().startswith("b "))
    assert b_row.rstrip().endswith("— (R = 0)")  # the range table comes first
    report = (tmp_path / "report.md").read_text(encoding="utf-8")
    assert "| b | 2 | 2 | — | 0 | 2 | — (R = 0: all levels equal) |" in report
    # ... and a finer grid has nothing to find in b: the refinement holds it.
    assert "[factors.b]\nlevels = [0.25]" in report


def test_dimensionless_levels_print_without_a_unit_of_1(tmp_path: Path) -> None:
    ds = grid(
        {"ratio": 3, "b": 2}, lambda lv: 1.0 + lv["ratio"] + lv["b"], {"ratio": "1", "b": "mm"}
    )
    write_analysis(ds, tmp_path)
    for name in ("analysis.txt", "report.md"):
        text = (tmp_path / name).read_text(encoding="utf-8")
        assert "0.25, 0.3, 0.35" in text or "| ratio | 1 | 0.25 |" in text
        assert not re.search(r"0\.35 1(?![\d.])|\(0\.25 1\)", text), name


def test_analysis_text_stays_narrow_for_a_50_level_factor(tmp_path: Path) -> None:
    ds = grid(
        {"speed": 50, "b": 2},
        lambda lv: np.sin(lv["speed"] / 7.0) + lv["b"],
        {"speed": "1", "b": "mm"},
    )
    write_analysis(ds, tmp_path)
    text = (tmp_path / "analysis.txt").read_text(encoding="utf-8")
    widest = max(len(line) for line in text.splitlines())
    assert widest <= 120, widest  # was > 400: one column per level in one row
    assert "k of speed by level" in text  # the 50 level means are all there, wrapped
    assert text.count(": ") >= 50
