"""Reports render user text as text (issue 25 item 1, issue 23 item 6): the injection strings,
put in every text field a study file or a results file can carry, are inert in ``report.md``
rendered by python-markdown and by a CommonMark renderer (markdown-it-py) and in our own
``report.html``, and still read as written; ``report.html`` embeds only the run's own figures,
never a file a description names; the terminal gets no escape sequences.

Inert is checked on the rendered HTML with the standard library's parser: no ``<script>``
(report.html: only its own table-sorting script), no ``on…`` event attribute, no
``javascript:`` link, and every image is one of the run's figures."""

from __future__ import annotations

import base64
import io
import json
from html.parser import HTMLParser
from pathlib import Path
from urllib.parse import unquote

import markdown
import pytest
import xarray as xr
from markdown_it import MarkdownIt

from studies.cli import main
from studies.common.text_safety import TerminalText
from studies.report.html import SORT_SCRIPT

SCRIPT = "<script>alert(1)</script>"
IMG = "<img src=x onerror=alert(1)>"
LINK = "[click](javascript:alert(1))"
FILES = "![p](/etc/passwd) ![e](/proc/self/environ) ![z](/dev/zero)"
TERMINAL = "\x1b]0;owned\x07\x1b[2J\x1b[31mred\r\x9b"
INJECTION = f"{SCRIPT} {IMG} {LINK} {FILES} `code` **bold** _x_ | pipe &amp; {TERMINAL}"
SHOWN = f"{SCRIPT} {IMG} {LINK} {FILES} `code` **bold** _x_ | pipe &amp; "  # read as text
NAME = "<script>alert(1)"  # netCDF names hold no '/' nor control characters, coordinates no ' '

STUDY = f"""
name = "inject"
scene = "cam"
description = {json.dumps(INJECTION)}
responses = ["max_jerk", "max_lift"]
[factors.law]
levels = ["poly345", "cycloidal"]
[factors.cam_speed]
levels = [1000.0, 1300.0]
"""


class ActiveParts(HTMLParser):
    """What a browser would run or fetch in an HTML text."""

    def __init__(self) -> None:
        super().__init__()
        self.scripts: list[str] = []
        self.handlers: list[str] = []
        self.links: list[str] = []
        self.images: list[str] = []
        self.text: list[str] = []
        self._in_script = False

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        self.handlers += [f"{tag} {name}" for name, _ in attrs if name.lower().startswith("on")]
        for name, value in attrs:
            if name in ("href", "src", "action", "formaction") and value:
                (self.images if tag == "img" else self.links).append(value)
        if tag in ("script", "iframe", "object", "embed", "svg", "style", "base", "meta"):
            self.scripts.append(tag)
            self._in_script = tag == "script"

    def handle_endtag(self, tag: str) -> None:
        self._in_script = self._in_script and tag != "script"

    def handle_data(self, data: str) -> None:
        self.text.append(data)


def parts(page: str) -> ActiveParts:
    parser = ActiveParts()
    parser.feed(page)
    parser.close()
    return parser


def assert_inert(page: str, figures: set[str], own_script: bool = False) -> ActiveParts:
    found = parts(page)
    expected = ["style", "meta", "script"] if own_script else []
    assert sorted(found.scripts) == sorted(expected), found.scripts
    assert not found.handlers
    assert not [link for link in found.links if "javascript" in link.lower()]
    for src in found.images:
        assert src.startswith("data:image/png;base64,") or unquote(src) in figures, src
    return found


@pytest.fixture(scope="module")
def run_folder(tmp_path_factory: pytest.TempPathFactory) -> Path:
    tmp = tmp_path_factory.mktemp("inject")
    study = tmp / "inject.toml"
    study.write_text(STUDY, encoding="utf-8")
    assert main(["run", str(study), "--outputs", str(tmp / "out"), "--no-progress"]) == 0
    (folder,) = (tmp / "out" / "inject").iterdir()
    return folder


def figures_of(folder: Path) -> set[str]:
    return {p.name for p in folder.glob("*.png")}


def rendered(report: str) -> dict[str, str]:
    """report.md through python-markdown (with its table and fenced-code extensions) and
    through markdown-it-py's CommonMark preset with tables."""
    return {
        "python-markdown": markdown.markdown(report, extensions=["tables", "fenced_code"]),
        "commonmark": MarkdownIt("commonmark").enable("table").render(report),
    }


@pytest.mark.parametrize("renderer", ["python-markdown", "commonmark"])
def test_report_md_renders_the_description_as_text(run_folder: Path, renderer: str) -> None:
    report = (run_folder / "report.md").read_text(encoding="utf-8")
    page = rendered(report)[renderer]
    found = assert_inert(page, figures_of(run_folder))
    text = "".join(found.text)
    assert SHOWN in text  # the description reads as written
    assert "\x1b" not in report
    assert "\x07" not in report


def test_the_runs_analysis_txt_has_no_terminal_control_characters(run_folder: Path) -> None:
    # An audit's case: `analyze` cleaned the text it writes, but the run's own analysis.txt
    # kept the description's escape sequences, so `cat analysis.txt` retitled the terminal.
    text = (run_folder / "analysis.txt").read_text(encoding="utf-8")
    assert not [c for c in "\x1b\x07\r\x9b" if c in text]  # TERMINAL's control characters
    assert "owned" in text  # the description is there, as text


def test_report_html_is_inert_and_embeds_only_the_runs_figures(run_folder: Path) -> None:
    page = (run_folder / "report.html").read_text(encoding="utf-8")
    found = assert_inert(page, set(), own_script=True)
    assert SORT_SCRIPT.strip() in page
    assert SHOWN in "".join(found.text)
    own = {base64.b64encode(p.read_bytes()).decode() for p in run_folder.glob("*.png")}
    embedded = {src.removeprefix("data:image/png;base64,") for src in found.images}
    assert embedded == own  # every figure of the run, and nothing else
    assert base64.b64encode(Path("/etc/passwd").read_bytes()[:30]).decode()[:36] not in page


def hostile_results(folder: Path, target: Path) -> Path:
    """The run's results.nc with every text field a results file holds replaced by the
    injection: global attributes, units and long names, a factor's name and its levels, a
    response's name (``NAME``: an unclosed script tag)."""
    ds = xr.load_dataset(folder / "results.nc")
    for key in ("title", "study_name", "run_id", "created", "git_commit", "scene"):
        ds.attrs[key] = INJECTION
    for name in ds.variables:
        ds[name].attrs.update(units=INJECTION, long_name=INJECTION)
    factor, response = f"law{NAME}", f"max_jerk{NAME}"
    ds = ds.rename({"law": factor, "law_level": f"{factor}_level", "max_jerk": response})
    ds[factor] = ("run", [SCRIPT if v == "poly345" else IMG for v in ds[factor].values])
    ds.attrs["factors"] = json.dumps([factor, "cam_speed"])
    ds.attrs["responses"] = json.dumps([response, "max_lift"])
    path = target / "hostile.nc"
    ds.to_netcdf(path)
    return path


def test_analyze_of_a_hostile_results_file_writes_inert_reports(
    run_folder: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    results = hostile_results(run_folder, tmp_path)
    out = tmp_path / "analysis"
    assert main(["analyze", str(results), "--to", str(out)]) == 0
    printed = capsys.readouterr()
    for stream in (printed.out, printed.err):
        assert "\x1b" not in stream
        assert "\x07" not in stream
        assert "\x9b" not in stream
    figures = figures_of(out)
    assert any(NAME in name for name in figures)  # the hostile name reached a file name
    report = (out / "report.md").read_text(encoding="utf-8")
    for renderer, page in rendered(report).items():
        found = assert_inert(page, figures)
        assert SHOWN in "".join(found.text), renderer
    page = (out / "report.html").read_text(encoding="utf-8")
    found = assert_inert(page, set(), own_script=True)
    assert len(found.images) == len(figures)
    assert SCRIPT in "".join(found.text)


def test_terminal_text_keeps_lines_and_a_progress_bars_carriage_return() -> None:
    out = io.StringIO()
    stream = TerminalText(out)
    stream.write("\r 50%|#####     |")  # a progress bar redrawing its line
    stream.write(f"study: {TERMINAL}\tend\n")
    assert out.getvalue() == "\r 50%|#####     |study: ]0;owned[2J[31mred\tend\n"
