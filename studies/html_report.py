"""``report.html``: ``report.md`` as one self-contained page to mail to a colleague.

Every figure is embedded as a base64 ``data:`` URI (those the report links and any other figure
of the run, under "Figures"), the style and the few lines of script that make every table
sortable (click a column header) are inline: the page loads nothing from anywhere. The
Markdown converted is the subset :mod:`studies.markdown_report` writes: headings, pipe tables,
images, fenced code, bullet lists, paragraphs, ``code``, **bold** and *italics*.
"""

from __future__ import annotations

import base64
import html
import re
from collections.abc import Sequence
from pathlib import Path

HTML_NAME = "report.html"
IMAGE = re.compile(r"!\[([^\]]*)\]\(([^)\s]+)\)")
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
    linked = {m[2] for m in IMAGE.finditer(text)}
    others = [f for f in figures if f.suffix == ".png" and f.name not in linked]
    if others:
        text += "\n\n## Figures\n\n" + "\n\n".join(f"![{f.stem}]({f.name})" for f in others)
    body = markdown_to_html(text, folder)
    title = html.escape(text.splitlines()[0].lstrip("# ") if text else "report")
    page = (
        f'<!DOCTYPE html>\n<html lang="en">\n<head>\n<meta charset="utf-8">\n'
        f"<title>{title}</title>\n<style>{STYLE}</style>\n</head>\n<body>\n{body}\n"
        f"<script>{SORT_SCRIPT}</script>\n</body>\n</html>\n"
    )
    path = folder / HTML_NAME
    path.write_text(page, encoding="utf-8")
    return path


def markdown_to_html(text: str, folder: Path) -> str:
    """The Markdown subset of the reports as HTML; images read from ``folder`` and embedded."""
    out: list[str] = []
    lines = text.splitlines()
    i = 0
    while i < len(lines):
        line = lines[i]
        if line.startswith("```"):
            end = next((j for j in range(i + 1, len(lines)) if lines[j].startswith("```")), None)
            end = len(lines) if end is None else end
            out.append("<pre><code>" + html.escape("\n".join(lines[i + 1 : end])) + "</code></pre>")
            i = end + 1
        elif line.startswith("#"):
            level = min(len(line) - len(line.lstrip("#")), 6)
            out.append(f"<h{level}>{_inline(line[level:].strip(), folder)}</h{level}>")
            i += 1
        elif line.startswith("|"):
            end = i
            while end < len(lines) and lines[end].startswith("|"):
                end += 1
            out.append(_table(lines[i:end], folder))
            i = end
        elif line.lstrip().startswith(("- ", "* ")):
            end = i
            while end < len(lines) and lines[end].lstrip().startswith(("- ", "* ")):
                end += 1
            items = [f"<li>{_inline(x.lstrip()[2:], folder)}</li>" for x in lines[i:end]]
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
            out.append(f"<p>{_inline(' '.join(lines[i:end]), folder)}</p>")
            i = end
        else:
            i += 1
    return "\n".join(out)


def _cells(row: str) -> list[str]:
    inner = row.strip().removeprefix("|").removesuffix("|")
    return [c.strip().replace("\\|", "|") for c in re.split(r"(?<!\\)\|", inner)]


def _table(rows: list[str], folder: Path) -> str:
    header, body = _cells(rows[0]), rows[1:]
    if body and set(body[0].replace("|", "").strip()) <= set("-: "):
        body = body[1:]
    head = "".join(f"<th>{_inline(c, folder)}</th>" for c in header)
    lines = ["".join(f"<td>{_inline(c, folder)}</td>" for c in _cells(r)) for r in body]
    rows_html = "".join(f"<tr>{r}</tr>" for r in lines)
    return f"<table><thead><tr>{head}</tr></thead><tbody>{rows_html}</tbody></table>"


def _inline(text: str, folder: Path) -> str:
    parts = []
    last = 0
    for m in IMAGE.finditer(text):
        parts.append(_format(text[last : m.start()]))
        parts.append(_image(m[1], folder / m[2]))
        last = m.end()
    parts.append(_format(text[last:]))
    return "".join(parts)


def _format(text: str) -> str:
    escaped = html.escape(text, quote=False)
    escaped = re.sub(r"`([^`]+)`", r"<code>\1</code>", escaped)
    escaped = re.sub(r"\*\*([^*]+)\*\*", r"<strong>\1</strong>", escaped)
    return re.sub(r"(?<![\w*])\*([^*\s][^*]*)\*(?![\w*])", r"<em>\1</em>", escaped)


def _image(alt: str, path: Path) -> str:
    if not path.exists():
        return f"<p><em>figure {html.escape(path.name)} was not written</em></p>"
    data = base64.b64encode(path.read_bytes()).decode("ascii")
    kind = "svg+xml" if path.suffix == ".svg" else path.suffix.lstrip(".").lower()
    return f'<img alt="{html.escape(alt)}" src="data:image/{kind};base64,{data}">'
