"""A patch: edits to a rule file's text, with what they are for.

A repair never rewrites the whole file: each edit replaces one stretch of the source (a
rule, a clause, a deadline) or inserts text at one place, so everything else -- comments,
blank lines, the author's layout -- stays byte for byte, and the unified diff a person
reviews shows only what the repair changes. Edits are made against one text and applied
together (last first, so that earlier offsets stay valid); two edits of one patch never
overlap.
"""

from __future__ import annotations

import difflib
from dataclasses import dataclass

from cosleec.lang import ast as A

OPERATORS: dict[str, str] = {
    "remove-rule": "remove a rule the other rules already imply (or one that can never apply)",
    "remove-clause": "remove an unless clause that is never selected",
    "add-rule": "add a rule that forbids (or requires) what the finding shows",
    "add-unless": "add an unless clause for the situation the finding lives in (defeater introduction)",
    "refine-unless": "narrow or widen an unless clause's condition (defeater refinement)",
    "refine-trigger": "strengthen a rule's trigger condition so it no longer applies where the finding lives",
    "strengthen-response": "add to what a rule requires (or forbids)",
    "change-deadline": "move a deadline to the largest (or smallest) value that removes the finding",
    "merge-rules": "merge rules with one trigger into one",
    "split-rule": "split a rule in two at a condition",
    "declare-priority": "declare which rule takes precedence (cosleec's priority block)",
}
"""Every repair operator, by the name patches carry, with what it does."""


@dataclass(frozen=True, slots=True)
class Edit:
    """Replace ``source[start:end]`` with ``text`` (``start == end``: an insertion)."""

    start: int
    end: int
    text: str


@dataclass(frozen=True)
class Patch:
    """One candidate repair: its operator (a key of :data:`OPERATORS`), a sentence saying
    what it does, the rules it touches (names in the original file) and its edits."""

    operator: str
    summary: str
    rules: tuple[str, ...]
    edits: tuple[Edit, ...]

    def apply(self, source: str) -> str:
        """The patched text."""
        out = source
        for e in sorted(self.edits, key=lambda e: (e.start, e.end), reverse=True):
            out = out[: e.start] + e.text + out[e.end :]
        return out

    @property
    def size(self) -> int:
        """How big the edit is, for ranking: characters removed plus characters written."""
        return sum((e.end - e.start) + len(e.text) for e in self.edits)

    def overlaps(self, other: Patch) -> bool:
        """Whether an edit of this patch changes a stretch an edit of ``other`` changes (two
        insertions at one place do not: both are made, in order)."""
        return any(a.start < b.end and b.start < a.end for a in self.edits for b in other.edits)


def edits_between(before: str, after: str) -> tuple[Edit, ...]:
    """The line edits that turn ``before`` into ``after`` (what a patch made in two steps, on
    two different texts, is as one patch of the first)."""
    a, b = before.splitlines(keepends=True), after.splitlines(keepends=True)
    starts = [0]
    for line in a:
        starts.append(starts[-1] + len(line))
    out = []
    for op, i1, i2, j1, j2 in difflib.SequenceMatcher(None, a, b, autojunk=False).get_opcodes():
        if op != "equal":
            out.append(Edit(starts[i1], starts[i2], "".join(b[j1:j2])))
    return tuple(out)


def unified_diff(before: str, after: str, path: str) -> str:
    """The change as a unified diff (``a/PATH`` to ``b/PATH``, as git writes them, an absolute
    path without its leading slash; three lines of context)."""
    lines = difflib.unified_diff(
        before.splitlines(keepends=True),
        after.splitlines(keepends=True),
        fromfile=f"a/{path.lstrip('/')}",
        tofile=f"b/{path.lstrip('/')}",
    )
    return "".join(
        line if line.endswith("\n") else line + "\n\\ No newline at end of file\n" for line in lines
    )


class Text:
    """A rule file's text with its line offsets: spans (1-based line and column, end
    exclusive) to offsets, and the indentation of a line."""

    def __init__(self, source: str) -> None:
        self.source = source
        self.starts = [0]
        for i, ch in enumerate(source):
            if ch == "\n":
                self.starts.append(i + 1)

    def offset(self, line: int, col: int) -> int:
        """The offset of 1-based ``line``, ``col``."""
        return self.starts[line - 1] + col - 1

    def span(self, span: A.Span) -> tuple[int, int]:
        """``span`` as offsets ``(start, end)``."""
        return self.offset(span.line, span.col), self.offset(span.end_line, span.end_col)

    def indent(self, line: int) -> str:
        """The whitespace that starts 1-based ``line``."""
        start = self.starts[line - 1]
        end = self.starts[line] if line < len(self.starts) else len(self.source)
        text = self.source[start:end]
        return text[: len(text) - len(text.lstrip(" \t"))]

    def line_end(self, line: int) -> int:
        """The offset of the newline that ends 1-based ``line`` (or the end of the text)."""
        end = self.starts[line] - 1 if line < len(self.starts) else len(self.source)
        return end

    def whole_lines(self, start: int, end: int) -> tuple[int, int]:
        """The lines ``source[start:end]`` covers, newline included, when nothing but
        whitespace shares them with it (else just ``start, end``): what removing it removes."""
        first = self.source.rfind("\n", 0, start) + 1
        last = self.source.find("\n", end)
        last = len(self.source) if last < 0 else last
        if self.source[first:start].strip() or self.source[end:last].strip():
            return start, end
        return first, min(last + 1, len(self.source))


__all__ = ["OPERATORS", "Edit", "Patch", "Text", "edits_between", "unified_diff"]
