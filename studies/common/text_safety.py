"""User text made inert where it is shown: in Markdown, in the HTML page and on the terminal.

Everything a user wrote — a study's description and names, factor levels, units, notes, and any
attribute of a results file given to ``analyze`` — reaches ``report.md`` through
:func:`md_escape`: a ``<`` that could open a tag, comment or autolink and an ``&`` that could
start an entity become entities, a ``>`` that could start a quote is backslash-escaped, and the
Markdown characters that make links, images, code or emphasis are backslash-escaped, so
CommonMark renderers and python-markdown alike show the text as written and run none of it.
Prose such as "> 0 outside, < 0 inside" keeps its plain ``<`` and ``>`` (inert there: a tag
needs a letter, ``/``, ``!`` or ``?`` right after the ``<``), so report.md also reads as text. Text the report itself
marks up is a :class:`Markup`, which is never escaped twice. Terminal output goes through
:class:`TerminalText`, which drops control and escape characters.
"""

from __future__ import annotations

import re
import unicodedata
from typing import TYPE_CHECKING, TextIO
from urllib.parse import quote

if TYPE_CHECKING:
    import xarray as xr

MARKDOWN_SPECIAL = re.compile(r"([\\`*\[\]|])")
ACTIVE_AMPERSAND = re.compile(r"&(?=[A-Za-z0-9#]|$)")  # could start an entity
ACTIVE_LESS = re.compile(r"<(?!\s)")  # could open a tag, comment or autolink (or ends the text)
LONE_UNDERSCORE = re.compile(r"(?<![A-Za-z0-9])_|_(?![A-Za-z0-9])")  # not inside a word
IDENTIFIER = re.compile(r"[A-Za-z0-9_.:+-]+")
BIDI_CONTROLS = frozenset("\u202a\u202b\u202c\u202d\u202e\u2066\u2067\u2068\u2069")


class Markup(str):
    """Markdown the report wrote itself (never escaped again)."""

    __slots__ = ()


def printable(text: str, keep: str = "") -> str:
    """``text`` without control characters (C0, DEL, C1, bidirectional overrides) other than
    those in ``keep``."""
    if text.isprintable():
        return text
    return "".join(
        c
        for c in text
        if c in keep
        or (unicodedata.category(c) != "Cc" and c not in BIDI_CONTROLS and c not in "\u2028\u2029")
    )


def printable_attributes(ds: xr.Dataset) -> xr.Dataset:
    """``ds`` with control characters dropped from every text attribute (O(1) in the runs: a
    description or a unit from a study file reaches analysis.txt and the terminal)."""
    ds.attrs = {k: printable(v, "\n\t") if isinstance(v, str) else v for k, v in ds.attrs.items()}
    for name in list(ds.variables):
        variable = ds[name]
        variable.attrs = {
            k: printable(v) if isinstance(v, str) else v for k, v in variable.attrs.items()
        }
    return ds


def printable_dataset(ds: xr.Dataset) -> xr.Dataset:
    """``ds`` with control characters dropped from every text attribute and text coordinate
    (a results file from elsewhere: its text reaches figures, tables and the terminal)."""
    import numpy as np  # noqa: PLC0415  (on use: the CLI imports this module for --help)

    ds = printable_attributes(ds)
    for name in list(ds.variables):
        variable = ds[name]
        if variable.dtype.kind in "OU" and name in ds.coords:
            cleaned = [printable(str(v)) for v in variable.values.ravel()]
            ds = ds.assign_coords(
                {name: (variable.dims, np.asarray(cleaned).reshape(variable.shape))}
            )
            ds[name].attrs = variable.attrs
    return ds


def md_escape(value: object) -> Markup:
    """``value`` as Markdown text that renders as written: one line, no control characters,
    HTML inert (``&amp; &lt;`` where they could act), no quote, link, image, code span or
    emphasis of its own."""
    if isinstance(value, Markup):
        return value
    text = printable(" ".join(str(value).splitlines()), keep="\t")
    text = ACTIVE_LESS.sub("&lt;", ACTIVE_AMPERSAND.sub("&amp;", text))
    text = MARKDOWN_SPECIAL.sub(r"\\\1", text)
    if text.startswith(">"):  # a quote at the start of a line
        text = "\\" + text
    return Markup(LONE_UNDERSCORE.sub(r"\\_", text))


def code_span(value: object) -> Markup:
    """An identifier (a study name, a run id) as a Markdown code span; anything that is not a
    plain identifier is escaped text instead (a ``|`` would split a table cell even inside
    a code span, and renderers disagree on escapes there)."""
    text = str(value)
    return Markup(f"`{text}`") if IDENTIFIER.fullmatch(text) else md_escape(text)


def figure_target(name: str) -> str:
    """A figure's file name as a Markdown link target (percent-encoded where it must be)."""
    return quote(name, safe="")


def fence(text: str) -> str:
    """A backtick fence longer than any run of backticks in ``text`` (at least three), so the
    fenced block cannot be closed from inside."""
    runs = [len(m) for m in re.findall(r"`+", text)]
    return "`" * max(3, max(runs, default=0) + 1)


class TerminalText:
    """A text stream that drops control and escape characters before they reach a terminal.

    Newlines and tabs pass; a carriage return passes only as the first character of a write
    (how progress bars redraw their line), never from inside printed text."""

    def __init__(self, stream: TextIO) -> None:
        self.stream = stream

    def write(self, text: str) -> int:
        head = "\r" if text.startswith("\r") else ""
        self.stream.write(head + printable(text[len(head) :], keep="\n\t"))
        return len(text)

    def __getattr__(self, name: str) -> object:
        return getattr(self.stream, name)
