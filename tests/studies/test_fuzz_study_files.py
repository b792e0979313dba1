"""Fuzzing study files (issue 18, "What to build" 4): hypothesis writes study files, valid and
broken (types, ranges, units, names, design sizes, [noise] tables), for four scenes, and ``check`` answers each
with either "OK" (exit 0) or exit 2 and a list of problems, one line each, every line naming a
key of the file — never a traceback, never an error that is not a study problem.

500 examples per scene by default, the same ones every run (about 4 s a scene on 2 cores);
``HYPOTHESIS_PROFILE=long`` draws 5000 new ones.
"""

from __future__ import annotations

import contextlib
import copy
import io
import json
import math
import os
import re
import tempfile
import time
from pathlib import Path
from typing import Any

import pytest
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st

from studies.cli import main
from studies.common.units import UNITS
from studies.define import plan as planning
from studies.scenes import get_scene
from studies.scenes.checks import LATER_ADVICE

settings.register_profile(  # the same 500 documents every CI run: a fresh draw in CI found
    "fuzz-ci",  # a new edge case in two runs out of two (2026-12-07); HYPOTHESIS_PROFILE=long
    max_examples=500,  # draws 5000 new ones to look for more
    deadline=None,
    derandomize=True,
    suppress_health_check=[HealthCheck.too_slow],
)
settings.register_profile(
    "fuzz-long", max_examples=5000, deadline=None, suppress_health_check=[HealthCheck.too_slow]
)
FUZZ = settings.get_profile(
    "fuzz-long" if os.environ.get("HYPOTHESIS_PROFILE") == "long" else "fuzz-ci"
)
SCENES = ("cam", "valve", "luffing", "reed")
MAX_POINTS = 1000  # the size guard's limit here: larger designs are refused, fast
BARE_KEY = re.compile(r"[A-Za-z0-9_-]+")

# --- TOML text of a generated document ---------------------------------------------------


def toml_value(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float) and not math.isfinite(value):
        return "nan" if math.isnan(value) else ("inf" if value > 0 else "-inf")
    if isinstance(value, (int, float)):
        return repr(value)
    if isinstance(value, str):
        return toml_string(value)
    if isinstance(value, list):
        return "[" + ", ".join(toml_value(v) for v in value) + "]"
    return "{" + ", ".join(f"{toml_key(k)} = {toml_value(v)}" for k, v in value.items()) + "}"


def toml_key(key: str) -> str:
    return key if BARE_KEY.fullmatch(key) else toml_string(key)


def toml_string(text: str) -> str:
    """A TOML basic string: JSON's escapes, plus DEL, which TOML also wants escaped."""
    return json.dumps(text, ensure_ascii=False).replace("\x7f", "\\u007f")


def toml_text(doc: dict[str, Any]) -> str:
    """Top-level scalars first, then one ``[table]`` per dict, factors as ``[factors.X]``."""
    lines = [f"{toml_key(k)} = {toml_value(v)}" for k, v in doc.items() if not isinstance(v, dict)]
    for key, table in doc.items():
        if not isinstance(table, dict):
            continue
        if key == "factors" and all(isinstance(v, dict) for v in table.values()):
            for name, spec in table.items():
                lines.append(f"[factors.{toml_key(name)}]")
                lines += [f"{toml_key(k)} = {toml_value(v)}" for k, v in spec.items()]
            continue
        lines.append(f"[{toml_key(key)}]")
        lines += [f"{toml_key(k)} = {toml_value(v)}" for k, v in table.items()]
    return "\n".join(lines) + "\n"


# --- documents -------------------------------------------------------------------------------

HOSTILE_NUMBERS = st.sampled_from(
    [0, -1, 0.0, -0.0, 1e-300, 1e300, math.nan, math.inf, -math.inf, 2**63, -(2**64), 10**400]
)
ANY_VALUE = st.one_of(
    HOSTILE_NUMBERS,
    st.floats(allow_nan=True, allow_infinity=True),
    st.integers(min_value=-(2**70), max_value=2**70),
    st.booleans(),
    st.text(max_size=8),
    st.lists(st.floats(allow_nan=True), max_size=3),
    st.just({"value": 1.0, "units": "furlong"}),
)
UNIT_NAMES = st.one_of(st.sampled_from(sorted(UNITS)), st.text(max_size=5), st.integers())
NAMES = st.one_of(
    st.from_regex(r"[A-Za-z0-9_-]{1,20}", fullmatch=True),
    st.text(max_size=80),
    st.just("a" * 300),
    st.just("../../etc"),
    st.integers(),
)


def allowed(param: Any) -> st.SearchStrategy[Any]:
    """A value ``param`` allows, in its own units."""
    if param.kind == "choice":
        return st.sampled_from(param.choices)
    lo = param.minimum if param.minimum is not None else -1e3
    hi = param.maximum if param.maximum is not None else lo + 1e3
    if param.integer:
        return st.integers(math.ceil(lo) + 1, math.floor(min(hi, lo + 50)))
    return st.floats(lo, hi, exclude_min=param.exclusive_minimum, allow_subnormal=False)


def hostile(param: Any) -> st.SearchStrategy[Any]:
    """A value ``param`` refuses: out of range, of another type, not finite, not whole."""
    if param.kind == "text":
        return st.one_of(HOSTILE_NUMBERS, st.booleans(), st.just(["a"]))
    if param.kind == "vector":
        return st.one_of(
            st.just([]), st.just([1.0, math.nan]), HOSTILE_NUMBERS, st.text(max_size=3)
        )
    if param.kind == "choice":
        return st.one_of(st.just("no_such_choice"), HOSTILE_NUMBERS, st.booleans())
    outside = [HOSTILE_NUMBERS.filter(lambda v: param.check(v) is not None), st.booleans()]
    if param.maximum is not None:
        outside.append(st.floats(param.maximum, param.maximum * 2 + 1, exclude_min=True))
    if param.integer:
        outside.append(st.just(2.5))
    return st.one_of(*outside, st.text(max_size=3), st.just([1.0]))


@st.composite
def valid_document(draw: st.DrawFn, scene_name: str) -> dict[str, Any]:
    """A study a user could mean: every name known, every value allowed (the scene's
    cross-parameter checks may still refuse a combination)."""
    scene = get_scene(scene_name)
    variable = [p for p in scene.parameters if p.kind in ("number", "choice")]
    chosen = draw(st.lists(st.sampled_from(variable), min_size=1, max_size=4, unique=True))
    factors, fixed = chosen[: max(1, len(chosen) - 1)], chosen[max(1, len(chosen) - 1) :]
    responses = [r.name for r in scene.responses]
    some = st.lists(st.sampled_from(scene.settings), max_size=2, unique=True)
    settings_ = draw(some) if scene.settings else []
    doc = {
        "name": draw(st.from_regex(r"[A-Za-z0-9_-]{1,20}", fullmatch=True)),
        "scene": scene_name,
        "responses": draw(
            st.lists(st.sampled_from(responses), min_size=1, max_size=3, unique=True)
        ),
        "design": draw(st.sampled_from(["full_factorial", "sweep", "auto"])),
        "parameters": {p.name: draw(allowed(p)) for p in fixed},
        "factors": {
            p.name: {"levels": draw(st.lists(allowed(p), min_size=1, max_size=3, unique=True))}
            for p in factors
        },
        "settings": {p.name: draw(allowed(p)) for p in settings_} if settings_ else {},
    }
    numbers = [p for p in scene.parameters if p.kind == "number"]
    noisy = draw(st.lists(st.sampled_from(numbers), max_size=2, unique=True))
    if noisy and doc["design"] != "sweep":  # a sweep takes no noise
        doc["noise"] = draw(noise_table(noisy))
    return doc


@st.composite
def noise_table(draw: st.DrawFn, noisy: list[Any]) -> dict[str, Any]:
    """A [noise] table a user could mean: a small outer array or sample of tolerances (the
    range check may still refuse a spread that leaves a parameter's range)."""
    kind = draw(st.sampled_from(["L4", "L9", "sobol", "lhs", "random"]))
    table: dict[str, Any] = {"type": kind}
    if kind in ("sobol", "lhs", "random"):
        table["samples"] = 4
    for p in noisy:
        distribution = draw(st.sampled_from(["normal", "uniform", "triangular"]))
        spread = "sd" if distribution == "normal" else "half_width"
        table[p.name] = {
            "distribution": distribution,
            spread: draw(st.floats(0.1, 10.0)),
            "relative": True,
        }
    return table


@st.composite
def broken(draw: st.DrawFn, doc: dict[str, Any], scene_name: str) -> str:
    """Break ``doc`` in one way (in place); return the key a message must name."""
    scene = get_scene(scene_name)
    factor = draw(st.sampled_from(sorted(doc["factors"])))
    spec, param = doc["factors"][factor], scene.parameter(factor)
    kind = draw(st.integers(0, 11))
    if kind == 0:
        doc["name"] = draw(
            NAMES.filter(
                lambda n: not (isinstance(n, str) and BARE_KEY.fullmatch(n) and len(n) <= 64)
            )
        )
        return "name"
    if kind == 1:
        doc["responses"] = draw(st.one_of(st.just(["no_such_response"]), ANY_VALUE))
        return "responses" if doc["responses"] != ["no_such_response"] else "no_such_response"
    if kind == 2:
        doc["design"] = draw(st.one_of(st.sampled_from(["L99", "box_behnken"]), ANY_VALUE))
        return "design"
    if kind == 3:
        target = draw(
            st.sampled_from([p for p in scene.parameters if p.name not in doc["factors"]])
        )
        doc["parameters"][target.name] = draw(hostile(target))
        return target.name
    if kind == 4:
        target = draw(
            st.sampled_from(
                [p for p in scene.parameters if p.kind == "number" and p.name not in doc["factors"]]
            )
        )
        wrong = "kg" if target.units != "kg" else "m"
        units = draw(st.one_of(st.just("furlong"), st.just(wrong), st.integers()))
        doc["parameters"][target.name] = {"value": draw(allowed(target)), "units": units}
        return target.name
    if kind == 5:
        spec["levels"] = draw(
            st.one_of(ANY_VALUE, st.lists(hostile(param), min_size=1, max_size=3))
        )
        return factor
    if kind == 6:
        spec["units"] = draw(
            st.one_of(
                st.just("furlong"), st.integers(), st.just("kg" if param.units != "kg" else "m")
            )
        )
        return factor
    if kind == 7:
        spec["column"] = draw(st.one_of(st.integers(-(2**70), 0), st.booleans(), st.just(1.5)))
        return factor
    if kind == 8:
        spec["base"] = draw(st.one_of(st.just("not_a_level"), st.booleans(), st.just(-1e300)))
        return factor
    if kind == 9 and scene.settings:
        target = draw(st.sampled_from(scene.settings))
        doc["settings"][target.name] = draw(hostile(target))
        return target.name
    if kind == 10:  # the [noise] table
        return draw(broken_noise(doc, scene, factor))
    # design sizes: two factors of 40 to 2000 levels, more points than MAX_POINTS
    numbers = [
        p for p in scene.parameters if p.kind == "number" and p.name not in doc["parameters"]
    ]
    doc["factors"] = {
        p.name: {"levels": [float(i + 1) for i in range(draw(st.integers(40, 2000)))]}
        for p in draw(st.lists(st.sampled_from(numbers), min_size=2, max_size=2, unique=True))
    }
    doc["design"] = "full_factorial"
    return "design points"


@st.composite
def broken_noise(draw: st.DrawFn, doc: dict[str, Any], scene: Any, factor: str) -> str:
    """Break (or add) the [noise] table in one way; return the key a message must name."""
    table = doc.setdefault("noise", {"type": "L4"})
    target = draw(st.sampled_from([p for p in scene.parameters if p.kind == "number"]))
    how = draw(st.integers(0, 3))
    if how == 0:  # a spread that is no spread: negative, zero, NaN, text, a boolean
        table[target.name] = {
            "distribution": "normal",
            "sd": draw(st.one_of(st.floats(max_value=0.0), st.text(max_size=3), st.booleans())),
        }
        return target.name
    if how == 1:
        table[target.name] = {"distribution": "uniform", "half_width": 1.0, "spread": 2.0}
        return "spread"
    if how == 2:
        table["type"] = draw(st.one_of(st.sampled_from(["L7", "halton"]), ANY_VALUE))
        return "type"
    table[factor] = {"levels": [1.0, 2.0]}  # explicit levels on a control factor
    return factor


@st.composite
def study_document(
    draw: st.DrawFn, scene_name: str
) -> tuple[dict[str, Any], list[str], dict[str, Any]]:
    """A valid study, broken in 0, 1 or 2 ways; the keys a message must name; the study
    before it was broken."""
    doc = draw(valid_document(scene_name))
    pristine = copy.deepcopy(doc)
    offending = [draw(broken(doc, scene_name)) for _ in range(draw(st.integers(0, 2)))]
    return doc, offending, pristine


# --- the property ----------------------------------------------------------------------------


def keys_of(value: Any) -> set[str]:
    """Every key (at any depth) of a document, and every string value (names of things)."""
    if isinstance(value, dict):
        return set(value) | {k for v in value.values() for k in keys_of(v)}
    if isinstance(value, list):
        return {k for v in value for k in keys_of(v)}
    return {value} if isinstance(value, str) and value else set()


def check(text: str, folder: Path, *options: str) -> tuple[int, str, str]:
    study = folder / "fuzz.toml"
    study.write_text(text, encoding="utf-8")
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main(["check", *options, str(study)])
    return code, out.getvalue(), err.getvalue()


def assert_ok(out: str) -> None:
    """``check``'s OK, and where a quick check left something to ``check --full`` (issue #25)
    it says so on the OK line and names each item."""
    partial = ": OK as far as checked here — scene " in out
    assert partial or ": OK — scene " in out
    assert partial == ("\nnot checked here, `check --full` and `run` check it: " in out)


@pytest.mark.parametrize("scene", SCENES)
def test_check_answers_every_study_file_with_ok_or_readable_problems(
    scene: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("ENGINE_STUDIES_MAX_POINTS", str(MAX_POINTS))
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)

        @FUZZ
        @given(study=study_document(scene))
        def property_(study: tuple[dict[str, Any], list[str], dict[str, Any]]) -> None:
            doc, offending, pristine = study
            code, out, err = check(toml_text(doc), folder)
            event(f"exit {code}")
            assert "Traceback" not in err
            if code == 0:
                assert_ok(out)
                return
            assert code == 2, err
            assert err.startswith(f"error: study {folder / 'fuzz.toml'} has "), err
            problems = [line[4:] for line in err.splitlines() if line.startswith("  - ")]
            assert problems, err
            named = keys_of(doc) | {"design point", "factor", "design", "[factors]"}
            for line in problems:
                assert any(str(k) in line for k in named), line
            if (
                offending
                and not any(p.startswith("design point") for p in problems)
                and check(toml_text(pristine), folder)[0] == 0
            ):
                # a broken file stops before the per-point checks: its problems name the key
                # (unless the drawn study was refused before it was broken, e.g. by settings
                # that are each allowed but not together: jump_speed_high below _low)
                assert any(key in line for key in offending for line in problems), err

        property_()


@pytest.mark.parametrize("scene", SCENES)
def test_a_quick_check_says_nothing_the_full_check_contradicts(
    scene: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Reference: ``check --full`` (what ``run`` checks before computing) on the same file.
    Every problem the quick check reports, the full one reports (but those it found at a noise
    study's nominal values, which it says: the full check sees the noise cases instead);
    where the quick check left nothing out, both answers are the same, word for word.
    Both see the same machine: its free memory is read once (a live reading changes between
    the two checks, and a refusal states it)."""
    monkeypatch.setenv("ENGINE_STUDIES_MAX_POINTS", str(MAX_POINTS))
    free = planning.available_memory()
    monkeypatch.setattr(planning, "available_memory", lambda: free)
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)

        @settings(FUZZ, max_examples=min(FUZZ.max_examples, 40))
        @given(study=study_document(scene))
        def property_(study: tuple[dict[str, Any], list[str], dict[str, Any]]) -> None:
            text = toml_text(study[0])
            code, out, err = check(text, folder)
            full_code, full_out, full_err = check(text, folder, "--full")
            partial = "\nnot checked here, " in out
            nominal = " nominal values: " in out + err
            event(f"exit {code}/{full_code}{', partial' if partial else ''}")
            if code != 0 and not nominal:
                problems = {line for line in err.splitlines() if line.startswith("  - ")}
                assert full_code == code
                assert problems <= set(full_err.splitlines()), (err, full_err)
            elif not (partial or nominal):
                full_out, full_err = deferred(out, full_out), deferred(err, full_err)
                assert (full_code, full_out, full_err) == (code, out, err)

        property_()


def deferred(quick: str, full: str) -> str:
    """``full`` with each line the quick check left to ``--full`` (its concave-cam advice is
    LATER_ADVICE when the bisection is over its budget) taken as the quick check said it, when
    the two lines agree up to that advice: a pointer to the full answer, not a contradiction."""
    quick_lines, full_lines = quick.splitlines(keepends=True), full.splitlines(keepends=True)
    if len(quick_lines) != len(full_lines):
        return full
    agreed = []
    for q, f in zip(quick_lines, full_lines, strict=True):
        said = q.rstrip("\n").removesuffix(LATER_ADVICE)
        agreed.append(q if said != q.rstrip("\n") and f.startswith(said) else f)
    return "".join(agreed)


# --- hostile shapes: nesting, huge level lists, pathological settings (issue 25) -----------

PATHOLOGICAL = st.sampled_from([1e-300, 5e-324, 1e-12, 1e-7, 1e300, 2**53 + 1, 0.0])


@st.composite
def hostile_shape(draw: st.DrawFn, scene_name: str) -> dict[str, Any]:
    """A valid study with one hostile shape: a value nested deep at some key, a huge level
    list (under the file cap), or a setting at a pathological magnitude."""
    doc = draw(valid_document(scene_name))
    kind = draw(st.sampled_from(["nest", "levels", "setting"]))
    scene = get_scene(scene_name)
    if kind == "nest":
        depth = draw(st.integers(1, 60))
        value: Any = draw(st.sampled_from([1.0, "x", True]))
        for _ in range(depth):
            value = [value] if draw(st.booleans()) else {"a": value}
        table = draw(st.sampled_from(["factors", "parameters", "settings", "design", "top"]))
        if table == "factors":
            factor = draw(st.sampled_from(sorted(doc["factors"])))
            doc["factors"][factor]["levels"] = value
        elif table == "top":
            doc["description"] = value
        else:
            target = doc.setdefault(table, {}) if table != "design" else {}
            target["deep"] = value
            if table == "design":
                doc["design"] = {"type": doc["design"], "pool": value}
    elif kind == "levels":
        factor = draw(st.sampled_from(sorted(doc["factors"])))
        count = draw(st.integers(1_000, 15_000))
        repeat = draw(st.booleans())
        doc["factors"][factor]["levels"] = [1.0 if repeat else 1.0 + i for i in range(count)]
    else:
        numbers = [s for s in scene.settings if s.kind == "number"]
        if numbers:
            doc["settings"] = {draw(st.sampled_from(numbers)).name: draw(PATHOLOGICAL)}
    return doc


@pytest.mark.parametrize("scene", SCENES)
def test_check_answers_hostile_shapes_in_one_list_of_problems(
    scene: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Deep nesting, huge level lists, pathological settings: OK or exit 2 with problem lines,
    never a traceback (RecursionError, MemoryError, OverflowError before). The slowest
    answer is printed, not asserted."""
    monkeypatch.setenv("ENGINE_STUDIES_MAX_POINTS", str(MAX_POINTS))
    slowest = [0.0]
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)

        @settings(FUZZ, max_examples=min(FUZZ.max_examples, 40))
        @given(doc=hostile_shape(scene))
        def property_(doc: dict[str, Any]) -> None:
            start = time.perf_counter()
            code, out, err = check(toml_text(doc), folder)
            slowest[0] = max(slowest[0], time.perf_counter() - start)
            event(f"exit {code}")
            assert "Traceback" not in err
            assert code in (0, 2), err
            if code == 0:
                assert_ok(out)
            else:
                assert [line for line in err.splitlines() if line.startswith("  - ")], err

        property_()
    print(f"{scene}: slowest check of a hostile shape {slowest[0]:.3f} s")


def test_a_quick_check_that_leaves_the_convex_rise_angle_to_full_agrees_with_it(
    tmp_path: Path,
) -> None:
    """The case hypothesis found (CI, 2026-11-28): concave cams whose bisection is over the
    quick check's budget get LATER_ADVICE; the full check's lines agree up to it."""
    text = toml_text(
        {
            "name": "0",
            "scene": "cam",
            "responses": ["max_lift"],
            "design": "full_factorial",
            "parameters": {"lift": 1.0},
            "factors": {
                "cam_speed": {"levels": [1.0]},
                "base_radius": {"levels": [1.0, 2.0]},
                "law": {"levels": ["six_segment", "cycloidal", "harmonic"]},
            },
            "settings": {},
        }
    )
    code, out, err = check(text, tmp_path)
    full_code, full_out, full_err = check(text, tmp_path, "--full")
    assert LATER_ADVICE in err
    assert "it is convex from rise_angle = " in full_err
    assert (full_code, full_out, deferred(err, full_err)) == (code, out, err)
