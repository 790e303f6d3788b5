"""MkDocs hook: the API reference from the docstrings, on the site only.

`docs/api.md` is written to be read where people read it -- on the repository, where a
mkdocstrings directive (`::: cosleec.runtime.Manager`) would show as a bare line of text --
so it names each object to document in an HTML comment, `<!-- api: cosleec.runtime.Manager -->`,
which the repository's renderer hides. When the site is built, this replaces each such
comment with the directive, and mkdocstrings puts the object's docstrings there.
"""

from __future__ import annotations

import re
from typing import Any

#: ``<!-- api: dotted.name -->`` on a line of its own
MARKER = re.compile(r"^<!-- api: ([\w.]+) -->$", re.M)


def directives(markdown: str) -> str:
    """``markdown`` with each API marker replaced by its mkdocstrings directive."""
    return MARKER.sub(lambda m: f"::: {m.group(1)}", markdown)


def on_page_markdown(markdown: str, page: Any, **_: Any) -> str:
    """MkDocs calls it for every page: the page with the directives in place of the markers."""
    return directives(markdown)
