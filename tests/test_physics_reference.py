"""The physics reference in the repository defines every equation tag the code cites.

A tag is a capital letter and a number in brackets (``[V2]``, ``[C1]``); docs/physics.md defines
it in the first cell of a table row (``| [V2] | …``). Scanned: every Python file of the two
packages and of the tests, so a new citation without a definition fails here.
"""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
PHYSICS = ROOT / "docs" / "physics.md"
CITED = re.compile(r"\[([A-Z][0-9]+)\]")
DEFINED = re.compile(r"^\| \[([A-Z][0-9]+)\] \|", re.MULTILINE)


def cited_tags() -> dict[str, list[str]]:
    """Each cited tag with the files citing it."""
    found: dict[str, list[str]] = {}
    for folder in ("engine_kernels", "studies", "tests"):
        for path in sorted((ROOT / folder).rglob("*.py")):
            for tag in set(CITED.findall(path.read_text(encoding="utf-8"))):
                found.setdefault(tag, []).append(str(path.relative_to(ROOT)))
    return found


def test_every_cited_tag_is_defined_in_docs_physics():
    defined = set(DEFINED.findall(PHYSICS.read_text(encoding="utf-8")))
    cited = cited_tags()
    missing = {tag: files[:3] for tag, files in cited.items() if tag not in defined}
    assert not missing, f"tags cited but not defined in docs/physics.md: {missing}"
    # the scan itself must see the tags the kernels are known to cite (a broken regex or a
    # moved package would otherwise pass vacuously)
    assert {"C1", "R3", "V2", "V4", "K1", "F2", "B1", "L1"} <= set(cited)


def test_each_tag_is_defined_once():
    tags = DEFINED.findall(PHYSICS.read_text(encoding="utf-8"))
    assert len(tags) == len(set(tags)), sorted(t for t in tags if tags.count(t) > 1)
