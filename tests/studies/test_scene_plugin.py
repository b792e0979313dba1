"""A scene from another package: the example plugin under tests/plugin_scene (a damped, driven
oscillator) is pip-installed into a temporary folder, found through the entry-point group
``engine_studies.scenes``, listed by ``python -m studies scenes`` and run as a full factorial,
in a fresh process, with nothing in ``studies/`` or ``engine_kernels/`` knowing it. Its RK4
steady state is checked against the closed-form frequency response."""

from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

PLUGIN = Path(__file__).resolve().parents[1] / "plugin_scene"
STUDY = """
name = "oscillator_grid"
scene = "oscillator"
responses = ["amplitude", "phase_lag", "natural_frequency"]
[parameters]
mass = 1.0
force_amplitude = 10.0
[factors.drive_frequency]
levels = [3.0, 8.0, 10.0, 12.0, 25.0]
[factors.damping_ratio]
levels = [0.05, 0.2, 0.7]
[factors.stiffness]
levels = [4000.0, 8000.0]
"""


@pytest.fixture(scope="module")
def plugin_path(tmp_path_factory: pytest.TempPathFactory) -> Path:
    target = tmp_path_factory.mktemp("site")
    subprocess.run(
        [
            sys.executable,
            "-m",
            "pip",
            "install",
            "--quiet",
            "--no-deps",
            "--target",
            str(target),
            str(PLUGIN),
        ],
        check=True,
        capture_output=True,
    )
    return target


def studies(plugin_path: Path, *args: str) -> subprocess.CompletedProcess[str]:
    env = os.environ | {"PYTHONPATH": str(plugin_path)}
    return subprocess.run(
        [sys.executable, "-m", "studies", *args],
        env=env,
        capture_output=True,
        text=True,
        check=False,
    )


def test_the_plugin_scene_is_listed_beside_the_built_in_ones(plugin_path: Path) -> None:
    listed = studies(plugin_path, "scenes")
    assert listed.returncode == 0, listed.stderr
    assert "scene oscillator (plugin: oscillator_scene): damped driven oscillator" in listed.stdout
    assert "scene valve: valve-train dynamics" in listed.stdout


def test_a_full_factorial_on_the_plugin_scene_matches_the_closed_form(
    plugin_path: Path, tmp_path: Path
) -> None:
    study = tmp_path / "oscillator_grid.toml"
    study.write_text(STUDY, encoding="utf-8")
    ran = studies(plugin_path, "run", str(study), "--outputs", str(tmp_path), "--no-progress")
    assert ran.returncode == 0, ran.stderr
    (results,) = tmp_path.glob("oscillator_grid/*/results.nc")
    with xr.open_dataset(results) as ds:
        assert ds.sizes["run"] == 30
        f, zeta, k = (ds[n].values for n in ("drive_frequency", "damping_ratio", "stiffness"))
        m, f0 = 1.0, 10.0
        omega_n = np.sqrt(k / m)
        r = 2 * np.pi * f / omega_n
        # Closed form of the steady state: X = (F0/k) / √((1 − r²)² + (2ζr)²),
        # tan φ = 2ζr / (1 − r²) with φ in [0, π].
        amplitude = f0 / k / np.sqrt((1 - r**2) ** 2 + (2 * zeta * r) ** 2) * 1e3
        phase = np.degrees(np.arctan2(2 * zeta * r, 1 - r**2))
        np.testing.assert_allclose(ds["amplitude"].values, amplitude, rtol=1e-5)
        np.testing.assert_allclose(ds["phase_lag"].values, phase, atol=1e-3)
        np.testing.assert_allclose(ds["natural_frequency"].values, omega_n / (2 * np.pi))
        assert ds["amplitude"].attrs["units"] == "mm"
    assert (results.parent / "main_effects_amplitude.png").exists()


def install_plugin(target: Path) -> Path:
    subprocess.run(
        [
            *(sys.executable, "-m", "pip", "install", "--quiet", "--no-deps"),
            *("--target", str(target), str(PLUGIN)),
        ],
        check=True,
        capture_output=True,
    )
    return target


def recomputed_x1000(site: Path, argv: list[str], outputs: Path, old: Path) -> Path:
    """Run ``argv`` after an edit that multiplies the amplitude by 1000: it must recompute
    (not reuse ``old``) and give 1000 × the old amplitude; the new run's folder."""
    edited = studies(site, *argv)
    assert edited.returncode == 0, edited.stderr
    assert "reusing run" not in edited.stdout
    new = next(p for p in (outputs / "oscillator_grid").iterdir() if p != old)
    with xr.open_dataset(old / "results.nc") as a, xr.open_dataset(new / "results.nc") as b:
        np.testing.assert_allclose(b["amplitude"].values, 1e3 * a["amplitude"].values)
    return new


def test_editing_the_plugins_source_invalidates_the_cache_and_compare_names_it(
    tmp_path: Path,
) -> None:
    site = install_plugin(tmp_path / "site")
    study = tmp_path / "oscillator_grid.toml"
    study.write_text(STUDY, encoding="utf-8")
    outputs = tmp_path / "out"
    argv = ["run", str(study), "--outputs", str(outputs), "--no-progress"]
    first = studies(site, *argv)
    assert first.returncode == 0, first.stderr
    again = studies(site, *argv)
    assert "reusing run" in again.stdout  # same definition, same code: reused
    (old,) = (outputs / "oscillator_grid").iterdir()
    recorded = json.loads((old / "run.json").read_text(encoding="utf-8"))["code"]["scene"]
    assert (recorded["distribution"], recorded["version"]) == ("engine-studies-oscillator", "0.1.0")
    assert recorded["plugin"] is True

    # the edit: a response ×1000, no version bump, the package reinstalled in place
    source = site / "oscillator_scene" / "__init__.py"
    text = source.read_text(encoding="utf-8")
    assert text.count("np.hypot(a, b) * 1e3") == 1
    source.write_text(text.replace("np.hypot(a, b) * 1e3", "np.hypot(a, b) * 1e6"), "utf-8")
    new = recomputed_x1000(site, argv, outputs, old)

    compared = studies(site, "compare", old.name, new.name, "--outputs", str(outputs))
    assert compared.returncode == 0, compared.stderr
    # the scene's distribution and version are unchanged; its source hash is not
    assert re.search(
        r"code scene oscillator\s+plugin engine-studies-oscillator 0\.1\.0 → "
        r"plugin engine-studies-oscillator 0\.1\.0, source changed",
        compared.stdout,
    ), compared.stdout
    assert "moved: amplitude" in compared.stdout
    assert "definitions, code and versions: identical" not in compared.stdout


def test_editing_a_module_beside_the_plugins_package_invalidates_the_cache(tmp_path: Path) -> None:
    # An audit's case: the scene imports a module its distribution installs beside the package
    # (py-modules); only the package was hashed, so an edit of the module was served the
    # result of the code before it, as "identical code".
    plugin = tmp_path / "plugin"
    shutil.copytree(PLUGIN, plugin, ignore=shutil.ignore_patterns("build", "*.egg-info"))
    (plugin / "oscillator_gain.py").write_text("GAIN = 1e3\n", encoding="utf-8")
    source = plugin / "oscillator_scene" / "__init__.py"
    text = source.read_text(encoding="utf-8").replace(
        "np.hypot(a, b) * 1e3", "np.hypot(a, b) * GAIN"
    )
    text = text.replace("import math\n", "import math\n\nfrom oscillator_gain import GAIN\n")
    source.write_text(text, encoding="utf-8")
    project = plugin / "pyproject.toml"
    text = project.read_text(encoding="utf-8")
    project.write_text(text + 'py-modules = ["oscillator_gain"]\n', encoding="utf-8")
    site = tmp_path / "site"
    subprocess.run(
        [sys.executable, "-m", "pip", "install", "--quiet", "--no-deps", "--target", str(site),
         str(plugin)],
        check=True, capture_output=True,
    )  # fmt: skip
    study = tmp_path / "oscillator_grid.toml"
    study.write_text(STUDY, encoding="utf-8")
    outputs = tmp_path / "out"
    argv = ["run", str(study), "--outputs", str(outputs), "--no-progress"]
    assert studies(site, *argv).returncode == 0
    (old,) = (outputs / "oscillator_grid").iterdir()
    module = site / "oscillator_gain.py"
    module.write_text(module.read_text(encoding="utf-8").replace("1e3", "1e6"), "utf-8")
    recomputed_x1000(site, argv, outputs, old)
