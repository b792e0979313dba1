"""What `check` passes, `run` must not fail for a definition reason; what it refuses, `run`
refuses too, writing nothing. Over every shipped study, the README's example, the hand-written
corpus under data/corpus (designs, units, categorical factors, sweeps, interactions, concave
cams, refused files) and one generated study per scene asking for every response and every
curve. The runs also check the outputs a person or another tool reads: every figure rendered
with warnings as errors (pytest's filterwarnings), and every unit a CF tool parses (cf-units,
the UDUNITS-2 library CF names)."""

from __future__ import annotations

import json
from pathlib import Path

import cf_units
import pytest
import xarray as xr

from studies.cli import main
from studies.common.units import CANONICAL, UNITS, canonical
from studies.define.definition import catalog_names, find_study
from studies.scenes import SCENES, get_scene
from study_text import readme_study

CORPUS = Path(__file__).parent / "data" / "corpus"
# A factor per scene whose two levels keep every other default valid (scene units).
GENERATED_FACTOR = {
    "cam": ("base_radius", 1.1),
    "crank": ("engine_speed", 1.2),
    "reed": ("thickness", 1.2),
    "luffing": ("trolley_mass", 2.0),
    "rocker": ("valve_lift", 0.9),
    "valve": ("cam_speed", 1.2),
    "valve_accuracy": ("cam_speed", 1.2),
    "valve_spring_ladder": ("cam_speed", 1.2),
}
DECIBEL = "dB"  # S/N ratios in analysis.nc: CF's canonical unit for levels, not in UDUNITS


def everything_study(scene_name: str) -> str:
    """A 2-point full factorial of ``scene_name`` asking for every response and curve."""
    scene = get_scene(scene_name)
    name, ratio = GENERATED_FACTOR[scene_name]
    default = scene.parameter(name).default  # type: ignore[union-attr]
    return (
        f'name = "every_{scene_name}"\nscene = "{scene_name}"\n'
        f"responses = {json.dumps([r.name for r in scene.responses])}\n"
        f"curves = {json.dumps([c.name for c in scene.curves if c.name != name])}\n"
        f"[factors.{name}]\nlevels = [{default!r}, {default * ratio!r}]\n"
    )


def corpus() -> dict[str, str]:
    """Every study text of the check-then-run corpus, by a readable id."""
    texts = {f"catalog:{n}": find_study(n).read_text(encoding="utf-8") for n in catalog_names()}
    texts["readme:writing a study"] = readme_study()
    texts |= {f"corpus:{p.stem}": p.read_text(encoding="utf-8") for p in sorted(CORPUS.glob("*"))}
    texts |= {f"every:{s}": everything_study(s) for s in SCENES}
    return texts


STUDIES = corpus()


def test_the_corpus_is_broad() -> None:
    assert len(STUDIES) >= 30
    assert {f"every:{s}" for s in SCENES} <= set(STUDIES)


CHECKED_HERE_RUN_ELSEWHERE = {
    "catalog:valve_step_accuracy": (
        "160 points with scipy references and timed repeats (~4 min on 2 cores): run end to end "
        "by test_valve_accuracy.py::test_valve_step_accuracy_runs_with_one_reference_per_pair; "
        "its scene's units by every:valve_accuracy here"
    ),
}


@pytest.mark.parametrize(("key", "text"), STUDIES.items(), ids=STUDIES.keys())
def test_what_check_passes_runs_and_what_it_refuses_run_refuses(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], key: str, text: str
) -> None:
    study = tmp_path / "study.toml"
    study.write_text(text, encoding="utf-8")
    outputs = tmp_path / "outputs"
    checked = main(["check", str(study)])
    assert checked in (0, 2)
    if key in CHECKED_HERE_RUN_ELSEWHERE:
        assert checked == 0
        return
    ran = main(["run", str(study), "--outputs", str(outputs), "--no-progress"])
    err = capsys.readouterr().err
    assert "Traceback" not in err
    if checked == 2:
        assert ran == 2, err
        assert not outputs.exists()
        return
    assert ran == 0, err
    (folder,) = (p.parent for p in outputs.glob("*/*/results.nc"))
    with xr.open_dataset(folder / "results.nc") as ds:
        units = [str(v.attrs["units"]) for v in ds.variables.values() if "units" in v.attrs]
    with xr.open_dataset(folder / "analysis.nc") as an:
        units += [str(v.attrs["units"]) for v in an.variables.values() if "units" in v.attrs]
        units += [str(u) for name in ("units", "term_units") if name in an for u in an[name].values]
    for u in {u for u in units if u and u != DECIBEL}:
        cf_units.Unit(u)  # raises ValueError on a string UDUNITS cannot parse
    assert (folder / "analysis.txt").stat().st_size > 0
    assert (folder / "report.md").stat().st_size > 0
    assert list(folder.glob("*.png")), "no figure rendered"  # each drawn with warnings as errors


def test_every_unit_is_udunits_with_our_factor_to_si() -> None:
    # The conversion table checked against UDUNITS-2 (an independent table): each unit converts
    # to the SI unit of its dimension (the one with factor 1) by our factor.
    si = {u.dimension: name for name, u in CANONICAL.items() if u.to_si == 1.0}
    for name, unit in CANONICAL.items():
        target = cf_units.Unit(si[unit.dimension])
        factor = cf_units.Unit(name).convert(1.0, target)
        assert factor == pytest.approx(unit.to_si, rel=1e-12), name
    for alias in set(UNITS) - set(CANONICAL):
        assert canonical(alias) in CANONICAL
