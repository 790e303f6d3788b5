"""Docstrings and comments cite only files inside the repository.

A document named in src/ (``docs/reference/sleec-language.md §3``) must exist; a module that
uses a section mark or a COP code (``§4.5``, ``SD7``, ``E38``) must say which document it is from.
"""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
SOURCES = sorted([*(ROOT / "src" / "cosleec").rglob("*.py"), *(ROOT / "src" / "cosleec").rglob("*.lark")])
DOCUMENT = re.compile(r"[\w./-]+\.md\b")
CODE = re.compile(r"§\s*\d|\bSD\d+\b|\bchecklist [A-H]\d+\b")


def test_every_cited_document_is_in_the_repository() -> None:
    missing = [
        f"{path.relative_to(ROOT)}: {name}"
        for path in SOURCES
        for name in DOCUMENT.findall(path.read_text(encoding="utf-8"))
        if not (ROOT / name).is_file()
    ]
    assert not missing, "\n".join(missing)


def test_codes_say_where_they_come_from() -> None:
    vague = [
        str(path.relative_to(ROOT))
        for path in SOURCES
        if CODE.search(text := path.read_text(encoding="utf-8")) and "docs/reference/" not in text
    ]
    assert not vague, "\n".join(vague)
