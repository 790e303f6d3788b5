"""SLEEC in the editor: ``cosleec lsp``, a language server over stdio (pygls).

Diagnostics as you type -- ``cosleec check``'s codes, places and hints, checked
incrementally (:class:`~cosleec.lang.IncrementalAnalyser`) -- and ``cosleec analyse``'s
findings on save, with their verified repairs (``cosleec analyse --fix``) as quick fixes;
hover, go-to-definition, find-references, completion, the outline, formatting
(``cosleec fmt``) and rename. Editors start it as ``cosleec lsp``
(docs/editors.md); programs and tests can :func:`build` a server and drive its features
(features.py) on a :class:`Document` directly.

On floor 3: imports errors, lang, analysis and repair (the on-save analysis and repairs),
and pygls.
"""

from __future__ import annotations

from cosleec.lsp.document import Document, Settings
from cosleec.lsp.features import Refusal
from cosleec.lsp.index import Index, Kind, Role, Use
from cosleec.lsp.positions import LineIndex
from cosleec.lsp.server import SleecServer, build, serve_stdio
from cosleec.lsp.wire import Limits

__all__ = [
    "Document",
    "Index",
    "Kind",
    "Limits",
    "LineIndex",
    "Refusal",
    "Role",
    "Settings",
    "SleecServer",
    "Use",
    "build",
    "serve_stdio",
]
