"""``check`` answers at once (issue #25: under a second whatever the file): it draws no sample
that needs scipy.stats and starts no compiler, and says in one line per item what it left to
``check --full`` and ``run``; ``--full`` checks everything, as ``run`` does before computing.

The witnesses are independent of the code under test: ``sys.modules`` of a fresh interpreter
for what was imported, and the full check for what the quick one left out."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest

from studies.cli import main
from studies.define.definition import catalog_names, find_study

CORPUS = Path(__file__).parent / "data" / "corpus"
PROBE = """
import sys
from studies.cli import main
code = main(sys.argv[1:])
print("exit", code, *(m for m in ("numba", "scipy.stats") if m in sys.modules))
"""
UNCHECKED = "not checked here, `check --full` and `run` check it: "


def isac_full_factorial(factors: str, parameters: str = "", noise: str = "") -> str:
    """isac_l9 (a six-segment cam) as a full factorial of ``factors``."""
    text = find_study("isac_l9").read_text().split("[factors.seg2_width]")[0]
    text = text.replace('type = "L9"\nerror_columns = ["D"]', 'type = "full_factorial"')
    text = re.sub(r"\nseg1_width = .*", "\nseg1_width = 4.5\n" + parameters, text)
    return text + factors + noise


def check_fresh(*argv: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-c", PROBE, "check", *argv],
        capture_output=True,
        text=True,
        check=False,
        timeout=300,
    )


def many_cams(tmp_path: Path) -> Path:
    """8 000 distinct six-segment cams: their concavity scan is more than plain Python does
    at once."""
    levels = "levels = [" + ", ".join(f"{7 + 0.2 * i:g}" for i in range(20)) + "]\n"
    factors = "".join(
        f'[factors.{name}]\n{levels.replace("7", str(low))}units = "{units}"\n\n'
        for name, low, units in (
            ("seg2_width", 7, "deg"),
            ("seg6_amplitude", 3, "mm/rad^2"),
            ("seg2_amplitude", 12, "mm/rad^2"),
        )
    )
    path = tmp_path / "many_cams.toml"
    path.write_text(isac_full_factorial(factors))
    return path


def many_linkages(tmp_path: Path) -> Path:
    """1.2·10⁷ distinct valve linkages (rise angle × lash): more combinations than a quick
    check groups."""
    levels = [[60 + i / 128 for i in range(4000)], [0.05 + i / 16384 for i in range(3000)]]
    path = tmp_path / "many_linkages.toml"
    path.write_text(
        'name = "many_linkages"\nscene = "valve"\nresponses = ["max_tappet_lift"]\n'
        f"[factors.rise_angle]\nlevels = {levels[0]}\n[factors.lash]\nlevels = {levels[1]}\n"
    )
    return path


@pytest.mark.parametrize(
    ("study", "left_out"),
    [
        ("ohc125_robust", "the noise cases, a sobol sample of 32"),
        (str(CORPUS / "crank_sobol_sample.toml"), "the sobol sample of 16 design points"),
        ("many_cams", "the scene's advice (e.g. concave cams) from law, base_radius"),
        ("many_linkages", "the scene's checks that read law, valve_lift, rise_angle"),
    ],
    ids=["sobol-noise", "sobol-design", "8000-cams", "1.2e7-linkages"],
)
def test_a_quick_check_draws_no_sample_starts_no_compiler_and_says_what_it_left(
    study: str, left_out: str, tmp_path: Path
) -> None:
    made = {"many_cams": many_cams, "many_linkages": many_linkages}
    path = str(made[study](tmp_path)) if study in made else study
    done = check_fresh(path)
    assert done.returncode == 0, done.stderr
    lines = done.stdout.splitlines()
    assert "OK as far as checked here" in lines[0]
    assert any(line.startswith(UNCHECKED + left_out) for line in lines), done.stdout
    assert lines[-1] == "exit 0", "imported numba or scipy.stats"


def test_what_a_quick_check_leaves_out_the_full_check_finds(tmp_path: Path, capsys) -> None:
    # seg2_width 45 ± 30 deg: at the nominal the six widths fit the 70 deg half-event; a noise
    # case above ~55 deg leaves the fillet and segment 6 negative widths (an error).
    path = tmp_path / "noisy_widths.toml"
    factors = '[factors.seg6_amplitude]\nlevels = [3.5, 5.5]\nunits = "mm/rad^2"\n\n'
    noise = '[noise]\ntype = "sobol"\nsamples = 8\n\n[noise.seg2_width]\n'
    noise += 'distribution = "uniform"\nhalf_width = 30\n'
    path.write_text(isac_full_factorial(factors, "seg2_width = 45.0\n", noise))
    assert main(["check", str(path)]) == 0
    quick = capsys.readouterr().out
    assert UNCHECKED + "the noise cases, a sobol sample of 8 over 'seg2_width'" in quick
    assert main(["check", "--full", str(path)]) != 0
    full = capsys.readouterr().err
    assert "cannot be fitted to the rise_angle = 70 deg half-event" in full


@pytest.mark.parametrize("name", [n for n in catalog_names() if n != "ohc125_robust"])
def test_quick_and_full_checks_agree_where_the_quick_one_leaves_nothing_out(
    name: str, capsys
) -> None:
    assert main(["check", name]) == 0
    quick = capsys.readouterr()
    assert main(["check", "--full", name]) == 0
    full = capsys.readouterr()
    assert UNCHECKED not in quick.out
    assert (quick.out, quick.err) == (full.out, full.err)


def test_problems_of_a_noise_study_name_design_points_and_noise_cases(
    tmp_path: Path, capsys
) -> None:
    # One design point, 4 noise cases on the cam speed; its rise angle of 1 deg leaves the
    # six-segment widths unfittable whatever the speed. Was (full check): "design points 0, 1,
    # 2, 3", the computed points, in a study of one design point.
    path = tmp_path / "one_point.toml"
    text = find_study("isac_l9").read_text().split("[factors.seg2_width]")[0]
    text = text.replace('type = "L9"\nerror_columns = ["D"]', 'type = "full_factorial"')
    text = re.sub(r"\nrise_angle = .*", "\nrise_angle = 1.0", text)
    text += '[factors.seg2_width]\nlevels = [9.0]\nunits = "deg"\n\n[noise]\ntype = "sobol"\n'
    text += 'samples = 4\n\n[noise.cam_speed]\ndistribution = "uniform"\nhalf_width = 10\n'
    path.write_text(text + "relative = true\n")
    assert main(["check", "--full", str(path)]) == 2
    assert "  - design point 0 (all 4 noise cases): segment widths" in capsys.readouterr().err
    assert main(["check", str(path)]) == 2
    assert "  - design point 0 at its nominal values: segment widths" in capsys.readouterr().err
