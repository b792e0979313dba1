"""``report.html``: ``report.md`` as one self-contained page to mail to a colleague.

Every figure is embedded as a base64 ``data:`` URI (those the report links and any other figure
of the run, under "Figures"), the style and the few lines of script that make every table
sortable (click a column header) are inline: the page loads nothing from anywhere. The
Markdown converted is the subset :mod:`studies.report.markdown_report` writes: headings, pipe tables,
images, fenced code, bullet lists, paragraphs, ``code``, **bold** and *italics*, backslash
escapes and HTML entities (user text arrives escaped, :mod:`studies.common.text_safety`).

Only the run's own figures are embedded: an image whose target is not, by name, one of the
figures the analysis wrote into the report's folder (a regular file, not a link) is shown as
its caption, and no other file is ever read.
"""

from __future__ import annotations

import base64
import html
import re
import stat
from collections.abc import Sequence
from collections.abc import Set as AbstractSet
from pathlib import Path
from urllib.parse import unquote

from studies.common.bounded_files import InputFileError, read_bounded_bytes
from studies.common.text_safety import figure_target, md_escape, printable

HTML_NAME = "report.html"
IMAGE = re.compile(r"!\[((?:[^\]\\]|\\.)*)\]\(([^)\s]+)\)")
ESCAPE_OR_ENTITY = re.compile(
    r"\\([!-/:-@\[-`{-~])|&(#[0-9]{1,7}|#[xX][0-9a-fA-F]{1,6}|[A-Za-z][A-Za-z0-9]{0,31});"
)
FIGURE_BYTES = 64 * 1024 * 1024  # a figure larger than this is not embedded
STYLE = """
body { font-family: system-ui, sans-serif; max-width: 72rem; margin: 2rem auto; padding: 0 1rem;
       line-height: 1.45; color: #222; }
table { border-collapse: collapse; margin: 0.8rem 0; font-size: 0.9rem; }
th, td { border: 1px solid #ccc; padding: 0.2rem 0.5rem; text-align: left; }
th { background: #f3f3f3; cursor: pointer; user-select: none; }
th.asc::after { content: " ▲"; } th.desc::after { content: " ▼"; }
img { max-width: 100%; display: block; margin: 0.8rem 0; }
pre { background: #f6f6f6; padding: 0.6rem; overflow-x: auto; }
code { background: #f6f6f6; padding: 0 0.2rem; }
"""
SORT_SCRIPT = """
document.querySelectorAll("table").forEach(function (table) {
  table.querySelectorAll("th").forEach(function (th, col) {
    th.addEventListener("click", function () {
      var body = table.tBodies[0], rows = Array.from(body.rows);
      var asc = !th.classList.contains("asc");
      table.querySelectorAll("th").forEach(function (h) { h.classList.remove("asc", "desc"); });
      th.classList.add(asc ? "asc" : "desc");
      var key = function (r) { var t = r.cells[col] ? r.cells[col].textContent.trim() : "";
        var n = parseFloat(t.replace(/[^0-9eE+.\\-]/g, "")); return isNaN(n) ? t : n; };
      rows.sort(function (a, b) { var x = key(a), y = key(b);
        var c = (typeof x === typeof y) ? (x < y ? -1 : x > y ? 1 : 0) : (typeof x === "number" ? -1 : 1);
        return asc ? c : -c; });
      rows.forEach(function (r) { body.appendChild(r); });
    });
  });
});
"""


def write_html(report_md: Path, figures: Sequence[Path] = ()) -> Path:
    """Write ``report.html`` beside ``report_md``; return its path."""
    folder = report_md.parent
    text = report_md.read_text(encoding="utf-8")
    own = {f.name for f in figures if Path(f).parent == folder}
    linked = {unquote(m[2]) for m in IMAGE.finditer(text)}
    others = [f for f in figures if f.suffix == ".png" and f.name not in linked and f.name in own]
    if others:
        text += "\n\n## Figures\n\n" + "\n\n".join(
            f"![{md_escape(f.stem)}]({figure_target(f.name)})" for f in others
        )
    body = markdown_to_html(text, folder, own)
    title = _plain(printable(text.splitlines()[0].lstrip("# ")) if text else "report")
    page = (
        f'<!DOCTYPE html>\n<html lang="en">\n<head>\n<meta charset="utf-8">\n'
        f"<title>{title}</title>\n<style>{STYLE}</style>\n</head>\n<body>\n{body}\n"
        f"<script>{SORT_SCRIPT}</script>\n</body>\n</html>\n"
    )
    path = folder / HTML_NAME
    path.write_text(page, encoding="utf-8")
    return path


def markdown_to_html(text: str, folder: Path, figures: AbstractSet[str] = frozenset()) -> str:
    """The Markdown subset of the reports as HTML; the images named in ``figures`` are read
    from ``folder`` and embedded, any other image is shown as its caption."""
    out: list[str] = []
    lines = text.replace("\0", "").splitlines()
    i = 0
    while i < len(lines):
        line = lines[i]
        if line.startswith("```"):
            mark = line[: len(line) - len(line.lstrip("`"))]
            end = next((j for j in range(i + 1, len(lines)) if lines[j].strip() == mark), None)
            end = len(lines) if end is None else end
            out.append("<pre><code>" + html.escape("\n".join(lines[i + 1 : end])) + "</code></pre>")
            i = end + 1
        elif line.startswith("#"):
            level = min(len(line) - len(line.lstrip("#")), 6)
            out.append(f"<h{level}>{_inline(line[level:].strip(), folder, figures)}</h{level}>")
            i += 1
        elif line.startswith("|"):
            end = i
            while end < len(lines) and lines[end].startswith("|"):
                end += 1
            out.append(_table(lines[i:end], folder, figures))
            i = end
        elif line.lstrip().startswith(("- ", "* ")):
            end = i
            while end < len(lines) and lines[end].lstrip().startswith(("- ", "* ")):
                end += 1
            items = [f"<li>{_inline(x.lstrip()[2:], folder, figures)}</li>" for x in lines[i:end]]
            out.append("<ul>" + "".join(items) + "</ul>")
            i = end
        elif line.strip():
            end = i
            while (
                end < len(lines)
                and lines[end].strip()
                and not lines[end].startswith(("#", "|", "```"))
            ):
                end += 1
            out.append(f"<p>{_inline(' '.join(lines[i:end]), folder, figures)}</p>")
            i = end
        else:
            i += 1
    return "\n".join(out)


def _cells(row: str) -> list[str]:
    inner = row.strip().removeprefix("|").removesuffix("|")
    return [c.strip() for c in re.split(r"(?<!\\)\|", inner)]


def _table(rows: list[str], folder: Path, figures: AbstractSet[str]) -> str:
    header, body = _cells(rows[0]), rows[1:]
    if body and set(body[0].replace("|", "").strip()) <= set("-: "):
        body = body[1:]
    head = "".join(f"<th>{_inline(c, folder, figures)}</th>" for c in header)
    lines = ["".join(f"<td>{_inline(c, folder, figures)}</td>" for c in _cells(r)) for r in body]
    rows_html = "".join(f"<tr>{r}</tr>" for r in lines)
    return f"<table><thead><tr>{head}</tr></thead><tbody>{rows_html}</tbody></table>"


def _inline(text: str, folder: Path, figures: AbstractSet[str]) -> str:
    parts = []
    last = 0
    for m in IMAGE.finditer(text):
        parts.append(_format(text[last : m.start()]))
        parts.append(_image(_plain(m[1]), folder, unquote(m[2]), figures))
        last = m.end()
    parts.append(_format(text[last:]))
    return "".join(parts)


def _plain(text: str) -> str:
    """Markdown text (escapes and entities) as HTML-escaped plain text."""
    return html.escape(ESCAPE_OR_ENTITY.sub(_literal, text), quote=True)


def _literal(m: re.Match[str]) -> str:
    return m[1] if m[1] is not None else html.unescape(f"&{m[2]};")


def _format(text: str) -> str:
    """Code spans, **bold** and *italics* of Markdown text; an escaped or entity character is
    only ever that character (placeholders keep it out of the markup patterns)."""
    held: list[str] = []

    def hold(value: str) -> str:
        held.append(value)
        return f"\0{len(held) - 1}\0"

    text = ESCAPE_OR_ENTITY.sub(lambda m: hold(html.escape(_literal(m))), text)
    text = re.sub(r"`([^`\0]+)`", lambda m: hold(f"<code>{html.escape(m[1])}</code>"), text)
    escaped = html.escape(text, quote=False)
    escaped = re.sub(r"\*\*([^*]+)\*\*", r"<strong>\1</strong>", escaped)
    escaped = re.sub(r"(?<![\w*])\*([^*\s][^*]*)\*(?![\w*])", r"<em>\1</em>", escaped)
    return re.sub(r"\0(\d+)\0", lambda m: held[int(m[1])], escaped)


def _image(alt: str, folder: Path, name: str, figures: AbstractSet[str]) -> str:
    """The figure ``name`` of ``folder`` embedded, if it is one of the run's own ``figures``
    (a regular file under ``FIGURE_BYTES``); its caption otherwise. ``alt`` is HTML already."""
    if name not in figures or "/" in name or name in (".", ".."):
        return f"<p><em>{alt}</em></p>"
    path = folder / name
    try:
        if not stat.S_ISREG(path.lstat().st_mode):
            raise InputFileError(name)
        data = base64.b64encode(read_bounded_bytes(path, "figure", FIGURE_BYTES)).decode("ascii")
    except (OSError, InputFileError):
        return f"<p><em>figure {html.escape(name)} was not written</em></p>"
    kind = "svg+xml" if path.suffix == ".svg" else path.suffix.lstrip(".").lower()
    return f'<img alt="{alt}" src="data:image/{kind};base64,{data}">'
